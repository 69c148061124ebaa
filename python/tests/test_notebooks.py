"""The notebooks of examples/notebooks run from the first cell to the last (nbclient, Debian's ipykernel)."""
from pathlib import Path

import nbformat
import pytest
from nbclient import NotebookClient

import afford

NOTEBOOKS = Path(__file__).resolve().parents[2] / "examples" / "notebooks"


@pytest.mark.parametrize("name", sorted(p.stem for p in NOTEBOOKS.glob("*.ipynb")))
def test_the_notebook_runs(name, monkeypatch, tmp_path):
    monkeypatch.setenv("PYTHONPATH", str(Path(afford.__file__).resolve().parent.parent))  # this afford
    monkeypatch.setenv("TMPDIR", str(tmp_path))  # what a notebook writes in the temporary folder stays the test's
    monkeypatch.setenv("PYDEVD_DISABLE_FILE_VALIDATION", "1")  # (ipykernel's debugger, not used)
    nb = nbformat.read(NOTEBOOKS / f"{name}.ipynb", as_version=4)
    NotebookClient(nb, timeout=300, kernel_name="python3",
                   resources={"metadata": {"path": str(NOTEBOOKS)}}).execute()
    errors = [o for c in nb.cells if c.cell_type == "code" for o in c.get("outputs", []) if o.output_type == "error"]
    assert not errors
    # A notebook that writes in the temporary folder wrote under the test's own, not in the machine's /tmp.
    if any("tempfile" in "".join(c.source) for c in nb.cells if c.cell_type == "code"):
        assert any(tmp_path.glob("afford-*")), f"{name}: nothing of its temporary folder in TMPDIR ({tmp_path})"

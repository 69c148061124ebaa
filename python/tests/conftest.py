"""Experiments made once per session with the build's `afford`, in one process (memq), small."""
import os
import subprocess
import tempfile
from pathlib import Path

import pytest

BIN = Path(os.environ.get("AFFORD_BIN", Path(__file__).resolve().parents[2] / "build" / "bin")).resolve()


@pytest.fixture(autouse=True)
def own_temporary_folder(tmp_path, monkeypatch):
    """Each test's temporary folder (TMPDIR, for its processes too) is inside its own: what afford.run writes
    without `out`, and an example without `--out`, stays under the test's folder, not in the machine's /tmp."""
    folder = tmp_path / "TMPDIR"
    folder.mkdir()
    monkeypatch.setenv("TMPDIR", str(folder))
    monkeypatch.setattr(tempfile, "tempdir", str(folder))


def afford(*args: str, cwd: Path) -> None:
    r = subprocess.run([str(BIN / "afford"), *args, "--transport", "memq", "--quiet", "--progress", "none"],
                       cwd=cwd, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


@pytest.fixture(scope="session")
def made(tmp_path_factory):
    """Folders of a plain experiment with tests, a sweep, random tables and two extrinsic designs."""
    root = tmp_path_factory.mktemp("afford")
    logs = ["--log-root", str(root / "logs")]
    afford("experiment", "base", "--system", "all", "--reps", "2", "--steps", "400", "--extrinsic-reps", "1",
           "--scenarios", "scenario1", "--scenarios", "scenario2", "--run-prefix", "py", "--out", str(root / "base"),
           *logs, cwd=root)
    afford("experiment", "base", "--system", "IMP", "--reps", "1", "--steps", "200", "--set",
           "motivation.leak=0.1,0.3", "--run-prefix", "sw", "--keep-logs", "none", "--out", str(root / "sweep"),
           *logs, cwd=root)
    afford("experiment", "random-tables", "--system", "IMP", "--tables", "2", "--steps", "300", "--run-prefix", "rt",
           "--keep-logs", "none", "--out", str(root / "tables"), *logs, cwd=root)
    afford("experiment", "utility", "--reps", "1", "--steps", "300", "--extrinsic-reps", "1", "--run-prefix", "ut",
           "--keep-logs", "none", "--out", str(root / "utility"), *logs, cwd=root)
    small = root / "attention-small.yaml"  # the attention design, on 1 and 2 sub-goals, one scenario each
    small.write_text("extends: base\ndefault_systems: [IMP]\nplanner: {budget: 40, max_attempts: 10}\n"
                     "extrinsic:\n  generate: {sub_goals: [1, 2], per_point: 1, seed: 1}\n  tests: 1\n"
                     "  vary:\n    eye.attention: [bottom_up, top_down]\n")
    afford("experiment", "--config", str(small), "--reps", "1", "--steps", "300", "--run-prefix", "at",
           "--keep-logs", "none", "--out", str(root / "attention"), *logs, cwd=root)
    return root

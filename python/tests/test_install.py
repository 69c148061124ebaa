"""pip install of the package folder into a virtual environment, with no package index."""
import os
import shutil
import subprocess
import sys
from pathlib import Path

PYTHON = Path(__file__).resolve().parents[1]
BUILD = Path(os.environ.get("AFFORD_BUILD", PYTHON.parent / "build")).resolve()


def test_pip_installs_the_folder_into_a_venv_offline(made, tmp_path):
    src = tmp_path / "python"  # a copy: pip's build leaves its files beside the sources
    shutil.copytree(PYTHON, src, ignore=shutil.ignore_patterns("tests", "build", "*.egg-info", "__pycache__"))
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(tmp_path / "venv")], check=True)
    py = tmp_path / "venv" / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    env["AFFORD_BUILD"] = str(BUILD)
    r = subprocess.run([str(py), "-m", "pip", "install", "--no-index", "--no-build-isolation", str(src)],
                       capture_output=True, text=True, env=env)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([str(py), "-c", "import afford, sys; e = afford.load(sys.argv[1]); print(afford.__file__, len(e.runs))",
                        str(made / "base")], capture_output=True, text=True, env=env, cwd=tmp_path)
    assert r.returncode == 0, r.stdout + r.stderr
    assert str(tmp_path / "venv") in r.stdout and r.stdout.split()[-1] == "6"

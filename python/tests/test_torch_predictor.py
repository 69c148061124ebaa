"""The PyTorch affordance predictor of examples/torch-predictor: one run in process, as the predictors
process on the bus, and replayed gives one checksum (killed and restarted live: tests/restart, Restart.KilledTorchPredictorRejoinsAndTheRunIsUnchanged)."""
import os
import subprocess
import sys
from pathlib import Path

import afford

HERE = Path(__file__).resolve().parent
BIN = Path(os.environ.get("AFFORD_BIN", HERE.parents[1] / "build" / "bin"))
EXAMPLE = HERE.parents[1] / "examples" / "torch-predictor"
sys.path.insert(0, str(EXAMPLE))
from torch_predictor import TorchConv  # noqa: E402


def checksum(e):
    return e.runs["weights_checksum"].iloc[0]


def test_the_torch_predictor_is_one_run_in_process_on_the_bus_and_replayed(tmp_path, monkeypatch):
    inproc = afford.run("base", system="IMP", reps=1, steps=800, out=tmp_path / "in", affordance=TorchConv)
    log = inproc.runs["log_dir"].iloc[0]
    assert "kind: torch-conv" in afford.read_log(log, channels=["DECISION"]).config_yaml
    paper = afford.run("base", system="IMP", reps=1, steps=800, out=tmp_path / "paper")
    assert checksum(inproc) != checksum(paper)  # it is another learner
    monkeypatch.setenv("PYTHONPATH", f"{EXAMPLE}:{Path(afford.__file__).parent.parent}")
    command = f"{sys.executable} -m afford.process predictors {EXAMPLE / 'torch_predictor.py'}:TorchConv"
    bus = afford.run("base", system="IMP", reps=1, steps=800, out=tmp_path / "bus", transport="udpm",
                     set={"predictors.affordance.kind": "torch-conv"}, processes={"predictors": command})
    assert checksum(bus) == checksum(inproc)
    said = subprocess.run([BIN / "afford", "replay", log], capture_output=True, text=True)
    assert said.returncode != 0 and "afford.replay(LOG, affordance=" in said.stderr, said.stderr
    replayed = afford.replay(log, affordance=TorchConv)
    assert replayed["ok"] and replayed["weights_checksum"] == checksum(inproc), replayed

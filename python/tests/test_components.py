"""A motivation written in Python, in process and as a process on the bus, against the C++ ones."""
import sys
from pathlib import Path

import pytest

import afford
from motivations import Broken, PyNovelty, PyRandom

HERE = Path(__file__).resolve().parent
BIN = Path(__file__).resolve().parents[2] / "build" / "bin"


def checksum(e):
    return e.runs["weights_checksum"].iloc[0]


def test_a_python_motivation_in_process_equals_the_cpp_one(tmp_path):
    cpp = afford.run("base", system="IMP", reps=1, steps=1500, out=tmp_path / "cpp", set={"motivation.kind": "novelty"})
    py = afford.run("base", system="IMP", reps=1, steps=1500, out=tmp_path / "py", motivation=PyNovelty)
    assert checksum(py) == checksum(cpp)
    paper = afford.run("base", system="IMP", reps=1, steps=1500, out=tmp_path / "paper")
    assert checksum(paper) != checksum(cpp)  # the motivation made a difference
    # its log replays: the predictors to the same weights; the decider is said not to be replayed
    log = afford.read_log(py.runs["log_dir"].iloc[0], channels=["DECISION"])
    assert len(log) == 1500 and all(d["threshold"] == 0.1 for d in log)


def test_a_python_motivation_as_a_process_on_the_bus_equals_the_cpp_example(tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", f"{HERE}:{Path(afford.__file__).parent.parent}")
    command = f"{sys.executable} -m afford.process motivation {HERE / 'motivations.py'}:PyRandom"
    py = afford.run("base", system="IMP", reps=1, steps=1000, out=tmp_path / "py", transport="udpm",
                    set={"motivation.kind": "py-random"}, processes={"motivation": command})
    cpp = afford.run("base", system="IMP", reps=1, steps=1000, out=tmp_path / "cpp", transport="udpm",
                     set={"motivation.kind": "random"}, processes={"motivation": str(BIN / "random-motivation")})
    assert checksum(py) == checksum(cpp)
    assert py.summary["processes"] == {"motivation": command}
    # ... and in process, the same
    inproc = afford.run("base", system="IMP", reps=1, steps=1000, out=tmp_path / "in", motivation=PyRandom)
    assert checksum(inproc) == checksum(py)


def test_a_python_error_fails_the_run_naming_the_step_and_the_error(tmp_path):
    with pytest.raises(RuntimeError, match="failed"):
        afford.run("base", system="IMP", reps=1, steps=100, out=tmp_path / "b", motivation=Broken)
    e = afford.load(tmp_path / "b")
    error = e.summary["systems"]["IMP"]["failed_runs"][0]["error"]
    assert "motivation 'broken' (Python): decide() at step 7 raised ValueError: no decision at step seven" in error


def test_bad_classes_are_named():
    class Nameless:
        kind = "Not A Name"

        def decide(self, p):
            return afford.Decision(False)

    with pytest.raises(ValueError, match="Not A Name"):
        afford.register_motivation(Nameless)
    with pytest.raises(TypeError, match="no decide"):
        afford.register_motivation(type("nodecide", (), {}))
    with pytest.raises(ValueError, match="transport='memq'"):
        afford.run("base", motivation=PyNovelty, transport="udpm")

"""Components written in Python (a motivation, an affordance predictor), in process and as processes on the
bus, against the C++ ones."""
import subprocess
import sys
from pathlib import Path

import pytest

import afford
from motivations import Broken, PyNovelty, PyPaper, PyRandom, ReturnsNothing
from predictors import Frozen, PyPerceptrons

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
    # its log replays: the predictors to the same weights; the decider is said not to be replayed, and why
    log = afford.read_log(py.runs["log_dir"].iloc[0], channels=["DECISION"])
    assert len(log) == 1500 and all(d["threshold"] == 0.1 for d in log)
    said = subprocess.run([BIN / "afford", "replay", py.runs["log_dir"].iloc[0]], capture_output=True, text=True)
    assert said.returncode == 0, said.stdout + said.stderr
    assert "motivation.kind 'py-novelty' is not one of afford's own (a class in Python" in said.stdout + said.stderr
    assert "process of its own" not in said.stdout + said.stderr


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


def test_a_python_error_fails_the_run_naming_the_step_and_the_error(tmp_path, capfd):
    said = "motivation 'broken' (Python): decide() at step 7 raised ValueError: no decision at step seven"
    with pytest.raises(afford.ExperimentError) as failed:  # the reason is in the exception, not only on stderr
        afford.run("base", system="IMP", reps=1, steps=100, out=tmp_path / "b", motivation=Broken)
    assert capfd.readouterr().err.count(said) == 1  # said once on stderr (by the runner), with its trace    assert said in str(failed.value) and failed.value.out == tmp_path / "b" and failed.value.exit_code == 1
    assert isinstance(failed.value, RuntimeError) and any(said in e for e in failed.value.errors)
    e = afford.load(tmp_path / "b")
    error = e.summary["systems"]["IMP"]["failed_runs"][0]["error"]
    assert said in error


def test_a_decide_that_returns_no_decision_is_told_what_to_return(tmp_path):
    with pytest.raises(afford.ExperimentError, match=r"decide\(\) at step 2 returned None: decide\(\) returns an "
                                                     r"afford.Decision\(act, action, motivation, threshold\)"):
        afford.run("base", system="IMP", reps=1, steps=20, out=tmp_path / "none", motivation=ReturnsNothing,
                   log_level="off")


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


def test_python_ports_of_the_paper_give_the_cpp_weights_in_process(tmp_path):
    # Without a memory (which the paper's agent does not keep), a run with a port is comparable checksum for checksum.
    never = {"predictors.memory.keep": "never"}
    paper = {}
    for system in ("IGN", "IMP"):
        paper[system] = afford.run("base", system=system, reps=1, steps=1500, out=tmp_path / f"paper-{system}")
        motivation = afford.run("base", system=system, reps=1, steps=1500, out=tmp_path / f"m-{system}",
                                motivation=PyPaper, set=never)
        log = afford.read_log(motivation.runs["log_dir"].iloc[0], channels=["DECISION"])
        assert "kind: py-paper" in log.config_yaml and len(log) == 1500
        assert checksum(motivation) == checksum(paper[system]), system
    both = afford.run("base", system="IMP", reps=1, steps=1500, out=tmp_path / "both", motivation=PyPaper,
                      affordance=PyPerceptrons, set=never)
    assert checksum(both) == checksum(paper["IMP"])
    # with the memory it keeps for a motivation of one's own, the same decisions, another checksum
    kept = afford.run("base", system="IMP", reps=1, steps=1500, out=tmp_path / "kept", motivation=PyPaper)
    assert checksum(kept) != checksum(paper["IMP"])
    assert kept.runs["looks"].iloc[0] > 0


def test_a_python_affordance_predictor_replays_saves_and_plans_as_the_paper_one(tmp_path):
    # replay (predictors.replay) relearns remembered experiences through the component
    replay = {"predictors.replay.enabled": True}
    cpp = afford.run("base", system="IMP", reps=1, steps=400, out=tmp_path / "cpp-replay", set=replay)
    py = afford.run("base", system="IMP", reps=1, steps=400, out=tmp_path / "py-replay", set=replay,
                    affordance=PyPerceptrons)
    assert checksum(py) == checksum(cpp) and py.runs["replayed"].iloc[0] > 0
    # afford replay cannot rebuild a component it does not have, and says so
    said = subprocess.run([BIN / "afford", "replay", py.runs["log_dir"].iloc[0]], capture_output=True, text=True)
    assert said.returncode != 0 and "predictors.affordance.kind 'py-perceptrons' is not one of afford's own" in said.stderr
    # the checkpoint holds the component's arrays; the extrinsic tests load them into a new one and plan alike
    kw = dict(system="IMP", reps=1, steps=2500, extrinsic_reps=1, scenarios=["scenario2"], set={"planner.budget": 40})
    cpp = afford.run("base", out=tmp_path / "cpp", **kw)
    py = afford.run("base", out=tmp_path / "py", affordance=PyPerceptrons, **kw)
    assert checksum(py) == checksum(cpp)
    columns = ["scenario", "success", "completion", "attempts", "actions_checked"]
    assert py.extrinsic[columns].equals(cpp.extrinsic[columns])
    assert cpp.extrinsic["actions_checked"].iloc[0] > 0
    # a component of another kind learns otherwise, and its own checkpoint serves its tests
    frozen = afford.run("base", out=tmp_path / "frozen", affordance=Frozen, **kw)
    assert checksum(frozen) != checksum(cpp)
    assert set(frozen.affordances["value"]) == {0.5}
    assert len(frozen.extrinsic) == 1


def test_a_python_affordance_predictor_as_a_process_on_the_bus(tmp_path, monkeypatch):
    monkeypatch.setenv("PYTHONPATH", f"{HERE}:{Path(afford.__file__).parent.parent}")
    command = f"{sys.executable} -m afford.process predictors {HERE / 'predictors.py'}:PyPerceptrons"
    py = afford.run("base", system="IMP", reps=1, steps=1000, out=tmp_path / "py", transport="udpm",
                    set={"predictors.affordance.kind": "py-perceptrons"}, processes={"predictors": command})
    paper = afford.run("base", system="IMP", reps=1, steps=1000, out=tmp_path / "paper")
    assert checksum(py) == checksum(paper)
    assert py.summary["processes"] == {"predictors": command}


class RaisingLearner(PyPerceptrons):
    kind = "raising"

    def learn(self, image, action, succeeded):
        raise ArithmeticError("cannot learn this")


class SinglePrecision(PyPerceptrons):
    kind = "single"

    def state(self, action):
        return [w.astype("float32") for w in super().state(action)]


class ThreeActions(PyPerceptrons):
    kind = "three"

    def predict(self, image):
        affordance, lp = super().predict(image)
        return affordance[:3], lp


class NotFinite(PyPerceptrons):
    kind = "not-finite"

    def predict(self, image):
        affordance, lp = super().predict(image)
        return affordance, lp[:2] + [float("nan")] + lp[3:]


@pytest.mark.parametrize("cls, message", [
    (RaisingLearner, "affordance predictor 'raising' (Python): learn() raised ArithmeticError: cannot learn this"),
    (SinglePrecision, "affordance predictor 'single' (Python): state(0)[0] is an array of float32, not float64"),
    (ThreeActions, "affordance predictor 'three' (Python): predict()'s affordance has 3 numbers, not one per action"),
    (NotFinite, "affordance predictor 'not-finite' (Python): predict()'s learning progress[2] is not finite"),
])
def test_a_python_affordance_predictor_that_misbehaves_fails_its_run_naming_what(tmp_path, cls, message):
    with pytest.raises(RuntimeError, match="failed"):
        afford.run("base", system="IMP", reps=1, steps=60, out=tmp_path / "b", affordance=cls)
    error = afford.load(tmp_path / "b").summary["systems"]["IMP"]["failed_runs"][0]["error"]
    assert message in error


def test_a_class_that_is_not_an_affordance_predictor_is_named():
    with pytest.raises(TypeError, match="no learn"):
        afford.register_affordance(type("predictonly", (), {"predict": lambda self, image: None}))
    with pytest.raises(ValueError, match="transport='memq'"):
        afford.run("base", affordance=PyPerceptrons, transport="udpm")


def test_a_python_goal_chooser_in_process_and_as_a_process_on_the_bus_is_one_run(tmp_path, monkeypatch):
    from goals import PyColours
    inproc = afford.run("base", system="GOALS", reps=1, steps=600, out=tmp_path / "in", goals=PyColours)
    monkeypatch.setenv("PYTHONPATH", f"{HERE}:{Path(afford.__file__).parent.parent}")
    command = f"{sys.executable} -m afford.process goals {HERE / 'goals.py'}:PyColours"
    bus = afford.run("base", system="GOALS", reps=1, steps=600, out=tmp_path / "bus", transport="udpm",
                     set={"goals.kind": "py-colours"}, processes={"motivation": command})
    assert checksum(bus) == checksum(inproc)
    imgep = afford.run("base", system="GOALS", reps=1, steps=600, out=tmp_path / "imgep")
    assert checksum(imgep) != checksum(inproc)  # the chooser made a difference
    # its goals were colour goals after the explorations, and some were reached
    results = afford.read_log(inproc.runs["log_dir"].iloc[0], channels=["GOAL_RESULT"]).frame("GOAL_RESULT")
    assert set(results.module) == {0, 1} and results[results.module == 1].reached.sum() > 0
    # replayed: the predictors and the planner; the chooser is said not to be, and why
    said = subprocess.run([BIN / "afford", "replay", inproc.runs["log_dir"].iloc[0]], capture_output=True, text=True)
    assert said.returncode == 0, said.stdout + said.stderr
    assert "goals.kind 'py-colours' is not one of afford's own" in said.stdout


def test_a_goal_out_of_the_scene_fails_the_run_naming_the_field(tmp_path):
    from goals import OutOfPlace
    with pytest.raises(afford.ExperimentError, match=r"goal chooser 'out-of-place' \(Python\): next\(\) at step 0 "
                                                     r"\(goal 0\) returned x = 1\.5"):
        afford.run("base", system="GOALS", reps=1, steps=20, out=tmp_path / "oop", goals=OutOfPlace, log_level="off")


def test_a_python_chooser_that_raises_is_said_once_with_its_trace(tmp_path, capfd):
    from goals import Raises
    with pytest.raises(afford.ExperimentError, match=r"goal chooser 'raises' \(Python\): next\(\) at step 0 \(goal 0\) "
                                                     r"raised ValueError: no goal here"):
        afford.run("base", system="GOALS", reps=1, steps=20, out=tmp_path / "r", goals=Raises)
    err = capfd.readouterr().err
    assert err.count("raised ValueError: no goal here") == 1 and err.count("goals.py(") == 1, err


def test_the_process_module_says_the_version_it_is():
    r = subprocess.run([sys.executable, "-m", "afford.process", "--version"], capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    assert r.stdout == f"afford.process {afford.__version__}\n"

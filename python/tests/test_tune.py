"""afford.tune / `afford tune`: studies with Optuna, shared by workers, pruned on the curves, stopped and continued."""
import contextlib
import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import afford

pytest.importorskip("optuna")

PYTHON = sys.executable
BIN = Path(os.environ.get("AFFORD_BIN", Path(__file__).resolve().parents[2] / "build" / "bin")).resolve()
LEAK = "motivation.leak=log:0.01:0.9"
RATE = "predictors.affordance.learning_rate=log:0.005:1"


def tune_command(out: Path, trials: int, steps: int, *more: str) -> list[str]:
    return [PYTHON, "-m", "afford", "tune", "base", "--out", str(out), "--param", LEAK, "--param", RATE,
            "--trials", str(trials), "--steps", str(steps), *more]


def run_tune(*command: str, **kw) -> subprocess.CompletedProcess:
    return subprocess.run(list(command), capture_output=True, text=True, env={**os.environ}, **kw)


def wait_for(condition, what: str, seconds: float = 60):
    end = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < end, f"waited {seconds} s for {what}"
        time.sleep(0.02)


def test_two_workers_share_one_study_and_run_each_trial_once(tmp_path):
    out = tmp_path / "study"
    command = tune_command(out, 6, 600)
    workers = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
               for _ in range(2)]
    said = [w.communicate(timeout=300)[0] for w in workers]
    assert [w.returncode for w in workers] == [0, 0], said
    s = afford.load_study(out)
    df = s.trials
    assert sorted(df["number"]) == list(range(6))  # six trials in all, none asked twice
    assert set(df["state"]) <= {"COMPLETE", "PRUNED"}
    assert df["worker"].nunique() == 2  # both took trials
    for f in df["folder"]:
        runs = list((out / f / "runs").glob("*.json"))
        assert len(runs) <= 1, f"{f} ran more than one experiment"
    # Every finished trial is an experiment folder: it loads, with the trial's parameters as its settings.
    best = s.best
    e = afford.load(s.best_folder)
    assert e.runs["affordance_mae"].iloc[0] == pytest.approx(best["value"])
    settings = json.loads((s.best_folder / "experiment.json").read_text())["options"]["settings"]
    assert f"motivation.leak={best['param motivation.leak']!r}" in settings
    r = afford.replay(e.runs["log_dir"].iloc[0], log_level="error")
    assert r["ok"] and r["weights_checksum"] == e.runs["weights_checksum"].iloc[0]
    # The report: the trials as CSV, the figures, the markdown naming the best trial's folder.
    for name in ("trials.csv", "fig_tune_history.png", "fig_tune_params.png", "report.md"):
        assert (out / name).stat().st_size > 0, name
    assert f"`{best['folder']}`" in (out / "report.md").read_text()


def test_successive_halving_stops_trials_at_its_rungs(tmp_path):
    s = afford.tune(tmp_path / "study", "base", params={"predictors.affordance.learning_rate": afford.Float(0.001, 1, log=True)},
                    trials=6, steps=1000, keep_logs="none", say=None)
    df = s.trials
    pruned = df[df["state"] == "PRUNED"]
    assert len(pruned), df
    # the rungs: 10% of the run (prune_warmup), then x3: 100, 300, 900 steps
    assert set(pruned["pruned_at"]) <= {100, 300, 900} and (pruned["intrinsic_steps"] < pruned["planned_steps"]).all()
    assert len(df[df["state"] == "COMPLETE"]) >= 1


def test_the_median_pruner_stops_a_trial_whose_curve_is_worse_than_the_median(tmp_path):
    s = afford.tune(tmp_path / "study", "base", params={"predictors.affordance.learning_rate": afford.Float(0.001, 1, log=True)},
                    trials=8, steps=1000, keep_logs="none", pruner="median", say=None)
    df = s.trials
    pruned = df[df["state"] == "PRUNED"]
    assert len(pruned), df
    for _, t in pruned.iterrows():
        assert 0 < t["intrinsic_steps"] < t["planned_steps"]
        folder = tmp_path / "study" / t["folder"]
        assert json.loads((folder / "experiment.json").read_text())["state"] == "interrupted"
        # ... worse, at the step it was pruned, than the median of the trials finished before it
        import optuna
        study = optuna.load_study(study_name="afford", storage=afford.study._storage(tmp_path / "study"))
        trial = study.trials[t["number"]]
        step = max(trial.intermediate_values)
        earlier = [u.intermediate_values[step] for u in study.trials
                   if u.number < t["number"] and u.state.name == "COMPLETE" and step in u.intermediate_values]
        assert len(earlier) >= 4 and trial.intermediate_values[step] > sorted(earlier)[(len(earlier) - 1) // 2]
    done = df[df["state"] == "COMPLETE"]
    assert (done["intrinsic_steps"] == done["planned_steps"]).all()


def interrupted_line(stderr: str) -> str:
    """The one line that says a study was interrupted, checked: no traceback, said once."""
    assert "Traceback" not in stderr, stderr
    lines = [line for line in stderr.splitlines() if line.startswith("afford tune: interrupted by SIG")]
    assert len(lines) == 1, stderr
    return lines[0]


def continue_as_said(line: str) -> subprocess.CompletedProcess:
    """The command the interrupted line names, pasted into a shell where it says."""
    where, command = re.fullmatch(r".*; the same command continues the study \(in (.*?)\): (.*)", line).groups()
    return subprocess.run(["/bin/sh", "-c", command], cwd=where, capture_output=True, text=True, timeout=300)


def test_ctrl_c_stops_a_study_and_the_same_command_continues_it(tmp_path):
    out = tmp_path / "study"
    command = tune_command(out, 2, 1500, "--no-prune", "--keep-logs", "none")
    worker = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    # once the second trial has begun (its folder holds its experiment), Ctrl-C
    wait_for(lambda: (out / "trials" / "0001" / "experiment.json").exists(), "the second trial")
    worker.send_signal(signal.SIGINT)
    said, stderr = worker.communicate(timeout=120)
    assert worker.returncode == 130, said + stderr
    assert "during trial 1" in interrupted_line(stderr)
    before = afford.load_study(out).trials
    assert list(before["state"]) == ["COMPLETE", "FAIL"] and before["stopped"].iloc[1] == "interrupted"
    again = continue_as_said(interrupted_line(stderr))
    assert again.returncode == 0, again.stdout + again.stderr
    df = afford.load_study(out).trials
    assert df["state"].iloc[0] == "COMPLETE" and df["value"].iloc[0] == before["value"].iloc[0]  # kept
    done = df[df["state"] == "COMPLETE"]
    assert len(done) == 2
    retry = df[df["retry_of"] == 1]
    assert len(retry) == 1 and retry["param motivation.leak"].iloc[0] == before["param motivation.leak"].iloc[1]


# SIGINT as `afford tune` starts, at a point of its own: when the process first imports the module named, or
# opens a file whose name ends so (a sitecustomize.py on its path, which Python runs as it starts).
SIGINT_AT = """import os, signal, sys
kind, name = os.environ["AFFORD_TEST_SIGINT_AT"].split(":")
def at(event, args, sent=[]):
    if not sent and event == kind and name in str(args[0]):
        sent.append(1)
        os.kill(os.getpid(), signal.SIGINT)
sys.addaudithook(at)
"""


@pytest.mark.parametrize("at", ["import:pandas", "import:optuna", "open:trials.csv"],
                         ids=["importing the package", "opening the study", "writing the report"])
def test_sigint_as_afford_tune_starts_and_ends_stops_it_in_one_line_with_nothing_lost(tmp_path, at):
    (tmp_path / "hook").mkdir()
    (tmp_path / "hook" / "sitecustomize.py").write_text(SIGINT_AT)
    out = tmp_path / "study"
    command = [str(BIN / "afford"), "tune", "base", "--out", str(out), "--param", LEAK, "--trials", "1",
               "--steps", "100", "--no-prune", "--keep-logs", "none"]
    r = subprocess.run(command, capture_output=True, text=True, timeout=120,
                       env={**os.environ, "AFFORD_TEST_SIGINT_AT": at,
                            "PYTHONPATH": f"{tmp_path / 'hook'}:{os.environ.get('PYTHONPATH', '')}"})
    assert r.returncode == 130, r.stdout + r.stderr
    line = interrupted_line(r.stderr)
    if at == "open:trials.csv":  # after its trial: the study is whole, its report written
        assert "as this worker ended" in line and (out / "report.md").is_file()
        assert afford.load_study(out).trials["state"].tolist() == ["COMPLETE"]
        return
    if at == "import:pandas":  # (held back until the study's handler was in place)
        assert "before the study began (nothing was written)" in line and not out.exists()
        return
    # as Optuna was imported to open the study: the study is made, no trial ran, and the command said continues it
    assert "before this worker's next trial" in line and afford.load_study(out).trials.empty
    again = continue_as_said(line)
    assert again.returncode == 0, again.stdout + again.stderr
    assert afford.load_study(out).trials["state"].tolist() == ["COMPLETE"]


def test_a_trial_whose_worker_was_killed_runs_again(tmp_path):
    out = tmp_path / "study"
    command = tune_command(out, 1, 1500, "--no-prune", "--keep-logs", "none")
    worker = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wait_for(lambda: (out / "trials" / "0000" / "experiment.json").exists(), "the first trial")
    worker.kill()
    worker.wait()
    assert afford.load_study(out).trials["state"].tolist() == ["RUNNING"]
    again = run_tune(*command, timeout=300)
    assert again.returncode == 0, again.stdout + again.stderr
    assert "its worker" in again.stdout and "is gone" in again.stdout
    df = afford.load_study(out).trials
    assert df["stopped"].iloc[0] == "worker lost"
    assert (df["state"] == "COMPLETE").sum() == 1 and (df["retry_of"] == 0).sum() == 1


def test_a_bad_study_is_refused_before_anything_runs(tmp_path):
    with pytest.raises(afford.ConfigError, match="parameter 'motivation.leek' at .*unknown key"):
        afford.tune(tmp_path / "a", params={"motivation.leek": "float:0.1:0.5"}, say=None)
    with pytest.raises(afford.ConfigError, match="parameter 'motivation.leak' at 2.0: .*out of range"):
        afford.tune(tmp_path / "a", params={"motivation.leak": afford.Float(0.1, 2.0)}, say=None)
    assert not (tmp_path / "a").exists()
    with pytest.raises(ValueError, match="'log:0:1'.*|a log scale needs a low above 0"):
        afford.tune(tmp_path / "a", params={"motivation.leak": "log:0:1"}, say=None)
    with pytest.raises(ValueError, match="is not float:LOW:HIGH"):
        afford.tune(tmp_path / "a", params={"motivation.leak": "between 0 and 1"}, say=None)
    with pytest.raises(ValueError, match="cannot prune"):
        afford.tune(tmp_path / "a", params={"motivation.leak": "float:0.1:0.5"}, objective="success",
                    prune=True, say=None)
    with pytest.raises(ValueError, match="objective 'nope.py:f': no file"):
        afford.tune(tmp_path / "a", params={"motivation.leak": "float:0.1:0.5"}, objective="nope.py:f", say=None)
    # A folder holding another study, or anything else, is not written into.
    afford.tune(tmp_path / "b", params={"motivation.leak": "float:0.1:0.5"}, trials=1, steps=200,
                keep_logs="none", say=None)
    with pytest.raises(ValueError, match=r"holds another study \(steps: 200 there, 300 here\)"):
        afford.tune(tmp_path / "b", params={"motivation.leak": "float:0.1:0.5"}, trials=1, steps=300,
                    keep_logs="none", say=None)
    (tmp_path / "c").mkdir()
    (tmp_path / "c" / "notes.txt").write_text("mine")
    with pytest.raises(ValueError, match="is not empty and holds no study"):
        afford.tune(tmp_path / "c", params={"motivation.leak": "float:0.1:0.5"}, say=None)
    assert (tmp_path / "c" / "notes.txt").read_text() == "mine"
    # ... and from the command line: exit 2, saying what is wrong
    said = run_tune(PYTHON, "-m", "afford", "tune", "base", "--out", str(tmp_path / "d"), "--param", "motivation.leak")
    assert said.returncode == 2 and "--param motivation.leak: KEY=SPEC" in said.stderr
    assert not (tmp_path / "d").exists()


def test_an_objective_of_ones_own_and_a_trial_it_fails(tmp_path):
    calls = []

    def objective(e):  # a function of the afford.load result; what it raises fails that trial, saying why
        calls.append(e)
        if len(calls) == 2:
            raise RuntimeError("no value for this one")
        return float(e.runs["looks"].iloc[0])

    s = afford.tune(tmp_path / "s", params={"motivation.leak": "float:0.1:0.5"}, objective=objective,
                    direction="maximize", trials=3, steps=300, keep_logs="none", say=None)
    df = s.trials
    assert df["state"].tolist() == ["COMPLETE", "FAIL", "COMPLETE"]
    assert "no value for this one" in df["error"].iloc[1]
    assert s.best["value"] == max(df["value"].dropna())
    # a named objective of the extrinsic tests: maximised, and no pruning (the curves' error is not its measure)
    t = afford.tune(tmp_path / "t", params={"motivation.leak": "float:0.1:0.5"}, objective="table2", trials=2,
                    steps=300, extrinsic_reps=2, scenarios=["scenario1"], keep_logs="none", say=None)
    assert t.definition["direction"] == "maximize" and t.definition["prune"] is False
    for _, row in t.trials.iterrows():
        e = afford.load(tmp_path / "t" / row["folder"])
        assert row["value"] == e.summary["systems"]["IMP"]["extrinsic"]["table_metric"]["scenario1"]


def test_on_curve_sees_each_point_and_can_stop_the_experiment(tmp_path):
    points = []

    def on_curve(p):
        points.append(p)
        return "enough" if p.step >= 300 else None

    with pytest.raises(afford.ExperimentStopped, match="enough") as stopped:
        afford.run("base", system="IMP", reps=2, steps=1000, out=tmp_path / "e", keep_logs="none", on_curve=on_curve)
    assert stopped.value.reason == "enough"
    assert [p.step for p in points] == [0, 100, 200, 300] and {p.run for p in points} == {0}
    assert points[0].mae == pytest.approx(0.5) and points[-1].mae < points[0].mae
    state = json.loads((tmp_path / "e" / "experiment.json").read_text())
    assert state["state"] == "interrupted" and state["interruptions"][0]["signal"] == "enough"
    # the run is said cut where it was (at least the curve point that stopped it), not where a heartbeat last was
    where = state["interruptions"][0]["cut"][0]["where"]
    assert re.fullmatch(r"interrupted at step (\d+)", where) and int(where.split()[-1]) >= 300, where
    # the folder resumes as an interrupted experiment's does, by the command its summary says (and the exception)
    said = json.loads((tmp_path / "e" / "summary.json").read_text())["interrupted"]
    assert f"to resume it (in {said['resume_in']}): {said['resume']}" in str(stopped.value)
    r = subprocess.run(["/bin/sh", "-c", said["resume"] + " --quiet --progress none"], cwd=said["resume_in"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert len(afford.load(tmp_path / "e").runs) == 2


def test_a_signal_as_a_trials_experiment_ends_stops_the_study_after_it_with_the_trial_finished(tmp_path,
                                                                                               monkeypatch):
    real = afford._afford.run_experiment

    def late(request):  # as if SIGINT came as the experiment wrote its summary: too late to stop any run
        code, _, errors, why = real(request)
        return code, signal.SIGINT, errors, why
    monkeypatch.setattr(afford._afford, "run_experiment", late)
    with pytest.raises(KeyboardInterrupt, match="before this worker's next trial"):
        tune_here(tmp_path / "study", 2)
    assert afford.load_study(tmp_path / "study").trials["state"].tolist() == ["COMPLETE"]


def test_a_signal_as_a_trial_begins_stops_it_at_its_first_curve_point(tmp_path, monkeypatch):
    real = afford.study.run

    def late(*args, **kwargs):  # as if SIGINT came as the trial began, before its experiment's handlers took over
        os.kill(os.getpid(), signal.SIGINT)
        return real(*args, **kwargs)
    monkeypatch.setattr(afford.study, "run", late)
    with pytest.raises(KeyboardInterrupt, match="during trial 0"):
        tune_here(tmp_path / "study", 1)
    df = afford.load_study(tmp_path / "study").trials
    assert df["state"].tolist() == ["FAIL"] and df["stopped"].iloc[0] == "interrupted"
    assert df["intrinsic_steps"].iloc[0] < df["planned_steps"].iloc[0]  # (stopped near its start, not at its end)


def test_the_help_names_every_system_and_the_default_pruner():
    from afford.tune_command import _parser
    said = {a.dest: " ".join(a.help.split()) for a in _parser()._actions if a.help}
    assert "GOALS" in afford._afford.systems
    for system in afford._afford.systems:
        assert system in said["system"]
        afford.check("base", system=system, steps=10)  # (one an experiment runs)
    assert "halving (the default" in said["pruner"] and "median" not in said["prune"]



# ---- a worker killed at any moment: nothing it leaves stops the others (docs/operating.md#locks) -------------

def tune_here(out: Path, trials: int, **kw) -> list[str]:
    """tune_command's study, in this process, without pruning: what it says."""
    said = []
    afford.tune(out, "base", params=dict(p.split("=", 1) for p in (LEAK, RATE)), trials=trials, steps=300,
                keep_logs="none", prune=False, say=said.append, **kw)
    return said


@contextlib.contextmanager
def within(seconds: int, what: str):
    """A bound on a block that would otherwise wait for good (SIGALRM raises in it)."""
    def late(*_):
        raise TimeoutError(f"{what}: still waiting after {seconds} s")
    old = signal.signal(signal.SIGALRM, late)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def dies_inside(what) -> None:
    """A child process that enters the context `what()` and is killed (SIGKILL) inside it."""
    r, w = os.pipe()
    pid = os.fork()
    if pid == 0:
        try:
            with what():
                os.write(w, b"1")
                signal.pause()
        finally:
            os._exit(1)
    os.close(w)
    done = os.read(r, 1)
    os.kill(pid, signal.SIGKILL)
    os.waitpid(pid, 0)
    os.close(r)
    assert done == b"1", "the child failed before it was killed"


def test_a_worker_killed_while_it_holds_the_journals_lock_does_not_stop_the_next(tmp_path):
    out = tmp_path / "study"
    tune_here(out, 1)
    lock = afford.study._storage(out)._backend._lock  # (killed while appending to the journal)
    dies_inside(lambda: contextlib.nullcontext(lock.acquire()))
    with within(60, "the next worker, waiting for the journal's lock"):
        tune_here(out, 2)
    assert afford.load_study(out).trials["state"].tolist() == ["COMPLETE", "COMPLETE"]


@pytest.fixture(scope="module")
def one_trial(tmp_path_factory) -> Path:
    """A study of one trial, made once: tests copy it."""
    out = tmp_path_factory.mktemp("one") / "study"
    tune_here(out, 1)
    return out


@pytest.mark.parametrize("first", ["writer", "reader"])
@pytest.mark.parametrize("tail", [b'{"op_code": 2, "worker_id": "w", "study_id": 0, "user_at',
                                  b'{"op_code": 2, "worker_id": "w", "study_id": 0, "user_attr": {"c": 3}}'],
                         ids=["torn", "whole"])
def test_a_journal_line_its_killed_writer_left_unended_is_mended_by_the_next(tmp_path, one_trial, tail, first):
    import shutil
    import optuna
    from optuna.storages import JournalFileStorage
    out = tmp_path / "study"
    shutil.copytree(one_trial, out)
    journal = out / "study.journal"
    before = journal.read_bytes()
    with open(journal, "ab") as f:
        f.write(tail)  # (a line whose writer was killed before its end)
    whole = tail.endswith(b"}")
    mended = before + (tail + b"\n" if whole else b"")
    if first == "writer":  # the next to touch the journal appends to it, without reading it
        writer = JournalFileStorage(str(journal), lock_obj=afford.locks.JournalLock(journal))
        for key, value in (("a", 1), ("b", 2)):
            writer.append_logs([{"op_code": 2, "worker_id": "w", "study_id": 0, "user_attr": {key: value}}])
    else:  # a worker reads it first (as the killed one left it), then appends
        study = optuna.load_study(study_name="afford", storage=afford.study._storage(out))
        assert journal.read_bytes() == mended and study.user_attrs == ({"c": 3} if whole else {})
        study.set_user_attr("a", 1)
        study.set_user_attr("b", 2)
        assert study.user_attrs == ({"c": 3} if whole else {}) | {"a": 1, "b": 2}
    again = optuna.load_study(study_name="afford", storage=afford.study._storage(out))  # (reads it all anew)
    assert again.user_attrs == ({"c": 3} if whole else {}) | {"a": 1, "b": 2}
    assert journal.read_bytes().startswith(mended)
    lines = journal.read_bytes().split(b"\n")
    assert lines[-1] == b"" and all(json.loads(line) is not None for line in lines[:-1])


def test_a_reader_takes_a_line_being_written_whole_never_in_two_pieces(tmp_path, monkeypatch):
    import threading
    from optuna.storages._journal import file as optuna_file
    out = tmp_path / "study"
    tune_here(out, 1)
    journal = out / "study.journal"
    storage = afford.study._storage(out)  # (a worker's, which has read the journal so far)
    line = json.dumps({"op_code": 2, "worker_id": "w", "study_id": 0, "user_attr": {"c": 3}}).encode() + b"\n"
    go_on, half_written = os.pipe(), os.pipe()
    writer = os.fork()
    if writer == 0:  # another worker, in the middle of an append: half of its line written, under the lock
        try:
            lock = afford.locks.JournalLock(journal)
            lock.acquire()
            with open(journal, "ab", buffering=0) as f:
                f.write(line[:40])
                os.write(half_written[1], b"1")
                os.read(go_on[0], 1)
                f.write(line[40:])
            lock.release()
        finally:
            os._exit(0)
    assert os.read(half_written[0], 1) == b"1"
    half = journal.stat().st_size
    saw_half = threading.Event()

    class Slow:  # (the reader's file: at a line's first half, it waits until the writer has written the rest)
        def __init__(self, f):
            self.f = f

        def __getattr__(self, name):
            return getattr(self.f, name)

        def __enter__(self):
            return self

        def __exit__(self, *exc):
            self.f.close()

        def __iter__(self):
            while piece := self.f.readline():
                yield piece
                if not piece.endswith(b"\n"):
                    saw_half.set()
                    wait_for(lambda: journal.stat().st_size > half, "the writer to finish its line")
    monkeypatch.setattr(optuna_file, "open", lambda *a, **k: Slow(open(*a, **k)), raising=False)
    failed = []
    reader = threading.Thread(target=lambda: failed.extend(_raised(storage.get_all_studies)))
    reader.start()
    wait_for(lambda: saw_half.is_set() or waits_for_a_lock(os.getpid()),
             "the reader to wait for the writer, or to see half its line")
    os.write(go_on[1], b"1")
    reader.join(60)
    os.waitpid(writer, 0)
    assert not failed, failed
    assert storage.get_study_user_attrs(0) == {"c": 3}


def waits_for_a_lock(pid: int) -> bool:
    """The process `pid` waits for a flock (/proc/locks: "N: -> FLOCK ADVISORY READ PID ...")."""
    return any(f[1:3] == ["->", "FLOCK"] and f[5] == str(pid)
               for f in (line.split() for line in Path("/proc/locks").read_text().splitlines()) if len(f) > 5)


def _raised(call) -> list[BaseException]:
    try:
        call()
    except Exception as e:  # (to the test's thread)
        return [e]
    return []


def test_a_trial_asked_for_by_a_worker_that_died_before_claiming_it_runs_again(tmp_path):
    import optuna
    out = tmp_path / "study"
    tune_here(out, 1)

    @contextlib.contextmanager
    def ask():  # as a worker does under the claim; killed there, before it names itself the trial's worker
        study = optuna.load_study(study_name="afford", storage=afford.study._storage(out))
        with afford.locks.claim(out):
            study.ask({k: afford.study._distribution(afford.study.parse_param(k, v))
                       for k, v in json.loads((out / "study.json").read_text())["params"].items()})
            yield
    dies_inside(ask)
    before = afford.load_study(out).trials
    assert before["state"].tolist() == ["COMPLETE", "RUNNING"] and before["worker"].iloc[1] is None
    said = tune_here(out, 2)
    assert "trial 1: its worker died before claiming it: it runs again" in said
    df = afford.load_study(out).trials
    assert df["state"].tolist() == ["COMPLETE", "FAIL", "COMPLETE"] and df["stopped"].iloc[1] == "worker lost"
    assert df["retry_of"].iloc[2] == 1
    assert df["param motivation.leak"].iloc[2] == before["param motivation.leak"].iloc[1]


def test_another_hosts_trial_runs_again_once_its_worker_is_gone_and_not_before(tmp_path):
    out = tmp_path / "study"
    objective = tmp_path / "objective.py"  # on the other host, it holds its trial until killed
    objective.write_text("import socket, threading\n\ndef mae(e):\n    if socket.gethostname() == 'node-b':\n"
                         "        print('in the objective', flush=True)\n        threading.Event().wait()\n"
                         "    return float(e.runs['affordance_mae'].mean())\n")
    command = tune_command(out, 1, 300, "--keep-logs", "none", "--no-prune", "--objective", f"{objective}:mae")
    other = subprocess.Popen([PYTHON, "-c", "import socket, sys\nsocket.gethostname = lambda: 'node-b'\n"
                              "from afford.tune_command import main\nsys.exit(main(sys.argv[1:]))", *command[4:]],
                             stdout=subprocess.PIPE, text=True)
    assert other.stdout.readline().strip() == "in the objective"
    # alive on its host (its worker file held): its trial is left to it
    said = tune_here(out, 2, objective=f"{objective}:mae")
    assert "1 trial(s) still run in other workers; this worker is done" in said
    df = afford.load_study(out).trials
    assert df["state"].tolist() == ["RUNNING", "COMPLETE"] and df["worker"].iloc[0] == f"node-b:{other.pid}"
    other.kill()  # (a node lost: its locks go with it)
    other.wait()
    other.stdout.close()
    said = tune_here(out, 2, objective=f"{objective}:mae")
    assert f"trial 0: its worker (node-b:{other.pid}) is gone: it runs again" in said
    df = afford.load_study(out).trials
    assert df["state"].tolist() == ["FAIL", "COMPLETE", "COMPLETE"] and df["retry_of"].iloc[2] == 0
    assert not list((out / "workers").iterdir())  # (each worker's file gone with it)


def test_a_lock_matplotlib_left_behind_does_not_stop_a_studys_figures(tmp_path):
    """Matplotlib's font-cache lock is a file of its own (not a kernel lock): a process killed while it wrote the cache
    left it, and every later import of pyplot waited 5 s and raised TimeoutError (a study's report with it). One that
    no live process can hold (older than a writer ever holds it) is taken away by afford's pyplot()."""
    cache = tmp_path / "mpl"  # a cache without its font list: Matplotlib writes it, under its lock
    cache.mkdir()
    from matplotlib import font_manager
    stale = cache / f"fontlist-v{font_manager.FontManager.__version__}.json.matplotlib-lock"
    stale.write_text("")
    then = time.time() - 3600
    os.utime(stale, (then, then))
    r = subprocess.run([sys.executable, "-c", "from afford import locks; plt = locks.pyplot(); plt.figure()"],
                       env={**os.environ, "MPLCONFIGDIR": str(cache)}, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert not stale.exists()
    assert list(cache.glob("fontlist-*.json")), "Matplotlib wrote no font cache"


def test_a_study_of_0_2_0_reads_its_extrinsic_reps_of_zero_as_the_experiments_count(tmp_path):
    # 0.1.0 and 0.2.0 kept extrinsic_reps, 0 for "not given"; 0.3.0 keeps extrinsic_tests (None: not given).
    from afford.study import _read_definition
    old = tmp_path / "study.json"
    for kept, read in ((0, None), (2, 2)):
        old.write_text(json.dumps({"experiment": "base", "extrinsic_reps": kept}))
        d = _read_definition(old)
        assert d["extrinsic_tests"] == read and "extrinsic_reps" not in d
    old.write_text(json.dumps({"experiment": "base", "extrinsic_tests": 0}))
    assert _read_definition(old)["extrinsic_tests"] == 0


def test_a_range_given_in_python_and_on_the_command_line_is_one_study():
    # afford.Float(0.005, 1, log=True) and `--param KEY=log:0.005:1` are one range: a worker started either way
    # joins the other's study (the study's folder compares the specs).
    from afford.search import parse_param
    given = parse_param("k", afford.Float(0.005, 1, log=True)).spec()
    assert given == parse_param("k", "log:0.005:1").spec() == parse_param("k", "log:0.005:1.0").spec()
    assert afford.Int(1, 8).spec() == parse_param("k", "int:1:8").spec()


def test_a_table_study_estimates_the_truth_once_for_every_trial(tmp_path, capfd):
    """A table world's trials are measured against its truth, estimated once into the study's folder (out/truth)
    and read by every trial after; checking the study's keys estimates none. A study varying the table's own
    physics (a key of the table section) has a truth per world it tries."""
    s = afford.tune(tmp_path / "s", "table", params={"motivation.leak": "float:0.1:0.5"}, trials=2, steps=40,
                    set={"table.truth.trials": 2}, keep_logs="none", say=None, log_level="info")
    assert s.trials["state"].tolist() == ["COMPLETE", "COMPLETE"]
    stored = sorted((tmp_path / "s" / "truth").glob("table-*.json"))
    assert len(stored) == 1, stored
    assert not list((tmp_path / "s" / "trials").glob("*/logs/truth")), "a trial estimated its own truth"
    said = "".join(capfd.readouterr())
    assert said.count("estimating the table's truth") == 1, said
    assert said.count("(estimated before)") == 1, said

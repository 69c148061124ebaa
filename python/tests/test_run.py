"""afford.run: an experiment in this process, as `afford experiment` runs it."""
import json
import os
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import afford


def test_a_run_returns_its_experiment_and_is_the_commands(made, tmp_path):
    said = []
    e = afford.run("base", system="IMP", reps=1, steps=400, out=tmp_path / "run", run_prefix="py", say=said.append)
    assert len(e.runs) == 1 and e.summary["steps"] == 400
    # it says, through Python (a notebook shows it), what it runs and where, and each run as it finishes
    text = "\n".join(said)
    assert f"experiment base (IMP): 1 run(s) of 400 steps, 1 at a time, over memq" in text, text
    assert f"into {tmp_path / 'run'}" in text, text
    assert f"[1/1] py-base-IMP-s1 done in" in text, text
    # the command's run of the same seed and steps (made by conftest: --system all --reps 2 --steps 400)
    base = afford.load(made / "base")
    same = base.runs[(base.runs.system == "IMP") & (base.runs.seed == 1)]
    assert e.runs["weights_checksum"].iloc[0] == same["weights_checksum"].iloc[0]


def test_settings_are_config_keys(tmp_path):
    a = afford.run("base", system="IMP", reps=1, steps=300, out=tmp_path / "a", set={"motivation.leak": 0.3})
    b = afford.run("base", system="IMP", reps=1, steps=300, out=tmp_path / "b")
    assert a.runs["weights_checksum"].iloc[0] != b.runs["weights_checksum"].iloc[0]
    with pytest.raises(afford.ConfigError, match="'motivation.leek': unknown key; did you mean 'motivation.leak'"):
        afford.run("base", system="IMP", reps=1, steps=300, out=tmp_path / "c", set={"motivation.leek": 0.3})
    with pytest.raises(ValueError, match="steps is a whole number, at least 1"):
        afford.run("base", system="IMP", reps=1, steps=0, out=tmp_path / "e")
    with pytest.raises(ValueError):  # a ConfigError is one
        afford.run("no-such-experiment", out=tmp_path / "d")


SCRIPT = textwrap.dedent("""
    import os, signal, sys, threading, time
    from pathlib import Path
    import afford
    out = Path(sys.argv[1])
    def interrupt():  # as soon as the first run has logged its configuration
        while not list((out / "logs").glob("*/log.00.lcm")):
            time.sleep(0.01)
        os.kill(os.getpid(), signal.SIGINT)
    threading.Thread(target=interrupt, daemon=True).start()
    try:
        afford.run("base", system="IMP", reps=2, steps=200000, out=out, run_prefix="ctrlc")
        print("not interrupted")
    except KeyboardInterrupt as e:
        print("KeyboardInterrupt:", e)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler, signal.getsignal(signal.SIGINT)
    e = afford.run("base", system="IMP", reps=1, steps=200, out=out.parent / "after", run_prefix="after")
    print("after:", len(e.runs))
""")


def test_ctrl_c_stops_it_as_it_stops_the_command_and_python_goes_on(tmp_path):
    r = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path / "cut")], capture_output=True, text=True,
                       timeout=240, env=os.environ)
    assert r.returncode == 0, r.stdout + r.stderr
    assert "KeyboardInterrupt: afford.run('base') was interrupted" in r.stdout, r.stdout + r.stderr
    assert "after: 1" in r.stdout
    summary = json.loads((tmp_path / "cut" / "summary.json").read_text())
    assert summary["interrupted"]["signal"] == "SIGINT"


def test_a_signal_as_the_experiment_is_checked_stops_it_before_any_run(tmp_path):
    class SignalsOnce(afford.Motivation):  # its first copy is made as the experiment is checked, before any run
        kind = "signals-once"
        made = []

        def __init__(self, *args, **kwargs):
            if not SignalsOnce.made:
                os.kill(os.getpid(), signal.SIGINT)  # (Ctrl-C, as the experiment is being checked)
            SignalsOnce.made.append(1)

        def decide(self, p):
            return afford.Decision(True, 0, 0.0, 0.0)
    with pytest.raises(KeyboardInterrupt, match="was interrupted"):
        afford.run("base", system="IMP", reps=1, steps=100, out=tmp_path / "e", motivation=SignalsOnce,
                   log_level="off")
    said = json.loads((tmp_path / "e" / "summary.json").read_text())["interrupted"]
    assert said["signal"] == "SIGINT" and said["finished"] == 0 and len(said["not_started"]) == 1


def test_calls_in_a_loop_with_one_log_root_never_collide(tmp_path):
    # run ids start with the second; twenty calls within a few seconds take twenty prefixes
    ids = set()
    for k in range(20):
        e = afford.run("base", system="IMP", reps=1, steps=5, out=tmp_path / f"o{k}", log_root=tmp_path / "logs",
                       reuse_agents=False, keep_logs="none")
        ids.update(e.runs["run_id"])
    assert len(ids) == 20


def test_an_experiment_never_mixes_with_another_in_its_folder(tmp_path):
    out = tmp_path / "out"
    first = afford.run("base", system="IMP", reps=1, steps=60, out=out, extrinsic_reps=1, scenarios=["scenario1"])
    assert len(first.extrinsic) == 1
    with pytest.raises(afford.ConfigError, match="holds a finished experiment .* --replace"):
        afford.run("base", system="IMP", reps=1, steps=40, out=out)
    (out / "fig_old.png").write_bytes(b"a figure of the first experiment")
    second = afford.run("base", system="IMP", reps=1, steps=40, out=out, replace=True)
    assert second.summary["steps"] == 40 and len(second.extrinsic) == 0
    assert not (out / "extrinsic_IMP.csv").exists() and not (out / "fig_old.png").exists()
    (out / "notes.txt").write_text("mine")
    with pytest.raises(afford.ConfigError, match=r"files afford did not write \(notes.txt\)"):
        afford.run("base", system="IMP", reps=1, steps=40, out=out, replace=True)
    assert (out / "notes.txt").read_text() == "mine" and afford.load(out).summary["steps"] == 40


def test_a_zero_given_is_a_zero_and_left_out_the_experiment_says(tmp_path):
    # an experiment file asking for a test of its own (extrinsic.tests); extrinsic_reps=0 runs none.
    asks = tmp_path / "asks.yaml"
    asks.write_text("extends: base\nextrinsic: {scenarios: [scenario1], tests: 1}\n")
    none = afford.run(str(asks), system="IMP", reps=1, steps=50, out=tmp_path / "zero", extrinsic_reps=0,
                      keep_logs="none")
    assert len(none.extrinsic) == 0
    own = afford.run(str(asks), system="IMP", reps=1, steps=50, out=tmp_path / "own", keep_logs="none")
    assert len(own.extrinsic) == 1

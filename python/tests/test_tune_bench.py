"""bench/tune_bench.py's floor that no trial ran twice: it reads what the trial folders hold, and a duplicate put
there on purpose is found."""
import importlib.util
from pathlib import Path

import pytest

import afford

pytest.importorskip("optuna")


def bench():
    spec = importlib.util.spec_from_file_location("tune_bench", Path(__file__).resolve().parents[2] / "bench" /
                                                  "tune_bench.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_a_trial_run_twice_is_found_in_what_the_trial_folders_hold(tmp_path):
    import optuna
    ran_twice = bench().ran_twice
    out, params = tmp_path / "study", {"motivation.leak": "float:0.1:0.5"}

    def study(trials: int):
        afford.tune(out, params=params, trials=trials, steps=200, keep_logs="none", prune=False, say=None)
        return afford.load_study(out).trials
    assert ran_twice(out, study(1)) == []
    # a fault: trial 0's values queued again as the retry of a stopped trial, though it ran to its end
    journal = optuna.load_study(study_name="afford", storage=afford.study._storage(out))
    journal.enqueue_trial(journal.trials[0].params, user_attrs={"retry_of": 0})
    assert ran_twice(out, study(2)) == ["trial 1 ran the values of trial 0 again, which had run to its end"]
    # another: a second experiment in trial 1's folder, planned with another trial's run ids
    afford.run("base", system="IMP", reps=1, steps=100, out=out / "trials" / "0001", run_prefix="trial0002",
               keep_logs="none", replace=True)
    said = ran_twice(out, afford.load_study(out).trials)
    assert "trial 1: trials/0001 plans run trial0002-base-IMP-s1, not its own" in said, said

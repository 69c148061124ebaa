"""Studies over config keys with Optuna: afford.tune(...) and `afford tune` (python3 -m afford tune).

    import afford
    s = afford.tune("studies/leak", "base", params={"motivation.leak": afford.Float(0.01, 0.9, log=True)},
                    objective="affordance_mae", trials=24, steps=3000)
    s.trials            # one row per trial: its state, value, parameters, folder, intrinsic steps
    afford.load(s.best_folder)

A study is a folder: study.json (what it searches and how), study.journal
(Optuna's journal file storage, which every worker shares through the file
system), study.lock and workers/ (its locks, python/afford/locks.py),
trials/NNNN (each trial an ordinary experiment folder: it loads, plots and
replays as any other), and, as trials end, trials.csv,
fig_tune_history.png, fig_tune_params.png and report.md. Several workers
(processes, or Slurm array tasks of scripts/slurm-submit.sh --tune) given
the same folder share the study: together they run `trials` trials, each
once. Pruning stops a trial whose learning curve's error, at a curve step,
falls behind the other trials' at that step (successive halving, or the
median pruner). Ctrl-C (or SIGTERM) stops the trial under way as it stops an
experiment; running the same command again continues the study, the stopped
trial's parameters first. docs/python.md#studies.
"""
from __future__ import annotations

import contextlib
import json
import math
import os
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

from . import _afford, locks
from .experiments import CurvePoint, ExperimentError, ExperimentStopped, check, run
from .results import Experiment
from .search import OBJECTIVES, Choice, _distribution, _objective, parse_param

STUDY_NAME = "afford"
KEPT = ("experiment", "system", "reps", "steps", "set", "params", "objective", "direction", "seed", "prune",
        "pruner", "prune_startup", "prune_warmup", "extrinsic_tests", "scenarios", "keep_logs")  # study.json's fields a later command must match
RETRIED = ("interrupted", "worker lost")  # trials stopped by these run again (their parameters first)


def _read_definition(file: Path) -> dict[str, Any]:
    """study.json as this release writes it: 0.1.0 and 0.2.0 kept `extrinsic_reps`, 0 for "not given" (the
    experiment's own count); from 0.3.0 `extrinsic_tests` is None for that and 0 for no tests."""
    d = json.loads(file.read_text())
    if "extrinsic_tests" not in d:
        d["extrinsic_tests"] = d.pop("extrinsic_reps", 0) or None
    return d


def _stopped(t) -> str | None:
    """Why a trial stopped short: "interrupted" (Ctrl-C), "worker lost" (it failed with nothing said: its
    worker was found gone), or None (it finished, was pruned, or failed saying why)."""
    from optuna.trial import TrialState
    a = t.user_attrs
    if a.get("stopped"):
        return a["stopped"]
    return "worker lost" if t.state == TrialState.FAIL and not a.get("error") else None


# ---- the study folder ----------------------------------------------------------------------------------------

def _write_whole(path: Path, text: str) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def _storage(folder: Path):
    import warnings
    import optuna
    from optuna.storages import JournalStorage
    with warnings.catch_warnings():  # (Optuna 3.1 calls its journal storage experimental; it is what shares a study)
        warnings.simplefilter("ignore", optuna.exceptions.ExperimentalWarning)
        return JournalStorage(locks.journal(folder / "study.journal"))  # (its locks: flocks, locks.py)


def _sampler(seed: int, number: int):
    """TPE, its randomness keyed by (seed, trial number): a worker's draws do not depend on which worker it is."""
    import numpy as np
    import optuna
    key = int(np.random.SeedSequence([seed, number, 0x7475]).generate_state(1)[0])
    return optuna.samplers.TPESampler(seed=key)


PRUNERS = ("halving", "median")


def _pruner(d: dict[str, Any], first_run_steps: int):
    """halving (default): Optuna's successive halving (asynchronous, as Ray Tune's ASHA): at steps
    warmup x 3^k a trial goes on only if its curve's error is among the best third of the trials that got
    there. median: Optuna's median pruner: from the `prune_startup`-th finished trial on, a trial past the
    warmup whose curve's error at a step is above the finished trials' median there stops. The warmup is
    `prune_warmup` of the first run's steps."""
    import optuna
    if not d["prune"]:
        return optuna.pruners.NopPruner()
    warmup = max(1, int(d["prune_warmup"] * first_run_steps))
    if d["pruner"] == "halving":
        return optuna.pruners.SuccessiveHalvingPruner(min_resource=warmup, reduction_factor=3)
    return optuna.pruners.MedianPruner(n_startup_trials=d["prune_startup"], n_warmup_steps=warmup)


# ---- results ----------------------------------------------------------------------------------------------------

@dataclass
class Study:
    """A study folder as data: `trials` one row per trial; `definition` what study.json says."""
    folder: Path
    definition: dict[str, Any]
    trials: Any  # pandas.DataFrame

    @property
    def best(self):
        done = self.trials[self.trials["state"] == "COMPLETE"]
        if done.empty:
            return None
        values = done["value"]
        return done.loc[values.idxmin() if self.definition["direction"] == "minimize" else values.idxmax()]

    @property
    def best_folder(self) -> Path | None:
        b = self.best
        return None if b is None else self.folder / b["folder"]

    def __repr__(self) -> str:
        counts = self.trials["state"].value_counts().to_dict() if len(self.trials) else {}
        return f"Study({str(self.folder)!r}: {self.definition.get('objective')}, {counts})"


def _frame(folder: Path, definition: dict[str, Any], trials: Sequence[Any]):
    import pandas as pd
    rows = []
    for t in trials:
        a = t.user_attrs
        row = {"number": t.number, "state": t.state.name,
               "value": t.value if t.state.name == "COMPLETE" else None,  # (a pruned trial's: its last_intermediate)
               "stopped": _stopped(t), "retry_of": a.get("retry_of"),
               "intrinsic_steps": a.get("intrinsic_steps"), "planned_steps": a.get("planned_steps"),
               "pruned_at": a.get("pruned_at"),
               "last_intermediate": t.intermediate_values[max(t.intermediate_values)] if t.intermediate_values else None,
               "seconds": t.duration.total_seconds() if t.duration else None,
               "folder": a.get("folder"), "worker": "{host}:{pid}".format(**a["worker"]) if a.get("worker") else None,
               "error": a.get("error")}
        for key in definition["params"]:
            row[f"param {key}"] = t.params.get(key)
        rows.append(row)
    columns = ["number", "state", "value", *[f"param {k}" for k in definition["params"]], "stopped", "retry_of",
               "intrinsic_steps", "planned_steps", "pruned_at", "last_intermediate", "seconds", "folder", "worker",
               "error"]
    df = pd.DataFrame(rows, columns=columns)
    for c in ("retry_of", "intrinsic_steps", "planned_steps", "pruned_at"):
        df[c] = df[c].astype("Int64")
    df["value"] = df["value"].astype(float)
    return df


def load_study(folder: str | Path) -> Study:
    """A study folder (afford.tune, `afford tune --out DIR`) as a Study: its trials as a data frame."""
    folder = Path(folder)
    if not (folder / "study.json").is_file():
        raise FileNotFoundError(f"{folder} holds no study.json: not a study's folder")
    definition = _read_definition(folder / "study.json")
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    trials = optuna.load_study(study_name=STUDY_NAME, storage=_storage(folder)).get_trials(deepcopy=False)
    return Study(folder, definition, _frame(folder, definition, trials))


def _scale(ax, values) -> None:
    """A log scale for values that span more than two decades (an error going from 0.05 to 1e-8)."""
    v = [x for x in values if x is not None and x == x]
    if v and min(v) > 0 and max(v) / min(v) > 100:
        ax.set_yscale("log")


def _save(fig, path: Path) -> None:
    plt = locks.pyplot()
    tmp = path.with_name(f".{path.stem}.{os.getpid()}.tmp.png")
    fig.savefig(tmp)
    plt.close(fig)
    os.replace(tmp, path)


def write_report(study: Study) -> Path:
    """trials.csv, fig_tune_history.png, fig_tune_params.png and report.md in the study's folder."""
    plt = locks.pyplot()

    folder, d, df = study.folder, study.definition, study.trials
    _write_whole(folder / "trials.csv", df.to_csv(index=False))
    minimize = d["direction"] == "minimize"
    done = df[df["state"] == "COMPLETE"].sort_values("number")
    pruned = df[df["state"] == "PRUNED"]

    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    ax.scatter(done["number"], done["value"], color="tab:blue", label="finished", zorder=3)
    if len(pruned):
        ax.scatter(pruned["number"], pruned["last_intermediate"], marker="x", color="tab:gray",
                   label="pruned (its curve's error when pruned)", zorder=2)
    if len(done):
        best = done["value"].cummin() if minimize else done["value"].cummax()
        ax.step(done["number"], best, where="post", color="tab:red", label="best so far")
    ax.set_xlabel("trial")
    ax.set_ylabel(d["objective"])
    _scale(ax, list(done["value"]) + list(pruned["last_intermediate"]))
    ax.set_title(f"{d['experiment']}: {d['objective']} ({d['direction']}), {len(done)} finished, {len(pruned)} pruned")
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, folder / "fig_tune_history.png")

    keys = list(d["params"])
    fig, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 3.6), dpi=110, squeeze=False)
    for ax, key in zip(axes[0], keys):
        p = parse_param(key, d["params"][key])
        column = f"param {key}"
        if isinstance(p, Choice):
            names = [str(c) for c in p.choices]
            where = {n: i for i, n in enumerate(names)}
            ax.scatter([where.get(str(v), -1) for v in done[column]], done["value"], color="tab:blue")
            ax.set_xticks(range(len(names)), names)
        else:
            ax.scatter(done[column], done["value"], color="tab:blue", label="finished")
            if len(pruned):
                ax.scatter(pruned[column], pruned["last_intermediate"], marker="x", color="tab:gray", label="pruned")
            if p.log:
                ax.set_xscale("log")
        ax.set_xlabel(key)
        ax.set_ylabel(d["objective"])
        _scale(ax, list(done["value"]) + list(pruned["last_intermediate"]))
    if len(pruned) and axes[0][0].get_legend_handles_labels()[0]:
        axes[0][0].legend(fontsize=8)
    fig.suptitle("parameters against the objective")
    fig.tight_layout()
    _save(fig, folder / "fig_tune_params.png")

    counts = df["state"].value_counts().to_dict()
    lines = [f"# Study of {d['experiment']} ({d['system']}): {d['objective']}, {d['direction']}d", "",
             f"Folder `{folder}`; {len(df)} trials: " + ", ".join(f"{n} {s.lower()}" for s, n in sorted(counts.items())) +
             f". Intrinsic steps run: {int(df['intrinsic_steps'].fillna(0).sum())} of "
             f"{int(df['planned_steps'].fillna(0).sum())} planned.", "",
             "Searched: " + ", ".join(f"`{k}` {v}" for k, v in d["params"].items()) +
             (f"; fixed: " + ", ".join(f"`{k}={v}`" for k, v in d["set"].items()) if d["set"] else "") + ".", ""]
    if len(done):
        top = done.sort_values("value", ascending=minimize).head(10)
        lines += ["| trial | value | " + " | ".join(keys) + " | folder |",
                  "|---|---|" + "---|" * len(keys) + "---|"]
        for _, r in top.iterrows():
            lines.append(f"| {r['number']} | {r['value']:.4g} | " +
                         " | ".join(f"{r[f'param {k}']:.4g}" if isinstance(r[f"param {k}"], float) else
                                    str(r[f"param {k}"]) for k in keys) + f" | `{r['folder']}` |")
        lines.append("")
    lines += ["![history](fig_tune_history.png)", "", "![parameters](fig_tune_params.png)", "",
              "The trials, one row each: `trials.csv` (or `afford.load_study(folder).trials`)."]
    _write_whole(folder / "report.md", "\n".join(lines) + "\n")
    return folder / "report.md"


# ---- running a study --------------------------------------------------------------------------------------------

class Stop:
    """The signal a study was sent (0: none), SIGINT or SIGTERM. The first is said at once and remembered, and
    `check` raises KeyboardInterrupt where the study stops with nothing lost: before it is made, between trials,
    after its report (a trial under way stops as an experiment does); a second quits at once (KeyboardInterrupt
    where the program is)."""

    def __init__(self):
        self.signal = 0

    @property
    def name(self) -> str:
        return signal.Signals(self.signal).name if self.signal else ""

    def on(self, sig, frame) -> None:
        if self.signal:
            raise KeyboardInterrupt(f"and again by {signal.Signals(sig).name}, at once (what had finished is kept)")
        self.signal = sig
        print(f"\nafford tune: {self.name}: stopping before the next trial begins, with what finished kept (a second "
              f"signal quits at once)", file=sys.stderr, flush=True)

    def check(self, where: str) -> None:
        if self.signal:
            raise KeyboardInterrupt(where)


STOP_SIGNALS = {signal.SIGINT, signal.SIGTERM}
_current: Stop | None = None  # the Stop whose handlers are in place (main thread)


def stop_on_signals() -> Stop:
    """A Stop whose handlers are in place for good (`afford tune`, which ends with the study), and the signals let
    through: one `afford tune` held back from its start (apps/afford/commands/tune.cpp) comes now."""
    global _current
    _current = Stop()
    for s in STOP_SIGNALS:
        signal.signal(s, _current.on)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    return _current


@contextlib.contextmanager
def _stopping():
    """The Stop in place (the command's), else one in place while this runs, its signals let through and the
    handlers and mask before it put back after. Outside the main thread, whose the handlers are, a Stop no signal
    reaches (afford.run still stops on Ctrl-C)."""
    global _current
    if threading.current_thread() is not threading.main_thread():
        yield Stop()
        return
    if _current is not None:
        yield _current
        return
    stop = _current = Stop()
    old = {s: signal.signal(s, stop.on) for s in STOP_SIGNALS}
    mask = signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    try:
        yield stop
    finally:
        _current = None
        for s, h in old.items():
            signal.signal(s, h)
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)


def _definition(experiment, system, reps, steps, set, params, objective, direction, seed, prune, pruner, prune_startup,
                prune_warmup, extrinsic_reps, scenarios, keep_logs, trials) -> dict[str, Any]:
    if not params:
        raise ValueError("a study searches at least one config key: give params ({'key': afford.Float(...)}, "
                         "or --param KEY=SPEC)")
    parsed = {k: parse_param(k, v) for k, v in params.items()}
    if not callable(objective) and objective not in OBJECTIVES:
        _objective(objective)  # a FILE.py:FUNCTION: found and loadable now, not after the first trial
    if direction is None:
        direction = OBJECTIVES[objective][1] if isinstance(objective, str) and objective in OBJECTIVES else "minimize"
    if direction not in ("minimize", "maximize"):
        raise ValueError(f"direction '{direction}': minimize or maximize")
    if prune is None:
        prune = direction == "minimize" and isinstance(objective, str) and objective in ("affordance_mae", "curve_mae")
    if prune and direction != "minimize":
        raise ValueError("pruning compares the learning curves' affordance error, which is better lower: a study "
                         "that maximizes cannot prune on it (prune=False, --no-prune)")
    if isinstance(trials, bool) or not isinstance(trials, int) or trials < 1:
        raise ValueError(f"trials={trials!r}: a whole number, at least 1")
    if isinstance(prune_startup, bool) or not isinstance(prune_startup, int) or prune_startup < 1:
        raise ValueError(f"prune_startup={prune_startup!r}: a whole number of trials, at least 1")
    if pruner not in PRUNERS:
        raise ValueError(f"pruner {pruner!r}: {' or '.join(PRUNERS)}")
    if not 0 <= prune_warmup < 1:
        raise ValueError(f"prune_warmup={prune_warmup!r}: a share of the first run's steps, in [0, 1)")
    return {"experiment": experiment, "system": system, "reps": reps, "steps": steps, "set": dict(set or {}),
            "params": {k: p.spec() for k, p in parsed.items()}, "seed": seed, "prune": bool(prune),
            "pruner": pruner, "prune_startup": prune_startup, "prune_warmup": float(prune_warmup),
            "objective": objective if isinstance(objective, str) else
            f"{getattr(objective, '__module__', '?')}.{getattr(objective, '__qualname__', '?')}",
            "direction": direction, "extrinsic_tests": extrinsic_reps, "scenarios": list(scenarios),
            "keep_logs": keep_logs, "trials": trials, "afford_version": _afford.version}


def _check_keys(d: dict[str, Any]) -> list[tuple[str, str, int]]:
    """Every searched key at its ends (each choice), checked as afford.run checks: a bad key fails now."""
    def plan(values: dict[str, Any]):
        return check(d["experiment"], system=d["system"], reps=d["reps"], steps=d["steps"], set={**d["set"], **values},
                     seed=d["seed"], extrinsic_reps=d["extrinsic_tests"], scenarios=d["scenarios"])
    for key, spec in d["params"].items():
        p = parse_param(key, spec)
        for v in (p.choices if isinstance(p, Choice) else (p.low, p.high)):
            try:
                plan({key: v})
            except ValueError as e:
                raise type(e)(f"parameter '{key}' at {v!r}: {e}") from None
    return plan({})


def _open(folder: Path, d: dict[str, Any]):
    """The study in `folder`, made if new; a folder holding another study (or anything else) is refused."""
    import optuna
    optuna.logging.set_verbosity(optuna.logging.WARNING)
    folder.mkdir(parents=True, exist_ok=True)
    with locks.claim(folder):
        stored = folder / "study.json"
        if stored.is_file():
            old = _read_definition(stored)
            try:  # each range as this release writes it (one stored as Float(0.005, 1) was 'log:0.005:1')
                old["params"] = {k: parse_param(k, v).spec() for k, v in old.get("params", {}).items()}
            except (ValueError, AttributeError):
                pass
            differ = [k for k in KEPT if old.get(k) != d.get(k)]
            if differ:
                said = "; ".join(f"{k}: {old.get(k)!r} there, {d.get(k)!r} here" for k in differ)
                raise ValueError(f"{folder} holds another study ({said}): give another folder, or the same "
                                 f"definition to continue it")
            if d["trials"] != old.get("trials"):
                _write_whole(stored, json.dumps({**old, "trials": d["trials"]}, indent=2) + "\n")
        else:
            # (slurm/: scripts/slurm-submit.sh --tune's job scripts and output, written before any worker runs)
            if not {p.name for p in folder.iterdir()} <= {"study.lock", "slurm"}:
                raise ValueError(f"{folder} is not empty and holds no study: give a new folder for a study")
            _write_whole(stored, json.dumps(d, indent=2) + "\n")
        return optuna.create_study(study_name=STUDY_NAME, storage=_storage(folder), direction=d["direction"],
                                   load_if_exists=True)


def _retry_stopped(study, folder: Path, say) -> None:
    """Under the claim: a running trial whose worker is gone (its worker file free, locks.gone), or that no
    worker claimed (a worker asks for a trial and claims it under the claim, which this one holds now: its
    asker died before claiming it), fails as lost; each interrupted or lost trial not yet retried is queued
    again with its parameters (the retry says which it retries)."""
    from optuna.trial import TrialState
    for t in study.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        who = t.user_attrs.get("worker")
        if who is None or locks.gone(folder, who):
            study.tell(t.number, state=TrialState.FAIL, skip_if_finished=True)  # with no error said: lost
            why = "its worker died before claiming it" if who is None else \
                f"its worker ({who.get('host')}:{who.get('pid')}) is gone"
            say(f"trial {t.number}: {why}: it runs again")
    retried = {t.user_attrs.get("retry_of") for t in study.get_trials(deepcopy=False)}
    for t in study.get_trials(deepcopy=False, states=(TrialState.FAIL,)):
        if _stopped(t) in RETRIED and t.number not in retried:  # (a retry's own values are in fixed_params)
            study.enqueue_trial(t.system_attrs.get("fixed_params", t.params), user_attrs={"retry_of": t.number})


def _counts(study) -> tuple[int, int]:
    """(trials finished: done, pruned or failed saying why; trials running)."""
    from optuna.trial import TrialState
    finished = running = 0
    for t in study.get_trials(deepcopy=False):
        if t.state == TrialState.RUNNING:
            running += 1
        elif t.state in (TrialState.COMPLETE, TrialState.PRUNED) or (
                t.state == TrialState.FAIL and _stopped(t) not in RETRIED):
            finished += 1
    return finished, running


def tune(out: str | Path, experiment: str = "base", params: dict[str, Any] | None = None,
         objective: str | Callable[[Experiment], float] = "affordance_mae", direction: str | None = None,
         trials: int = 24, system: str = "IMP", reps: int | None = 1, steps: int | None = None,
         set: dict[str, Any] | None = None, seed: int = 1, extrinsic_reps: int | None = None, scenarios: Iterable[str] = (),
         prune: bool | None = None, pruner: str = "halving", prune_startup: int = 5, prune_warmup: float = 0.1,
         keep_logs: str = "all",
         log_level: str = "error", say: Callable[[str], None] | None = print) -> Study:
    """Run (or continue, or join) a study in the folder `out`; returns it once `trials` trials have finished.

    `params`: config key -> afford.Float(low, high, log=), afford.Int(...), afford.Choice([...]) or a spec
    string ("log:0.001:0.1"). `objective`: affordance_mae (default), curve_mae, success, "FILE.py:FUNCTION" or a
    function of the afford.load result; `direction` defaults to the named objective's. Every trial runs
    `experiment` for `system` with the same `seed` (its runs differ only in the parameters), `reps` runs of
    `steps` steps, `set` fixed, in this process (memq), into out/trials/NNNN; a table world's truth is estimated
    once per world into out/truth, which every trial and worker reads. `prune` (default: for the error
    objectives) stops a trial whose curve's error falls behind the other trials': `pruner` "halving" (successive
    halving, from `prune_warmup` of the first run's steps on) or "median" (Optuna's median pruner, once
    `prune_startup` trials have finished); see _pruner.

    Another process given the same folder and definition joins the study (the trials are shared, none runs
    twice); a folder holding a different study raises ValueError saying what differs. Ctrl-C stops the trial
    under way and raises KeyboardInterrupt; calling again continues. A bad key or value raises ConfigError
    before any trial runs.
    """
    say = say or (lambda _: None)
    folder = Path(out)
    with _stopping() as stop:
        d = _definition(experiment, system, reps, steps, set, params, objective, direction, seed, prune, pruner,
                        prune_startup, prune_warmup, extrinsic_reps, scenarios, keep_logs, trials)
        planned = _check_keys(d)
        value_of = _objective(objective)
        stop.check("before the study began (nothing was written)")
        study = _open(folder, d)
        offsets, total = [], 0  # each planned run's first step in the trial's count of intrinsic steps
        for _, _, n in planned:
            offsets.append(total)
            total += n
        study.pruner = _pruner(d, planned[0][2] if planned else 0)
        distributions = {k: _distribution(parse_param(k, v)) for k, v in d["params"].items()}
        (folder / "trials").mkdir(exist_ok=True)
        try:
            with locks.worker(folder) as me:  # (held while this call runs: its trials' worker is alive)
                _work(study, d, folder, me, offsets, total, distributions, value_of, log_level, say, stop)
        finally:  # the report, from the study as it is now: under the claim, so that a worker's report of an
            # older state never lands after a later one's (the last worker to end writes the whole study)
            with locks.claim(folder):
                result = load_study(folder)
                if len(result.trials):
                    write_report(result)
        finished, running = _counts(study)
        if running:
            say(f"{running} trial(s) still run in other workers; this worker is done")
        stop.check(f"as this worker ended (its trials had run; the report is written in {folder})")
    return result


def _work(study, d, folder: Path, me: dict[str, Any], offsets, total: int, distributions, value_of, log_level: str,
          say, stop: Stop) -> None:
    """This worker's (`me`, locks.worker) trials, one after another, until the study has its trials finished or
    under way. A trial is asked for and claimed (its worker named) under the claim; `stop` is checked before."""
    import optuna
    while True:
        kept = f"what finished is kept in {folder}"
        stop.check(f"before this worker's next trial ({kept})")
        with locks.claim(folder):
            stop.check(f"before this worker's next trial ({kept})")  # (one that came while it waited for the claim)
            _retry_stopped(study, folder, say)
            finished, running = _counts(study)
            if finished + running >= json.loads((folder / "study.json").read_text())["trials"]:
                break
            study.sampler = _sampler(d["seed"], len(study.get_trials(deepcopy=False)))
            trial = study.ask(distributions)
            trial.set_user_attr("worker", me)
            trial.set_user_attr("folder", f"trials/{trial.number:04d}")
            trial.set_user_attr("planned_steps", total)
            if stop.signal:  # (one that came while the trial was asked for: it runs again, when continued)
                trial.set_user_attr("stopped", "interrupted")
                study.tell(trial, state=optuna.trial.TrialState.FAIL)
                stop.check(f"before trial {trial.number} began ({kept}; its values run first when the study goes "
                           f"on)")
        _run_trial(study, trial, d, folder, offsets, total, value_of, log_level, say, stop)


def _run_trial(study, trial, d, folder: Path, offsets: list[int], total: int, value_of, log_level: str, say,
               stop: Stop) -> None:
    from optuna.trial import TrialState
    where = folder / trial.user_attrs["folder"]
    params = ", ".join(f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in trial.params.items())
    progress = {"steps": 0}

    def on_curve(p: CurvePoint) -> str | None:
        at = offsets[p.run] + p.step
        progress["steps"] = at
        if stop.signal:  # (one this study took as the trial began, before the experiment's handlers took over)
            return "interrupted"
        if not d["prune"] or p.step == 0:
            return None
        trial.report(p.mae, at)
        if at >= total:  # the last run's final table: the trial has run to its end, nothing left to save
            return None
        return "pruned" if trial.should_prune() else None

    began = time.monotonic()
    interrupted = False
    try:
        e = run(d["experiment"], system=d["system"], reps=d["reps"], steps=d["steps"], set={**d["set"], **trial.params},
                seed=d["seed"], extrinsic_reps=d["extrinsic_tests"], scenarios=d["scenarios"],
                keep_logs=d["keep_logs"], out=where, run_prefix=f"trial{trial.number:04d}", log_level=log_level,
                truth_dir=folder / "truth",
                progress="none", on_curve=on_curve)
    except ExperimentStopped as x:
        if x.reason == "pruned":
            trial.set_user_attr("intrinsic_steps", progress["steps"])
            trial.set_user_attr("pruned_at", progress["steps"])
            study.tell(trial, state=TrialState.PRUNED)
            say(f"trial {trial.number}: {params}: pruned at step {progress['steps']} "
                f"({time.monotonic() - began:.1f} s)")
            return
        interrupted = True  # (on_curve's "interrupted": this study's signal)
    except KeyboardInterrupt as x:  # (the experiment stopped on the signal: a further one quits at once)
        stop.signal = stop.signal or getattr(x, "signal", signal.SIGINT)
        interrupted = True
    except (ExperimentError, ValueError, OSError) as x:  # (afford.ConfigError is a ValueError)
        why = (x.errors[0] if isinstance(x, ExperimentError) and x.errors else str(x)).strip()
        trial.set_user_attr("intrinsic_steps", progress["steps"])
        trial.set_user_attr("error", why[:1000])
        study.tell(trial, state=TrialState.FAIL)
        say(f"trial {trial.number}: {params}: failed: {why}")
        return
    if interrupted:
        trial.set_user_attr("intrinsic_steps", progress["steps"])
        trial.set_user_attr("stopped", "interrupted")
        study.tell(trial, state=TrialState.FAIL)
        say(f"trial {trial.number}: {params}: interrupted at step {progress['steps']}")
        raise KeyboardInterrupt(f"during trial {trial.number} (what finished is kept in {folder}, and the trial's "
                                f"folder; its values run first when the study goes on)")
    trial.set_user_attr("intrinsic_steps", total)
    try:
        value = float(value_of(e))
    except Exception as x:  # the researcher's objective: whatever it raises fails this trial, saying why
        trial.set_user_attr("error", f"objective: {type(x).__name__}: {x}"[:500])
        study.tell(trial, state=TrialState.FAIL)
        say(f"trial {trial.number}: {params}: the objective failed: {type(x).__name__}: {x}")
        return
    if not math.isfinite(value):
        trial.set_user_attr("error", f"objective: {value} is not a finite number")
        study.tell(trial, state=TrialState.FAIL)
        say(f"trial {trial.number}: {params}: the objective gave {value}, not a finite number")
        return
    study.tell(trial, value)
    say(f"trial {trial.number}: {params}: {d['objective']} {value:.4g} ({time.monotonic() - began:.1f} s)")

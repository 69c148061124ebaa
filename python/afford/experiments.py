"""Experiments from Python: afford.run(experiment, ...) runs `afford experiment` in this process."""
from __future__ import annotations

import json
import signal
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable, Iterable, NamedTuple

from . import _afford
from .components import ROLES
from .results import Experiment, load


def _setting(key: str, value: Any) -> str:
    if isinstance(value, bool):
        value = "true" if value else "false"
    elif isinstance(value, (list, tuple)):
        value = "[" + ",".join(str(v) for v in value) + "]"
    return f"{key}={value}"


class ExperimentError(RuntimeError):
    """An experiment that ran but failed (a run or a test failed, an agent could not be tested).

    The message says why (the errors the runner said, the last of them);
    `errors` holds them, `out` the experiment's folder (its summary.json
    lists each failed run and test with its reason), `exit_code` the exit
    status `afford experiment` would have had.
    """

    def __init__(self, message: str, errors: list[str], out: Path, exit_code: int):
        super().__init__(message)
        self.errors, self.out, self.exit_code = errors, out, exit_code


class ExperimentStopped(RuntimeError):
    """An experiment that `on_curve` stopped (afford.run(on_curve=...) returned a reason).

    It stopped as Ctrl-C stops one: the runs under way were cut, what
    finished is written in `out`, and `afford experiment --resume --out OUT`
    would complete it. `reason` is what on_curve returned.
    """

    def __init__(self, message: str, reason: str, out: Path):
        super().__init__(message)
        self.reason, self.out = reason, out


class CurvePoint(NamedTuple):
    """Where an intrinsic run's learning curve stands, as afford.run tells `on_curve` while the run goes.

    `run`: the run's index in the experiment's plan (0, 1, ... in the order
    they are planned); `step`: the curve's step; `mae`: the mean absolute
    error of the run's affordance table at that step from the world's.
    """
    run_id: str
    system: str
    run: int
    step: int
    mae: float


def _to_stderr(line: str) -> None:
    """afford.run's default `say`: Python's sys.stderr, which a notebook shows (the process's own it does not)."""
    print(line, file=sys.stderr, flush=True)


def _count(name: str, value: Any) -> None:
    if value is not None and (isinstance(value, bool) or not isinstance(value, int) or value < 1):
        raise ValueError(f"afford.run({name}={value!r}): {name} is a whole number, at least 1 (or None: the "
                         f"experiment's own)")


def _request(experiment: str, system: Any, reps: int | None, steps: int | None, set: dict[str, Any] | None,
             transport: str, out: str | Path | None, log_root: str | Path | None, seed: int, jobs: int,
             extrinsic_reps: int | None, scenarios: Iterable[str], keep_logs: str, run_prefix: str, reuse_agents: bool,
             progress: str, log_level: str, motivation: Any, affordance: Any, goals: Any,
             processes: dict[str, str] | None, tables: int | None, table_seed: int | None,
             replace: bool, truth_dir: str | Path | None = None) -> tuple[dict[str, Any], Path]:
    """afford.run's request to the C++ runner, checked as far as Python checks it, and its folder."""
    _count("reps", reps)
    _count("steps", steps)
    if experiment.endswith((".yaml", ".yml")) or "/" in experiment:
        experiment = str(Path(experiment).resolve())
    settings = dict(set or {})
    for argument, cls, role in (("motivation", motivation, "motivation"), ("affordance", affordance, "predictors"),
                                ("goals", goals, "goals")):
        if cls is None:
            continue
        key, register = ROLES[role]
        if transport != "memq":
            raise ValueError(f"afford.run({argument}=...) runs the class in this process: transport='memq'; over "
                             f"udpm, give processes={{'{'motivation' if role == 'goals' else role}': "
                             f"'{sys.executable} -m afford.process {role} MODULE:CLASS'}} "
                             f"and set={{'{key}': KIND}}")
        settings.setdefault(key, register(cls))
    out = Path(out) if out else Path(tempfile.mkdtemp(prefix=f"afford-{experiment}-"))
    systems = [system] if isinstance(system, str) else list(system or [])
    request = {
        "experiment": experiment, "systems": systems, "reps": reps, "steps": steps, "seed": seed, "jobs": jobs,
        "out": str(out), "log_root": str(log_root or out / "logs"), "transport": transport,
        "keep_logs": keep_logs, "settings": [_setting(k, v) for k, v in settings.items()],
        "processes": dict(processes or {}),
        "extrinsic_reps": extrinsic_reps, "scenarios": list(scenarios), "run_prefix": run_prefix,
        "progress": progress, "reuse_agents": reuse_agents, "log_level": log_level,
        "tables": tables, "table_seed": table_seed, "replace": bool(replace),
        "truth_dir": None if truth_dir is None else str(truth_dir),
    }
    return request, out


def run(experiment: str, system: str | Iterable[str] | None = None, reps: int | None = None,
        steps: int | None = None, set: dict[str, Any] | None = None, transport: str = "memq",
        out: str | Path | None = None, log_root: str | Path | None = None, seed: int = 1, jobs: int = 1,
        extrinsic_reps: int | None = None, scenarios: Iterable[str] = (), keep_logs: str = "all",
        run_prefix: str = "", reuse_agents: bool = True, progress: str = "lines",
        log_level: str = "info", motivation: Any = None, affordance: Any = None, goals: Any = None,
        processes: dict[str, str] | None = None,
        tables: int | None = None, table_seed: int | None = None, replace: bool = False,
        truth_dir: str | Path | None = None,
        on_curve: Callable[[CurvePoint], str | None] | None = None,
        say: Callable[[str], None] | None = _to_stderr) -> Experiment:
    """Run an experiment as `afford experiment` does and return what afford.load returns.

    `experiment`: a name of config/experiments/ (base, late1, ...) or an
    experiment file (a path ending in .yaml, as --config takes); `system`:
    FIX, IGN, IMP, GOALS, a list of them or "all" (the paper's three); `set`: config keys and values
    (`{"motivation.leak": 0.3}`; a list value is a YAML list, not a sweep).
    `out` defaults to a new temporary folder, `log_root` to `out`/logs.
    Over memq (the default) everything runs in this process; udpm starts the
    processes. Ctrl-C (a notebook's interrupt) stops it as it stops the
    command: the runs under way stop, what finished is written, and
    KeyboardInterrupt is raised naming the folder and the command that
    resumes it (`.../afford experiment --resume --out OUT`, each word quoted
    for a shell). A bad option or config key raises
    afford.ConfigError (a ValueError) naming it.

    `motivation`: a class written in Python (afford.Motivation) in the place
    of the shipped motivation, in this process (memq): it is registered under
    its kind and motivation.kind is set to it. `processes`: commands in the
    place of shipped processes, as `afford experiment --process NAME=CMD`
    (udpm), e.g. {"motivation": f"{sys.executable} -m afford.process motivation mine.py:Mine"}: the
    interpreter running this one, whose `import afford` works (a bare `python3` may be another).
    `goals`: a class written in Python (afford.GoalChooser) in the place of
    the shipped goal chooser of GOALS agents (goals.kind), in this process.
    `affordance`: a class written in Python (afford.AffordancePredictor) in
    the place of the paper's affordance and learning-progress predictors, in
    this process (memq); predictors.affordance.kind is set to its kind.
    `tables`, `table_seed`: random tables (--tables, --table-seed).
    `truth_dir`: where a table world's truth is read, or estimated first
    (--truth-dir; default `log_root`/truth).
    `replace`: `out` holds a finished experiment: remove its files and
    write this one in their place (without it, such a folder raises
    ConfigError; an experiment never mixes with another's files).
    `on_curve`: called with a CurvePoint at each point of each intrinsic
    run's learning curve (every run.curve_interval steps) as the run goes,
    from the thread that drives the run. A non-empty string it returns stops
    the experiment as Ctrl-C does, for that reason (afford.ExperimentStopped
    is raised; afford.tune prunes this way); an exception it raises stops it
    too and is raised once the runs have stopped.

    What it says, as `afford experiment` says it: what it will run and into
    which folder, each run and test as it finishes ([k/N]), and at
    `progress="lines"` (the default) where the runs under way stand, every
    30 s; `log_level` "info" (the default), "warn", "error" or "off" says
    less, `progress="none"` leaves the progress lines out. Each line is given
    to `say` (default: printed on Python's sys.stderr, which a notebook
    shows); None leaves them to the process's own stderr.

    Run ids start with the date and time, made unique in `log_root`: calls
    in a loop, or from several processes, never collide. A run or test
    that fails raises afford.ExperimentError (a RuntimeError) saying why.
    """
    request, out = _request(experiment, system, reps, steps, set, transport, out, log_root, seed, jobs,
                            extrinsic_reps, scenarios, keep_logs, run_prefix, reuse_agents, progress, log_level,
                            motivation, affordance, goals, processes, tables, table_seed, replace, truth_dir)
    if on_curve is not None:
        if not callable(on_curve):
            raise TypeError(f"afford.run(on_curve={on_curve!r}): a function of a CurvePoint")
        request["on_curve"] = lambda *point: on_curve(CurvePoint(*point))
    if say is not None:
        if not callable(say):
            raise TypeError(f"afford.run(say={say!r}): a function of a line (str), or None")
        request["say"] = say
    code, sig, errors, stopped_for = _afford.run_experiment(request)
    if sig and code != 128 + sig:
        # A signal that came too late to stop anything (the experiment ended as it would have without it): the
        # handler in place takes it now (afford.tune's stops the study after this trial; Python's raises
        # KeyboardInterrupt), and the experiment counts as what it is.
        signal.raise_signal(sig)
        sig = 0
    if stopped_for and not sig:
        raise ExperimentStopped(f"afford.run({experiment!r}) was stopped by on_curve ({stopped_for}): what "
                                f"finished is in {out}; {_resume(out)}", stopped_for, out)
    if sig:
        interrupted = KeyboardInterrupt(f"afford.run({experiment!r}) was interrupted: what finished is in {out}; "
                                        f"{_resume(out)}")
        interrupted.signal = sig  # (SIGINT or SIGTERM)
        raise interrupted
    if code != 0:
        said = "\n  ".join(errors[-5:]) if errors else "no error was said; see the messages above"
        more = f" (the last 5 of {len(errors)})" if len(errors) > 5 else ""
        raise ExperimentError(f"afford.run({experiment!r}) failed (exit {code}) in {out}{more}:\n  {said}",
                              list(errors), out, code)
    return load(out)


def _resume(out: Path) -> str:
    """What resumes the experiment stopped in `out`, as its summary says (a command for a shell, and where)."""
    try:
        said = json.loads((out / "summary.json").read_text())["interrupted"]
        return f"to resume it (in {said['resume_in']}): {said['resume']}"
    except (OSError, ValueError, KeyError, TypeError):
        return "its summary.json says how to resume it"


def check(experiment: str, system: str | Iterable[str] | None = None, reps: int | None = None,
          steps: int | None = None, set: dict[str, Any] | None = None, seed: int = 1, extrinsic_reps: int | None = None,
          scenarios: Iterable[str] = (), tables: int | None = None,
          table_seed: int | None = None) -> list[tuple[str, str, int]]:
    """Check an experiment as afford.run would before it runs, and run nothing.

    Raises afford.ConfigError naming a bad option, config key or value;
    returns the intrinsic runs it would run as (run id, system, steps), in
    the plan's order. Nothing is written.
    """
    with tempfile.TemporaryDirectory(prefix="afford-check-") as scratch:
        request, _ = _request(experiment, system, reps, steps, set, "memq", Path(scratch) / "out", None, seed, 1,
                              extrinsic_reps, scenarios, "all", "check", True, "none", "error", None, None, None,
                              None, tables, table_seed, False)
        return [tuple(r) for r in _afford.check_experiment(request)]


def replay(log: str | Path, affordance: Any = None, motivation: Any = None, goals: Any = None,
           into: Iterable[str] = (), run: str = "", bus_key: str | Path | None = None,
           log_level: str = "warning") -> dict[str, Any]:
    """Replay a recorded run into fresh learning processes in this process, as `afford replay LOG` does.

    `affordance`, `motivation`, `goals`: the classes written in Python the run used (registered here
    first), so that a run with a Python affordance predictor, which `afford replay` cannot rebuild, replays
    too. `into`: predictors, motivation, planner (default: the predictors and the run's decider). Returns
    {"weights_checksum": the replayed predictors', "recorded_checksum": the run's, "ok": everything the
    record holds was replayed and equals it, "consistent", "decisions", "decisions_differing",
    "decider_skipped", "events", "gaps", "dropped", "incomplete", "cut": what the log lacks of the run when
    it is cut short (then never ok), "run_id"}. A log it cannot read raises RuntimeError naming the file.
    """
    from .components import register_affordance, register_goals, register_motivation
    for cls, register in ((affordance, register_affordance), (motivation, register_motivation),
                          (goals, register_goals)):
        if cls is not None:
            register(cls)
    return _afford.replay(str(log), list(into), run, str(bus_key) if bus_key else "", log_level)

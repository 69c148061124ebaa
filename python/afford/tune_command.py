"""`afford tune` (python3 -m afford tune): a study from the command line (python/afford/study.py).

SIGINT and SIGTERM: `afford tune` holds them back from its start until the study's handler is in place (the
first thing here), so that none is lost and none interrupts an import; the first stops the study where nothing
is lost, and one line says so with the command that continues it; a second quits at once. Once the command has
said how it ended, they are held back again until the process is gone.
"""
from __future__ import annotations

import argparse
import os
import shlex
import signal
import sys
from pathlib import Path

from . import _afford, locks
from .search import _scalar
from .study import PRUNERS, STOP_SIGNALS, _read_definition, load_study, stop_on_signals, tune, write_report

PROGRAM = "AFFORD_TUNE_PROGRAM"  # the front door's name as it was run (apps/afford/commands/tune.cpp)


def _parser() -> argparse.ArgumentParser:
    systems = ", ".join(_afford.systems)
    ap = argparse.ArgumentParser(
        prog="afford tune",
        description="A study over config keys with Optuna (TPE, pruning on the learning curves, a journal "
                    "file every worker shares): each trial an experiment folder OUT/trials/NNNN. Run the same "
                    "command again to continue it, or in several processes (or Slurm array tasks) to share it. "
                    "Ctrl-C (SIGINT, or SIGTERM) stops it with what finished kept, and says the command that "
                    "continues it.")
    ap.add_argument("experiment", nargs="?", help="a name of config/experiments/ or an experiment file (default: "
                    "the study's, when --out holds one; else base)")
    ap.add_argument("--out", required=True, help="the study's folder")
    ap.add_argument("--param", action="append", default=[], metavar="KEY=SPEC",
                    help="a config key searched: float:LOW:HIGH, log:LOW:HIGH, int:LOW:HIGH, intlog:LOW:HIGH, "
                         "choice:A,B,...")
    ap.add_argument("--objective", help="affordance_mae (default), curve_mae, success, table2, or FILE.py:FUNCTION (a "
                    "function of the afford.load result)")
    ap.add_argument("--direction", choices=["minimize", "maximize"], help="default: the named objective's")
    ap.add_argument("--trials", type=int, help="trials in all, over every worker (default 24)")
    ap.add_argument("--system", help=f"the system each trial trains: {systems} (default IMP)")
    ap.add_argument("--reps", type=int, help="runs per trial (default 1)")
    ap.add_argument("--steps", type=int, help="intrinsic steps per run (default: the experiment's)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="a config key fixed in every trial")
    ap.add_argument("--seed", type=int, help="the runs' seed, the same in every trial; and the sampler's (default 1)")
    ap.add_argument("--extrinsic-reps", type=int, help="extrinsic tests per scenario (for objective success); 0: none "
                    "(default: the experiment's)")
    ap.add_argument("--scenarios", action="append", help="extrinsic scenarios (for objective success)")
    ap.add_argument("--prune", action=argparse.BooleanOptionalAction, default=None,
                    help="stop a trial whose learning curve falls behind the other trials', by --pruner (default: on "
                         "for the error objectives)")
    ap.add_argument("--pruner", choices=PRUNERS, help="halving (the default: successive halving, a third goes on at "
                    "each rung) or median (the median pruner)")
    ap.add_argument("--prune-startup", type=int, help="median: trials finished before any is pruned (default 5)")
    ap.add_argument("--prune-warmup", type=float, help="the share of its first run a trial runs before it may be "
                    "pruned (default 0.1)")
    ap.add_argument("--keep-logs", help="the trials' run logs: all (default: each trial replays), first, none")
    ap.add_argument("--report", action="store_true", help="write the report of the study in --out and run nothing")
    return ap


def command(argv: list[str]) -> str:
    """The command that runs `afford tune` with `argv` again, for a shell: each word quoted as it needs."""
    program = os.environ.get(PROGRAM)
    return shlex.join(([program] if program else [sys.executable, "-m", "afford"]) + ["tune", *argv])


def main(argv: list[str] | None = None) -> int:
    """The command, in a process that ends with it: SIGINT and SIGTERM are held back once it has said how it
    ended (one that comes then finds nothing left to stop, and the exit status says what was done)."""
    argv = sys.argv[1:] if argv is None else list(argv)
    stop = stop_on_signals()
    try:
        code = _main(_parser().parse_args(argv))
        stop.check("as the study ended (its trials had run; the report is written)")
        signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
        return code
    except KeyboardInterrupt as e:
        signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)  # (the line below is said whole)
        print(f"afford tune: interrupted by {stop.name or 'SIGINT'} {e or 'as it began'}; the same command continues "
              f"the study (in {os.getcwd()}): {command(argv)}", file=sys.stderr, flush=True)
        return 130


def _main(a: argparse.Namespace) -> int:
    out = Path(a.out)
    stored = _read_definition(out / "study.json") if (out / "study.json").is_file() else {}
    if a.report:
        if not stored:
            print(f"afford tune: {out} holds no study.json: no study to report", file=sys.stderr)
            return 2
        with locks.claim(out):
            print(write_report(load_study(out)))
        return 0

    def given(value, key, default):
        return value if value is not None else stored.get(key, default)
    try:
        for p in a.param:
            if "=" not in p:
                raise ValueError(f"--param {p}: KEY=SPEC, e.g. motivation.leak=log:0.01:0.9")
        params = dict(p.split("=", 1) for p in a.param) if a.param else stored.get("params")
        fixed = {}
        for s in a.set:
            key, sep, value = s.partition("=")
            if not sep:
                raise ValueError(f"--set {s}: KEY=VALUE")
            fixed[key] = _scalar(value)
        s = tune(out, experiment=given(a.experiment, "experiment", "base"), params=params,
                 objective=given(a.objective, "objective", "affordance_mae"), direction=given(a.direction, "direction", None),
                 trials=given(a.trials, "trials", 24), system=given(a.system, "system", "IMP"),
                 reps=given(a.reps, "reps", 1), steps=given(a.steps, "steps", None),
                 set=fixed if a.set else stored.get("set", {}), seed=given(a.seed, "seed", 1),
                 extrinsic_reps=given(a.extrinsic_reps, "extrinsic_tests", None),
                 scenarios=given(a.scenarios, "scenarios", []), prune=given(a.prune, "prune", None),
                 pruner=given(a.pruner, "pruner", "halving"),
                 prune_startup=given(a.prune_startup, "prune_startup", 5),
                 prune_warmup=given(a.prune_warmup, "prune_warmup", 0.1),
                 keep_logs=given(a.keep_logs, "keep_logs", "all"),
                 say=lambda line: print(line, flush=True))
    except (ValueError, FileNotFoundError) as e:
        print(f"afford tune: {e}", file=sys.stderr)
        return 2
    best = s.best
    if best is not None:
        print(f"best: trial {best['number']}, {s.definition['objective']} {best['value']:.4g}, in {s.best_folder}")
    print(out / "report.md")
    return 0

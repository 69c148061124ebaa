"""bench/run.sh tune: afford tune's floors, measured (docs/performance.md#studies).

Two studies of the same definition, each by W workers (processes running the same `afford tune` command) sharing
one journal file: one with pruning, one without. For each: trials finished (the floor: all of them), none run
twice (`ran_twice`: what the trial folders hold), the intrinsic steps run in all; then the saving pruning brings
(floor: 30% fewer steps), and the best trial's log replayed to its checksum. Exit 1 below a floor.

    bench/run.sh tune [--trials 24] [--workers 2] [--steps 6000] [--experiment base] [--system IMP]
                      [--param KEY=SPEC ...] [--seed 1] [--out DIR]
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd

import afford

AFFORD = Path(__file__).resolve().parents[1] / "build" / "bin" / "afford"
PARAMS = ["motivation.leak=log:0.01:0.9", "predictors.affordance.learning_rate=log:0.01:1"]


def ran_twice(folder: Path, trials) -> list[str]:
    """The work of a trial done twice, said one line each, from what the study's trial folders hold: each an
    experiment folder whose experiment.json plans its runs (run ids trialNNNN-...), runs/RUN.json for each run
    that finished and logs/RUN/run.json naming the folder that claimed the run. Twice: a folder two trials name; a
    trial's folder holding an experiment planned with another trial's run ids, a finished run it did not plan, or
    a run folder another experiment claimed; a retry (retry_of) of a trial whose folder holds its experiment
    finished (its values ran to the end twice). `trials`: afford.load_study(folder).trials."""
    said = [f"{f}: the folder of {n} trials" for f, n in trials["folder"].value_counts().items() if n > 1]
    finished = set()
    for number, f in zip(trials["number"], trials["folder"]):
        where, own = folder / f, f"trial{number:04d}-"
        if not (where / "experiment.json").is_file():
            continue  # (a trial asked for and not begun)
        state = json.loads((where / "experiment.json").read_text())
        planned = {r["run_id"] for r in state["runs"]}
        said += [f"trial {number}: {f} plans run {r}, not its own" for r in sorted(planned) if not r.startswith(own)]
        said += [f"trial {number}: {f} holds the finished run {p.stem}, which it did not plan"
                 for p in sorted((where / "runs").glob("*.json")) if p.stem not in planned]
        for claim in sorted((where / "logs").glob("*/run.json")):
            if Path(json.loads(claim.read_text())["out_dir"]).resolve() != where.resolve():
                said.append(f"trial {number}: {claim.parent} was claimed by another experiment")
        if state["state"] == "finished":
            finished.add(number)
    for number, of in zip(trials["number"], trials["retry_of"]):
        if pd.notna(of) and int(of) in finished:
            said.append(f"trial {number} ran the values of trial {int(of)} again, which had run to its end")
    return said


def study(folder: Path, a, prune: bool) -> dict:
    command = [str(AFFORD), "tune", a.experiment, "--out", str(folder), "--trials", str(a.trials), "--system",
               a.system, "--steps", str(a.steps), "--seed", str(a.seed), "--prune" if prune else "--no-prune"]
    for p in a.param or PARAMS:
        command += ["--param", p]
    began = time.monotonic()
    workers = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
               for _ in range(a.workers)]
    said = [w.communicate()[0] for w in workers]
    wall = time.monotonic() - began
    for w, text in zip(workers, said):
        if w.returncode != 0:
            sys.exit(f"a worker of {folder} failed (exit {w.returncode}):\n{text}")
    s = afford.load_study(folder)
    df = s.trials
    # Finished: done, pruned, or failed saying why (a diverged predictor); not running, not stopped short.
    finished = df[df["state"].isin(["COMPLETE", "PRUNED"]) | ((df["state"] == "FAIL") & df["error"].notna())]
    by_worker = df["worker"].value_counts().to_dict()
    twice = ran_twice(folder, df)
    best = s.best
    replayed = {}
    if best is not None:
        e = afford.load(s.best_folder)
        log = e.runs["log_dir"].iloc[0]
        replayed = afford.replay(log, log_level="error")
        replayed["recorded"] = e.runs["weights_checksum"].iloc[0]
    return {"prune": prune, "wall_seconds": round(wall, 1), "trials": len(df), "finished": len(finished),
            "pruned": int((df["state"] == "PRUNED").sum()), "failed": int((df["state"] == "FAIL").sum()),
            "run_twice": len(twice), "run_twice_said": twice, "by_worker": by_worker,
            "intrinsic_steps": int(df["intrinsic_steps"].fillna(0).sum()),
            "best": None if best is None else {"trial": int(best["number"]), "value": float(best["value"]),
                                               "params": {k[len("param "):]: best[k] for k in df.columns
                                                          if k.startswith("param ")}},
            "replay": {k: replayed.get(k) for k in ("weights_checksum", "recorded", "ok")}}


def main() -> int:
    ap = argparse.ArgumentParser(prog="bench/run.sh tune")
    ap.add_argument("--trials", type=int, default=24)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--steps", type=int, default=6000)
    ap.add_argument("--experiment", default="base")
    ap.add_argument("--system", default="IMP")
    ap.add_argument("--param", action="append")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=f"out/bench-tune-{time.strftime('%Y%m%d-%H%M%S')}")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    results = [study(out / "pruned", a, True), study(out / "unpruned", a, False)]
    with_p, without = results
    saving = 1 - with_p["intrinsic_steps"] / without["intrinsic_steps"]
    floors = {
        "every trial finished, by both studies": all(r["finished"] == a.trials and r["trials"] == a.trials
                                                     for r in results),
        "none run twice": all(r["run_twice"] == 0 for r in results),
        "pruning runs at least 30% fewer intrinsic steps": saving >= 0.30,
        "the best trial's log replays to its checksum": all(
            r["replay"]["ok"] and r["replay"]["weights_checksum"] == r["replay"]["recorded"] for r in results),
    }
    report = {"trials": a.trials, "workers": a.workers, "steps": a.steps, "experiment": a.experiment,
              "system": a.system, "params": a.param or PARAMS, "studies": results, "saving": round(saving, 3),
              "floors": floors}
    (out / "tune_bench.json").write_text(json.dumps(report, indent=2, default=str) + "\n")
    for r in results:
        print(f"{'pruned' if r['prune'] else 'unpruned'}: {r['finished']}/{r['trials']} finished "
              f"({r['pruned']} pruned, {r['failed']} failed) by {r['by_worker']}, run twice {r['run_twice']}, "
              f"{r['intrinsic_steps']} intrinsic steps, {r['wall_seconds']} s; best {r['best']}; replay {r['replay']}")
    print(f"pruning ran {100 * saving:.1f}% fewer intrinsic steps")
    for name, ok in floors.items():
        print(f"{'PASS' if ok else 'FAIL'}: {name}")
    print(out / "tune_bench.json")
    return 0 if all(floors.values()) else 1


if __name__ == "__main__":
    sys.exit(main())

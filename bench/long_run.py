#!/usr/bin/env python3
"""Runs of any length (docs/performance.md, "Runs of any length").

bench/run.sh long [--lengths 10000,100000,1000000] [--seed S] [--kill PROCESS] [--kill-at STEP] [--no-replay]
                  [--speed-reps R] [--system IMP|GOALS] [--out DIR]

For each length: one IMP run (or, with --system GOALS, one of the goals
agent: its motivation keeps the chooser's memory, its planner pursues goals)
of the base experiment over udpm with its log
kept (`afford experiment`, its processes in a private network namespace):
steps per second, every process's peak memory (the runner and the logger
too), the log's size beside what `afford experiment` said it would take, and
the log replayed (`afford replay`) to the run's weights. Then, with --kill,
the longest run again on hand-started processes (tests/restart's way) for
each process named, killed with SIGKILL once the run is past --kill-at
(default: half the run) and started again with the same command: how long it
takes to catch up, and the weights beside the uninterrupted run's.

The planner's peak is over the extrinsic test that follows each run, the
runner's over the run and that test (by then it has kept and summarised the
run's curve). Floors (exit 1 below one): at the longest length every process's peak within
64 MB of its peak at the shortest; steps per second at least 0.9 of the
shortest's; the replayed weights equal; the killed run's weights equal and
its catch-up within 30 s.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
AFFORD = ROOT / "build" / "bin" / "afford"
FLOOR_MB = 64
FLOOR_SPEED = 0.9
FLOOR_CATCH_UP = 30.0


def run_length(steps, seed, out, replay, keep_logs, system, rep=0):
    name = f"{steps}" + (f"-rep{rep}" if rep else "")
    folder, logs = out / f"run-{name}", out / f"logs-{name}"
    cmd = [str(AFFORD), "experiment", "base", "--system", system, "--reps", "1", "--steps", str(steps),
           "--seed", str(seed), "--extrinsic-reps", "1", "--scenarios", "scenario1", "--keep-logs", keep_logs,
           "--transport", "udpm", "--run-prefix", "long", "--out", str(folder), "--log-root", str(logs)]
    began = time.monotonic()
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{done.stderr[-3000:]}")
    disk = next((line.split("disk: ", 1)[1] for line in done.stderr.splitlines() if "disk: " in line), "")
    summary = json.loads((folder / "summary.json").read_text())
    run = summary["systems"][system]["runs"][0]
    # The extrinsic test after the run: the planner's peak, and the runner's over the whole experiment so far
    # (it has kept the run's outcome and summarised it by then: its curve grows with the run).
    for kept in sorted((folder / "runs").glob("*-e0.json")):
        test = json.loads(kept.read_text())["outcome"].get("peak_rss_kb") or {}
        for p in ("planner", "runner"):
            if p in test:
                run["peak_rss_kb"][p] = max(run["peak_rss_kb"].get(p, 0), test[p])
    result = {
        "steps": steps,
        "wall_seconds": time.monotonic() - began,
        "steps_per_second": run["steps_per_second"],
        "peak_rss_mb": {p: kb / 1024 for p, kb in run["peak_rss_kb"].items()},
        "log_bytes": run["log_bytes"],
        "said": disk,
        "weights_checksum": run["weights_checksum"],
        "log_dir": run["log_dir"],
    }
    if replay and run["log_dir"]:
        began = time.monotonic()
        said = out / f"replay-{name}.txt"
        with open(said, "w") as sink:
            child = subprocess.Popen([str(AFFORD), "replay", run["log_dir"]], stdout=sink, stderr=subprocess.STDOUT)
            _, status, usage = os.wait4(child.pid, 0)  # its own peak memory, not the runs' processes'
        text = said.read_text()
        m = re.search(r"weights_checksum: ([0-9a-f]{16})", text)
        result["replay_seconds"] = time.monotonic() - began
        result["replay_peak_mb"] = usage.ru_maxrss / 1024
        result["replay_checksum"] = m.group(1) if m else f"none (status {status}): {text[-500:]}"
    # The log of a long run is gigabytes: measured, it goes.
    subprocess.run(["rm", "-rf", str(logs)], check=False)
    return result


def run_kill(steps, seed, victim, at, out, system):
    work = out / f"kill-{victim}"
    done = subprocess.run(["bash", str(ROOT / "bench" / "long_kill.sh"), str(ROOT / "build"), str(work), victim,
                           str(seed), str(steps), str(at), system], capture_output=True, text=True)
    sys.stderr.write(done.stderr[-4000:])
    line = next((l for l in done.stdout.splitlines() if l.startswith("{")), None)
    if done.returncode != 0 or line is None:
        sys.exit(f"the run with {victim} killed failed:\n{done.stdout[-3000:]}")
    subprocess.run(["rm", "-rf", str(work / "logs")], check=False)
    return json.loads(line)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lengths", default="10000,100000,1000000")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--kill", default="", help="processes to kill, one run each, in the longest run (e.g. predictors,logger)")
    ap.add_argument("--kill-at", type=int, default=0, help="the step after which it is killed (default: half)")
    ap.add_argument("--no-replay", action="store_true")
    ap.add_argument("--keep-logs", default="all", choices=["all", "none"],
                    help="none: no log (and no replay), as the processes' memory and speed alone are measured")
    ap.add_argument("--speed-reps", type=int, default=3,
                    help="runs of the shortest length, their median steps/s the speed floor's base (one before the "
                         "longer runs, the rest after them): runs of one length vary by 10 to 20%% here")
    ap.add_argument("--system", default="IMP", choices=["IMP", "GOALS"],
                    help="GOALS: the goals agent of the goals phase (slower: bench its lengths apart from IMP's)")
    ap.add_argument("--out", default="bench-out/long")
    a = ap.parse_args()
    out = Path(a.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    lengths = [int(x) for x in a.lengths.split(",")]
    results = [run_length(n, a.seed, out, not a.no_replay, a.keep_logs, a.system) for n in lengths]
    # The shortest again after the longest (the speed floor's base: their median).
    base_runs = [results[0]] + [run_length(lengths[0], a.seed, out, False, a.keep_logs, a.system, rep)
                                for rep in range(1, max(1, a.speed_reps))]
    base_speed = statistics.median(r["steps_per_second"] for r in base_runs)
    for r in results:
        print(f"{r['steps']} steps: {r['steps_per_second']:.0f} steps/s, " +
              ", ".join(f"{p} {mb:.0f} MB" for p, mb in sorted(r["peak_rss_mb"].items())) +
              f"; log {r['log_bytes'] / 1e6:.0f} MB (said: {r['said']})" +
              (f"; replay {r['replay_seconds']:.0f} s, {r['replay_peak_mb']:.0f} MB, {'same weights' if r['replay_checksum'] == r['weights_checksum'] else 'OTHER WEIGHTS ' + r['replay_checksum']}"
               if "replay_checksum" in r else ""), flush=True)
    first, last = results[0], results[-1]
    verdicts = []
    for p, mb in sorted(last["peak_rss_mb"].items()):
        base = first["peak_rss_mb"].get(p)
        if base is not None:
            verdicts.append((f"{p}: peak {mb:.0f} MB at {last['steps']} steps, {base:.0f} MB at {first['steps']}",
                             mb - base <= FLOOR_MB))
    ratio = last["steps_per_second"] / base_speed
    print(f"{first['steps']} steps, {len(base_runs)} runs: " +
          ", ".join(f"{r['steps_per_second']:.0f}" for r in base_runs) +
          f" steps/s (median {base_speed:.0f})", flush=True)
    verdicts.append((f"steps/s at {last['steps']} / the median at {first['steps']}: {ratio:.3f}",
                     ratio >= FLOOR_SPEED))
    for r in results:
        if "replay_checksum" in r:
            verdicts.append((f"replay of the {r['steps']}-step log: {r['replay_checksum']}",
                             r["replay_checksum"] == r["weights_checksum"]))
    kills = []
    for victim in filter(None, a.kill.split(",")):
        kill = run_kill(last["steps"], a.seed, victim, a.kill_at or last["steps"] // 2, out, a.system)
        kill["process"] = victim
        kills.append(kill)
        print(f"{victim} killed at step {kill['killed_at']} of {last['steps']}: went on from its snapshot of step "
              f"{kill['restored_step']}, caught up in {kill['catch_up_seconds']:.1f} s; weights {kill['weights_checksum']}",
              flush=True)
        verdicts.append((f"{victim} killed: caught up in {kill['catch_up_seconds']:.1f} s",
                         kill["catch_up_seconds"] <= FLOOR_CATCH_UP))
        verdicts.append((f"{victim} killed: weights {kill['weights_checksum']}, uninterrupted {last['weights_checksum']}",
                         kill["weights_checksum"] == last["weights_checksum"]))
    for text, ok in verdicts:
        print(f"{'PASS' if ok else 'FAIL'}  {text}")
    (out / "long.json").write_text(json.dumps({"system": a.system, "lengths": results, "base_runs": base_runs, "base_steps_per_second": base_speed,
                                               "kills": kills,
                                               "verdicts": [{"what": t, "pass": ok} for t, ok in verdicts]}, indent=2))
    return 0 if all(ok for _, ok in verdicts) else 1


if __name__ == "__main__":
    sys.exit(main())

"""What a GOALS step costs beside an IMP step, and udpm beside memq on a full machine (issue 57):

    bench/run.sh goals-cost [--steps 6000] [--pairs 3] [--runs 8] [--jobs 2] [--rounds 3] [--parts goals,full]
                            [--transports udpm,memq] [--goals-floor 0.5] [--full-floor 0.61]
                            [--afford PROGRAM ...] [--out DIR]

goals: one run of each system (`afford experiment base --system IMP`, then GOALS, logs off, every run trains)
per pair and transport, --pairs times; steps per second of each (summary.json), the medians and the ratio
GOALS / IMP of the medians; floor --goals-floor over udpm.
full: --runs runs of IMP at --jobs over udpm, then over memq, --rounds times; the wall time of each, and the
ratio udpm / memq of the median walls' steps per second in all; floor --full-floor.

Several --afford programs (builds) are measured in turn within each pair and round, so that builds are
compared side by side on a shared machine. The machine's load (1-minute average) is printed with each
figure. Exit 1 when a floor is not met by the first --afford.
"""
import argparse
import json
import os
import pathlib
import resource
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def load():
    return os.getloadavg()[0]


def experiment(afford, out, prefix, system, steps, reps, jobs, transport):
    """One `afford experiment base`: its wall time, the CPU time of its processes (user and system, every
    process it started) and the runs of its summary.json."""
    folder = out / prefix
    cmd = [afford, "experiment", "base", "--system", system, "--reps", str(reps), "--steps", str(steps),
           "--jobs", str(jobs), "--transport", transport, "--keep-logs", "none", "--no-reuse-agents",
           "--progress", "none", "--quiet", "--out", str(folder), "--log-root", str(out / "logs"),
           "--run-prefix", prefix]
    began, used = time.monotonic(), resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(out / f"{prefix}.txt", "w") as log:
        code = subprocess.call(cmd, stdout=log, stderr=subprocess.STDOUT)
    wall = time.monotonic() - began
    now = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (now.ru_utime - used.ru_utime) + (now.ru_stime - used.ru_stime)
    if code != 0:
        sys.exit(f"goals-cost: {' '.join(cmd)} failed (exit {code}); see {out / prefix}.txt")
    summary = json.loads((folder / "summary.json").read_text())
    return wall, cpu, summary["systems"][system]["runs"]


def goals_part(args, builds, out):
    """{build: {transport: {system: [steps/s]}}} and the checksums seen, pairs alternated."""
    speeds = {b: {t: {"IMP": [], "GOALS": []} for t in args.transports} for b in builds}
    checksums = {}
    for i in range(args.pairs):
        for t in args.transports:
            for b, afford in builds.items():
                for system in ("IMP", "GOALS"):
                    _, cpu, runs = experiment(afford, out, f"{b}-{system}-{t}-{i}", system, args.steps, 1, 1, t)
                    sps = runs[0]["steps_per_second"]
                    speeds[b][t][system].append(sps)
                    checksums.setdefault((b, system), set()).add(runs[0]["weights_checksum"])
                    print(f"  pair {i + 1} {t} {b} {system}: {sps:.0f} steps/s, CPU {1e6 * cpu / args.steps:.0f} µs a "
                          f"step (load {load():.1f})", flush=True)
    return speeds, checksums


def full_part(args, builds, out):
    """{build: {transport: [wall s]}}, rounds alternated."""
    walls = {b: {"udpm": [], "memq": []} for b in builds}
    for i in range(args.rounds):
        for b, afford in builds.items():
            for t in ("udpm", "memq"):
                wall, cpu, runs = experiment(afford, out, f"{b}-full-{t}-{i}", "IMP", args.steps, args.runs, args.jobs, t)
                walls[b][t].append(wall)
                # The runs' own time (START to RESULT) against the wall: what the slots spent between runs.
                running = sum(args.steps / r["steps_per_second"] for r in runs) / args.jobs
                whole = sum(r["wall_seconds"] for r in runs) / args.jobs
                print(f"  round {i + 1} {b} {t}: {args.runs} runs at --jobs {args.jobs} in {wall:.1f} s; a slot's runs "
                      f"{running:.1f} s from START to RESULT, {whole:.1f} s with their set-up; CPU {1e6 * cpu / (args.runs * args.steps):.0f} µs a step "
                      f"(load {load():.1f})", flush=True)
    return walls


def listed(text, option, known):
    """The comma-separated names of --option, each one of `known`."""
    names = [n for n in text.split(",") if n]
    for n in names:
        if n not in known:
            sys.exit(f"goals-cost: --{option}: '{n}' is not one of {', '.join(known)}")
    return names


def main():
    ap = argparse.ArgumentParser(prog="bench/run.sh goals-cost")
    ap.add_argument("--steps", type=int, default=6000)
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--runs", type=int, default=8)
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--parts", default="goals,full")
    ap.add_argument("--transports", default="udpm,memq", help="of the goals part")
    ap.add_argument("--goals-floor", type=float, default=0.5)
    ap.add_argument("--full-floor", type=float, default=0.61)
    ap.add_argument("--afford", action="append", help="an afford program to measure (repeatable; default: this build's)")
    ap.add_argument("--out", default="build/bench/goals-cost")
    args = ap.parse_args()
    for name in ("steps", "pairs", "runs", "jobs", "rounds"):
        if getattr(args, name) < 1:
            sys.exit(f"goals-cost: --{name} must be at least 1")
    parts = listed(args.parts, "parts", ("goals", "full"))
    args.transports = listed(args.transports, "transports", ("udpm", "memq"))
    programs = args.afford or [str(ROOT / "build" / "bin" / "afford")]
    builds = {}
    for k, program in enumerate(programs):
        path = pathlib.Path(program).resolve()
        if not os.access(path, os.X_OK):
            sys.exit(f"goals-cost: --afford '{program}' is not an executable program")
        version = subprocess.run([str(path), "--version"], capture_output=True, text=True).stdout.split()
        builds[f"b{k}"] = str(path)
        print(f"b{k}: {path} ({version[-1] if version else 'version unknown'})")
    out = pathlib.Path(args.out).resolve() / time.strftime("%Y%m%d-%H%M%S")
    out.mkdir(parents=True, exist_ok=False)
    print(f"{os.cpu_count()} cores, load {load():.1f} at the start; folder {out}")
    code = 0
    first = next(iter(builds))
    report = {"args": vars(args), "builds": builds}
    if "goals" in parts:
        print(f"GOALS beside IMP: one run of {args.steps} steps each, {args.pairs} pair(s) per transport")
        speeds, checksums = goals_part(args, builds, out)
        report["goals"] = speeds
        for b in builds:
            for t in args.transports:
                imp, goals = (statistics.median(speeds[b][t][s]) for s in ("IMP", "GOALS"))
                ratio = goals / imp
                line = f"  {b} {t}: IMP {imp:.0f}, GOALS {goals:.0f} steps/s (medians); GOALS / IMP {ratio:.2f}"
                if t == "udpm":
                    met = ratio >= args.goals_floor
                    line += f" (floor {args.goals_floor}) {'PASS' if met else 'FAIL'}"
                    code = code or (0 if met or b != first else 1)
                print(line)
            print(f"  {b} weights checksums: IMP {sorted(checksums[(b, 'IMP')])}, GOALS {sorted(checksums[(b, 'GOALS')])}")
    if "full" in parts:
        print(f"A full machine: {args.runs} IMP runs of {args.steps} steps at --jobs {args.jobs}, {args.rounds} round(s)")
        walls = full_part(args, builds, out)
        report["full"] = walls
        for b in builds:
            udpm, memq = (statistics.median(walls[b][t]) for t in ("udpm", "memq"))
            ratio = memq / udpm  # steps per second in all, udpm / memq
            met = ratio >= args.full_floor
            print(f"  {b}: udpm {udpm:.1f} s, memq {memq:.1f} s (median walls); udpm / memq {ratio:.2f} "
                  f"(floor {args.full_floor}) {'PASS' if met else 'FAIL'}")
            code = code or (0 if met or b != first else 1)
    (out / "goals-cost.json").write_text(json.dumps(report, indent=2))
    return code


if __name__ == "__main__":
    sys.exit(main())

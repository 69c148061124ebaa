"""A full machine: N intrinsic runs at --jobs J (default: the cores) over each
transport, their throughput in all and per run, the ratio udpm / memq against
its floor, and how often each kind of process woke per step.

    bench/run.sh full [--runs N] [--steps S] [--jobs J] [--reps R]
                      [--transports udpm,memq] [--floor F] [--out DIR]

Each measurement is `afford experiment base --system IMP` without logs and
without stored agents (every run trains), in DIR/<date-time>/. Wake-ups are the voluntary and
involuntary context switches of every thread of every afford process, read
from /proc while the runs go (the last reading of a thread before it ends
counts), divided by the steps of all runs, for the main thread and the
others (LCM's receive thread, workers) apart. Exit 1 when udpm / memq is below
the floor.
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
AFFORD = ROOT / "build" / "bin" / "afford"


def switches(pid):
    """(kind, {tid: context switches}) of one process, or None once it is gone."""
    try:
        argv0 = pathlib.Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")[0].decode(errors="replace")
        kind = pathlib.Path(argv0).name or "?"
        counts = {}
        for task in pathlib.Path(f"/proc/{pid}/task").iterdir():
            n = 0
            for line in (task / "status").read_text().splitlines():
                if line.startswith(("voluntary_ctxt_switches", "nonvoluntary_ctxt_switches")):
                    n += int(line.split()[1])
            counts[task.name] = n
        return kind, counts
    except (FileNotFoundError, ProcessLookupError, PermissionError):
        return None


def afford_pids(root_pid):
    """The runner and every process under it."""
    children = {}
    for p in pathlib.Path("/proc").iterdir():
        if not p.name.isdigit():
            continue
        try:
            ppid = int((p / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (FileNotFoundError, IndexError, ValueError):
            continue
        children.setdefault(ppid, []).append(int(p.name))
    out, todo = [], [root_pid]
    while todo:
        pid = todo.pop()
        out.append(pid)
        todo.extend(children.get(pid, []))
    return out


def measure(transport, args, out_dir, rep):
    folder = out_dir / f"{transport}-{rep}"
    cmd = [str(AFFORD), "experiment", "base", "--system", "IMP", "--reps", str(args.runs), "--steps", str(args.steps),
           "--jobs", str(args.jobs), "--transport", transport, "--keep-logs", "none", "--no-reuse-agents",
           "--progress", "none", "--quiet", "--out", str(folder), "--log-root", str(out_dir / "logs"),
           "--run-prefix", f"full-{transport}-{rep}"]
    seen = {}  # (pid, tid) -> (kind, last count)
    began = time.monotonic()
    with open(out_dir / f"{transport}-{rep}.txt", "w") as log:
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT)
        while proc.poll() is None:
            for pid in afford_pids(proc.pid):
                got = switches(pid)
                if got:
                    kind, counts = got
                    for tid, n in counts.items():
                        seen[(pid, tid)] = (kind, n)
            time.sleep(0.2)
    wall = time.monotonic() - began
    if proc.returncode != 0:
        sys.exit(f"full: {transport} run {rep} failed (exit {proc.returncode}); see {out_dir}/{transport}-{rep}.txt")
    summary = json.loads((folder / "summary.json").read_text())
    per_run = [r["steps_per_second"] for r in summary["systems"]["IMP"]["runs"]]
    steps = args.runs * args.steps
    wakes = {}  # kind -> [main thread's, other threads', processes]
    for (pid, tid), (kind, n) in seen.items():
        w = wakes.setdefault(kind, [0, 0, set()])
        w[0 if str(pid) == tid else 1] += n
        w[2].add(pid)
    return {"wall": wall, "in_all": steps / wall, "per_run": statistics.median(per_run),
            "wakes_per_step": {k: (main / steps, other / steps, len(pids))
                               for k, (main, other, pids) in sorted(wakes.items())}}


def main():
    ap = argparse.ArgumentParser(prog="bench/run.sh full")
    ap.add_argument("--runs", type=int, default=4 * (os.cpu_count() or 1))
    ap.add_argument("--steps", type=int, default=6000)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--reps", type=int, default=2)
    ap.add_argument("--transports", default="udpm,memq")
    ap.add_argument("--floor", type=float, default=0.8)
    ap.add_argument("--out", default="build/bench/full")
    args = ap.parse_args()
    for name in ("runs", "steps", "jobs", "reps"):
        if getattr(args, name) < 1:
            sys.exit(f"full: --{name} must be at least 1")
    transports = [t for t in args.transports.split(",") if t]
    for t in transports:
        if t not in ("udpm", "memq"):
            sys.exit(f"full: --transports: '{t}' is neither udpm nor memq")
    # Each invocation in a folder of its own: experiment folders and run ids are never reused.
    out_dir = pathlib.Path(args.out).resolve() / time.strftime("%Y%m%d-%H%M%S")
    out_dir.mkdir(parents=True, exist_ok=False)
    print(f"full machine: {args.runs} runs of {args.steps} steps (base, IMP, no logs, every run trains), "
          f"--jobs {args.jobs} on {os.cpu_count()} cores, {args.reps} rep(s) per transport")
    results = {}
    for t in transports:
        reps = [measure(t, args, out_dir, r) for r in range(args.reps)]
        best = min(reps, key=lambda m: m["wall"])
        results[t] = best
        walls = ", ".join(f"{m['wall']:.1f}" for m in reps)
        print(f"  {t}: wall {walls} s; best: {best['in_all']:.0f} steps/s in all, "
              f"{best['per_run']:.0f} steps/s per run (median)")
        for kind, (main, other, n) in best["wakes_per_step"].items():
            print(f"      {kind:22s} {main + other:6.2f} wake-ups per step of all runs: main thread {main:.2f}, "
                  f"other threads (LCM's receive thread, workers) {other:.2f} ({n} process(es))")
    code = 0
    if "udpm" in results and "memq" in results:
        ratio = results["udpm"]["in_all"] / results["memq"]["in_all"]
        verdict = "PASS" if ratio >= args.floor else "FAIL"
        print(f"  udpm / memq in all: {ratio:.2f} (floor {args.floor}) {verdict}")
        code = 0 if ratio >= args.floor else 1
    (out_dir / "full.json").write_text(json.dumps({"args": vars(args), "results": results}, indent=2, default=list))
    return code


if __name__ == "__main__":
    sys.exit(main())

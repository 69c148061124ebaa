"""The whole reproduction on this machine: its wall time beside its critical
path (the longest chain of dependent work) and the share of the time the
cores were busy.

    bench/run.sh reproduction [--reps R] [--ext-reps K] [--jobs J] [--transport T]
                              [--out DIR] [WHAT ...]

Runs `scripts/reproduce.sh WHAT` (default: all) with OUT=DIR/<date-time> and
its report written there (docs/results.md is left alone), REPS and EXT_REPS if
given (default: the paper's counts), JOBS=J (default: the cores). Meanwhile it
reads /proc/stat: busy is the share of the cores' time not idle (nor waiting
for I/O) from the first experiment to the report, so run it on an otherwise
idle machine.

From every experiment folder's kept outcomes (runs/*.json):
  work           the wall seconds of every intrinsic run and test, summed;
  critical path  the longest chain of dependent work: an agent's training (or,
                 for an agent taken from the store, the training of the run it
                 was taken from) and then its longest test;
  bound          the least wall time J job slots could take: the larger of
                 work / J and the critical path.
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent


def cpu_times():
    """(busy, all) jiffies of every core, from /proc/stat."""
    fields = [int(v) for v in pathlib.Path("/proc/stat").read_text().splitlines()[0].split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)  # idle and iowait
    return sum(fields) - idle, sum(fields)


def outcomes(out):
    """run id -> (experiment, outcome) of every kept outcome under `out`."""
    found = {}
    for f in sorted(out.glob("*/runs/*.json")) + sorted(out.glob("*/conditions/*/runs/*.json")):
        try:
            j = json.loads(f.read_text())
            found[j["run_id"]] = (f.parent.parent.name, j["outcome"])
        except (OSError, ValueError, KeyError) as e:
            sys.exit(f"reproduction: {f}: not a kept outcome ({e})")
    return found


def critical_path(found):
    """(seconds, the chain) of the longest chain of dependent work, and the work in all."""
    agents = {rid: o for rid, (_, o) in found.items() if not o.get("extrinsic", {}).get("scenario")}
    tests = {rid: o for rid, (_, o) in found.items() if rid not in agents}
    work = sum(o["wall_seconds"] for _, o in found.values())
    best = (0.0, [])
    for rid, o in agents.items():
        chain, train = [rid], o["wall_seconds"]
        source = o.get("reused_from") or ""
        if source and source in found:  # trained once, by another experiment's run: that training comes first
            chain.insert(0, source)
            train += found[source][1]["wall_seconds"]
        mine = [(t["wall_seconds"], tid) for tid, t in tests.items() if tid.startswith(rid + "-")]
        longest = max(mine, default=(0.0, None))
        total = train + longest[0]
        if total > best[0]:
            best = (total, chain + ([longest[1]] if longest[1] else []))
    return best, work


def main():
    ap = argparse.ArgumentParser(prog="bench/run.sh reproduction")
    ap.add_argument("what", nargs="*", default=["all"])
    ap.add_argument("--reps", type=int)
    ap.add_argument("--ext-reps", type=int)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--transport", default="memq", choices=["memq", "udpm"])
    ap.add_argument("--out", default="build/bench/reproduction")
    args = ap.parse_args()
    for name in ("reps", "ext_reps", "jobs"):
        v = getattr(args, name)
        if v is not None and v < 1:
            sys.exit(f"reproduction: --{name.replace('_', '-')} must be at least 1")
    out = pathlib.Path(args.out).resolve() / time.strftime("%Y%m%d-%H%M%S")
    out.mkdir(parents=True, exist_ok=False)
    env = dict(os.environ, OUT=str(out), JOBS=str(args.jobs), TRANSPORT=args.transport,
               REPORT=str(out / "results.md"))
    if args.reps:
        env["REPS"] = str(args.reps)
    if args.ext_reps:
        env["EXT_REPS"] = str(args.ext_reps)
    subprocess.run([str(ROOT / "scripts" / "setup.sh")], check=True, stdout=subprocess.DEVNULL)
    busy0, all0 = cpu_times()
    began = time.monotonic()
    with open(out / "reproduce.txt", "w") as log:
        rc = subprocess.run([str(ROOT / "scripts" / "reproduce.sh"), *args.what], env=env, stdout=log,
                            stderr=subprocess.STDOUT, cwd=ROOT).returncode
    wall = time.monotonic() - began
    busy1, all1 = cpu_times()
    if rc != 0:
        sys.exit(f"reproduction: scripts/reproduce.sh failed (exit {rc}); see {out}/reproduce.txt")
    found = outcomes(out)
    (path, chain), work = critical_path(found)
    busy = (busy1 - busy0) / max(1, all1 - all0)
    cores = os.cpu_count() or 1
    bound = max(work / args.jobs, path)
    result = {"what": args.what, "reps": args.reps, "ext_reps": args.ext_reps, "jobs": args.jobs, "cores": cores,
              "transport": args.transport, "wall_seconds": wall, "runs_and_tests": len(found),
              "work_seconds": work, "critical_path_seconds": path, "critical_path": chain,
              "bound_seconds": bound, "busy_share": busy}
    (out / "reproduction.json").write_text(json.dumps(result, indent=2) + "\n")
    print(f"reproduction ({' '.join(args.what)}; {args.transport}, --jobs {args.jobs} on {cores} cores): "
          f"{len(found)} runs and tests")
    print(f"  wall {wall:.0f} s (plots and report included); cores busy {100 * busy:.0f}% of it")
    print(f"  work {work:.0f} s in all: {work / args.jobs:.0f} s on {args.jobs} slots")
    print(f"  critical path {path:.1f} s: {' -> '.join(chain)}")
    print(f"  bound {bound:.0f} s: the wall time is {wall / bound:.2f} times it")
    print(f"  {out}/reproduction.json")
    return 0


if __name__ == "__main__":
    sys.exit(main())

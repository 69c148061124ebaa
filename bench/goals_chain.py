"""Where a goals-phase step's time goes along its chain of messages, read from a run's log (issue 57):

    bench/run.sh goals-chain LOG [--first STEP] [--last STEP]

LOG is a run's log folder (logs/<run-id>) of a GOALS run, recorded with its log kept (`--keep-logs all`).
The logger stamps each message as it hears it. Each step t is cut into the links of its chain, from the
DECISION of step t-1 to the DECISION of step t: for a step that attended an object and asked the forward
models about it (a FOCUS of kind SCENE_OBJECT and a FORWARD_PREDICTION at step t),

    DECISION(t-1) -> SCENE(t) -> EFFECT(t-1) -> FOCUS(object) -> FORWARD_PREDICTION -> DECISION(t)

and for an exploration's step (a scan, no forward query)

    DECISION(t-1) -> SCENE(t) -> EFFECT(t-1) -> FOCUS(scan) -> DECISION(t)

Each link's median and mean are printed, with its share of the summed means and the processes that work
in it. Exit 1 when no step has a whole chain, 2 when LOG is not a log.
"""
import argparse
import collections
import pathlib
import statistics
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
SCENE_SCAN, SCENE_OBJECT = 0, 4  # focus_t's kinds (lcmtypes/focus_t.lcm)
# The points of a step's chain, each a message of step t or t-1 (its name, the step's offset, its label), and
# who works between two points: a step that attended an object and asked about it, and an exploration's
# step (a scan, no forward query).
ASKED = ([("DECISION", -1, "DECISION(t-1)"), ("SCENE", 0, "SCENE(t)"), ("EFFECT", -1, "EFFECT(t-1)"),
          ("FOCUS(object)", 0, "FOCUS(object)"), ("FORWARD_PREDICTION", 0, "FORWARD_PREDICTION"),
          ("DECISION", 0, "DECISION(t)")],
         ["environment: the action, its scene", "eye: the action's effect",
          "eye, planner, motivation: the looks, a goal's end and the next goal",
          "predictors: the update, the forward models' outputs", "planner: its choice"])
EXPLORED = ([("DECISION", -1, "DECISION(t-1)"), ("SCENE", 0, "SCENE(t)"), ("EFFECT", -1, "EFFECT(t-1)"),
             ("FOCUS(scan)", 0, "FOCUS(scan)"), ("DECISION", 0, "DECISION(t)")],
            ["environment: the action, its scene", "eye: the action's effect",
             "eye, planner, motivation: a goal's end, the next goal, the scan",
             "predictors, planner: the update, the object's affordances, the choice"])


def chains(first_heard, first, last, chain):
    """{link: [µs]} and the whole chain's [µs], of the steps from first to last that have every point of it
    (an exploration's: and no forward query)."""
    points, _ = chain
    out: dict[str, list[int]] = {f"{a[2]} -> {b[2]}": [] for a, b in zip(points, points[1:])}
    whole = []
    for t in range(max(first, 1), last + 1):
        if chain is EXPLORED and "FORWARD_PREDICTION" in first_heard.get(t, {}):
            continue
        times = [first_heard.get(t + offset, {}).get(name) for name, offset, _ in points]
        if any(p is None for p in times):
            continue
        for link, p, q in zip(out, times, times[1:]):
            out[link].append(q - p)
        whole.append(times[-1] - times[0])
    return out, whole


def report(title, chain, values, whole):
    if not whole:
        print(f"{title}: no step")
        return
    total = sum(statistics.mean(v) for v in values.values())
    print(f"{title}: {len(whole)} steps; a step's chain median {statistics.median(whole):.0f} µs, "
          f"mean {statistics.mean(whole):.0f} µs")
    for (link, v), who in zip(values.items(), chain[1]):
        mean = statistics.mean(v)
        print(f"  {link:40} median {statistics.median(v):6.0f} µs  mean {mean:6.0f} µs "
              f"({100 * mean / total:4.1f}%)  {who}")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("log", help="a GOALS run's log folder (logs/<run-id>)")
    ap.add_argument("--first", type=int, default=1, help="the first step counted (default 1)")
    ap.add_argument("--last", type=int, default=None, help="the last step counted (default: the run's last)")
    args = ap.parse_args()
    sys.path.insert(0, str(ROOT / "build" / "python"))
    from afford.logs import read_log  # noqa: E402 (the build's package)

    try:
        log = read_log(args.log, channels=["DECISION", "SCENE", "EFFECT", "FOCUS", "FORWARD_PREDICTION"])
    except RuntimeError as e:
        print(f"goals-chain: {e}", file=sys.stderr)
        return 2
    first_heard: dict[int, dict[str, int]] = collections.defaultdict(dict)
    for m in sorted(log.messages, key=lambda m: m.utime):
        step = m.fields.get("step")
        if step is None:
            continue
        name = m.channel
        if name == "FOCUS":
            kind = m.fields.get("kind")
            if kind not in (SCENE_SCAN, SCENE_OBJECT):
                continue
            name = "FOCUS(object)" if kind == SCENE_OBJECT else "FOCUS(scan)"
        first_heard[step].setdefault(name, m.utime)
    last = args.last if args.last is not None else max(first_heard, default=0)
    asked, asked_whole = chains(first_heard, args.first, last, ASKED)
    explored, explored_whole = chains(first_heard, args.first, last, EXPLORED)
    if not asked_whole and not explored_whole:
        print(f"goals-chain: {args.log}: no step from {args.first} to {last} has its whole chain "
              "(is it a GOALS run's log?)", file=sys.stderr)
        return 1
    print(f"{log.run_id}, steps {max(args.first, 1)} to {last}:")
    report("steps that attended an object and asked the forward models", ASKED, asked, asked_whole)
    report("steps of an exploration (a scan, no forward query)", EXPLORED, explored, explored_whole)
    return 0


if __name__ == "__main__":
    sys.exit(main())

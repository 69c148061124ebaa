"""Components written in Python against the all-C++ agent: steps per second (docs/performance.md).

    bench/run.sh python [--steps N] [--reps R] [--floor F] [--out DIR]

For each transport, the all-C++ run of base IMP, then the same run with the
Python port of the paper's motivation (python/tests/motivations.py:PyPaper),
and with the Python port of the paper's affordance predictor
(python/tests/predictors.py:PyPerceptrons): in this process over memq
(afford.run(motivation=..., affordance=...)), as a process of its own over
udpm (python3 -m afford.process). Each is a port, so every run must give the
C++ run's weights checksum; the median steps per second of R runs each,
and its ratio to the C++ run's. Exit 1 if the motivation's ratio is below
--floor (0.5) on a transport, or a checksum differs. First, the time
afford.load takes to read every folder of docs/results (floor 2 s in all).
"""
import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TESTS = ROOT / "python" / "tests"
sys.path.insert(0, str(TESTS))

import afford  # noqa: E402
from motivations import PyPaper  # noqa: E402
from predictors import PyPerceptrons  # noqa: E402

NEVER = {"predictors.memory.keep": "never"}  # the ports need no memory: the checksums compare with the paper's


def variants(transport):
    process = f"{sys.executable} -m afford.process"
    if transport == "memq":
        return [("C++", {}, {}), ("Python motivation", {"motivation": PyPaper}, NEVER),
                ("Python affordance predictor", {"affordance": PyPerceptrons}, {})]
    return [("C++", {}, {}),
            ("Python motivation", {"processes": {"motivation": f"{process} motivation {TESTS}/motivations.py:PyPaper"}},
             NEVER | {"motivation.kind": "py-paper"}),
            ("Python affordance predictor",
             {"processes": {"predictors": f"{process} predictors {TESTS}/predictors.py:PyPerceptrons"}},
             {"predictors.affordance.kind": "py-perceptrons"})]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=6000)
    ap.add_argument("--reps", type=int, default=3)
    ap.add_argument("--floor", type=float, default=0.5)
    ap.add_argument("--transports", default="memq,udpm")
    ap.add_argument("--out", default=None)
    a = ap.parse_args()
    out = Path(a.out or tempfile.mkdtemp(prefix="afford-bench-python-"))
    os.environ["PYTHONPATH"] = f"{TESTS}:{Path(afford.__file__).parent.parent}"
    failed = False
    start = time.perf_counter()
    folders = sorted(d for d in (ROOT / "docs" / "results").iterdir() if d.is_dir())
    rows = sum(len(f) for d in folders for f in afford.load(d).figures.values())
    took = time.perf_counter() - start
    failed |= took > 2.0
    print(f"afford.load of the {len(folders)} folders of docs/results ({rows} rows): {took:.2f} s (floor 2 s: "
          f"{'FAIL' if took > 2.0 else 'PASS'})")
    print(f"base IMP, {a.steps} steps, median of {a.reps} runs each; logs off; {out}")
    print(f"{'transport':9}  {'component':28}  {'steps/s':>8}  {'of C++':>6}  checksum")
    for transport in a.transports.split(","):
        base = None
        for name, kw, settings in variants(transport):
            rates, sums = [], set()
            for r in range(a.reps):
                e = afford.run("base", system="IMP", reps=1, steps=a.steps, transport=transport, keep_logs="none",
                               out=out / transport / f"{name.replace(' ', '-')}-{r}", set=settings, replace=True,
                               **kw)
                rates.append(float(e.runs["steps_per_second"].iloc[0]))
                sums.add(e.runs["weights_checksum"].iloc[0])
            rate = statistics.median(rates)
            base = base or (rate, sums)
            ratio = rate / base[0]
            same = sums == base[1] and len(sums) == 1
            failed |= not same or (name == "Python motivation" and ratio < a.floor)
            print(f"{transport:9}  {name:28}  {rate:8.0f}  {ratio:6.2f}  {','.join(sorted(sums))}"
                  f"{'' if same else '  DIFFERS from the C++ run'}")
    print(f"floors (docs/results loaded within 2 s; the Python motivation at least {a.floor} of the C++ run's "
          f"steps per second; the C++ checksums): {'FAIL' if failed else 'PASS'}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

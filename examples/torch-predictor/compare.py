"""The PyTorch predictor against the paper's perceptrons: affordance error and steps per second on the base
table and on random tables, IMP, the same seeds (docs/results-discussion.md reports it).

    PYTHONPATH=build/python /usr/bin/python3 examples/torch-predictor/compare.py [--steps 6000] [--reps 3]
        [--tables 3] [--out out/torch-compare]

The random tables are random-tables' first ones (its series, seed 1), the paper's agent (not its memory
condition). Writes OUT/runs.csv (one row per run: table, predictor, seed, affordance_mae, steps_per_second) and prints the
medians. In process (memq), one run at a time.
"""
import argparse
import shutil
import sys
from pathlib import Path

import pandas as pd

import afford

sys.path.insert(0, str(Path(__file__).resolve().parent))
from torch_predictor import TorchConv  # noqa: E402


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--steps", type=int, default=6000)
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--tables", type=int, default=3)
    p.add_argument("--out", default="out/torch-compare")
    a = p.parse_args()
    out = Path(a.out)
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    # random-tables' tables (its series, seed 1), the paper's agent only (without its memory condition)
    tables_file = out / "random-tables-paper.yaml"
    tables_file.write_text("extends: base\ndescription: random tables, the paper's agent\nextrinsic: none\n"
                           f"repetitions: 1\ntables:\n  count: {a.tables}\n  seed: 1\n")
    rows = []
    for name, affordance in (("perceptrons (paper)", None), ("torch-conv", TorchConv)):
        kw = dict(system="IMP", steps=a.steps, affordance=affordance, keep_logs="none")
        base = afford.run("base", reps=a.reps, out=out / name.split()[0] / "base", **kw)
        tables = afford.run(str(tables_file), out=out / name.split()[0] / "tables", **kw)
        for table, e in (("base", base), ("random", tables)):
            r = e.runs
            for _, run in r.iterrows():
                rows.append({"table": table, "predictor": name, "run_id": run["run_id"], "seed": run["seed"],
                             "affordance_mae": run["affordance_mae"], "steps_per_second": run["steps_per_second"]})
    df = pd.DataFrame(rows)
    df.to_csv(out / "runs.csv", index=False)
    summary = df.groupby(["table", "predictor"])[["affordance_mae", "steps_per_second"]].median()
    summary["runs"] = df.groupby(["table", "predictor"]).size()
    print(f"IMP, {a.steps} steps; medians over the runs:")
    print(summary.to_string(float_format=lambda v: f"{v:.4f}" if v < 10 else f"{v:.0f}"))
    return 0


if __name__ == "__main__":
    sys.exit(main())

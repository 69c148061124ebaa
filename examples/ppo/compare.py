"""PPO (examples/ppo/ppo.py) beside afford's goal planner with an IMP agent, on the same extrinsic scenarios.

    PYTHONPATH=build/python /usr/bin/python3 examples/ppo/compare.py --out ~/ppo-compare
    PYTHONPATH=build/python /usr/bin/python3 examples/ppo/compare.py --plot --out docs/ppo   # the figure again

PPO learns each scenario from its goal reward, on worlds of the scenario: its success (the policy's most
likely action, on worlds it never trained on) against the environment steps it trained. The planner needs no
reward: an IMP agent learns affordances and effects for --intrinsic-steps steps with no task, then the
planner (Algorithm 2, one-step) is tested on the scenario (--tests tests per agent, the planner's budget of
planner.budget steps each). Writes OUT/compare.csv, OUT/compare.md and OUT/fig_ppo_vs_planner.png (OUT: --out,
else a new folder in the temporary directory, never inside the checkout). --plot draws the figure again from a
folder's compare.csv and PPO's evaluations: OUT/ppo-SCENARIO/ppo_eval.csv, as written here, or
OUT/ppo_eval_SCENARIO.csv, as docs/ppo keeps them.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np
import pandas as pd

import afford
import ppo


def evaluations(out: Path, scenario: str) -> Path:
    """PPO's evaluations of `scenario` in `out`: ppo-SCENARIO/ppo_eval.csv (as main writes them) or
    ppo_eval_SCENARIO.csv (as docs/ppo keeps them)."""
    for path in (out / f"ppo-{scenario}" / "ppo_eval.csv", out / f"ppo_eval_{scenario}.csv"):
        if path.is_file():
            return path
    raise SystemExit(f"{out} holds no evaluations of PPO on {scenario}: neither ppo-{scenario}/ppo_eval.csv nor "
                     f"ppo_eval_{scenario}.csv")


def plot(out: Path, scenarios: list[str] | None = None) -> Path:
    """fig_ppo_vs_planner.png from compare.csv and each scenario's evaluations (default: compare.csv's scenarios)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    if not (out / "compare.csv").is_file():
        raise SystemExit(f"{out} holds no compare.csv: give --out the folder of an earlier comparison")
    table = pd.read_csv(out / "compare.csv")
    scenarios = scenarios or list(dict.fromkeys(table["scenario"]))
    curves = {scenario: pd.read_csv(evaluations(out, scenario)) for scenario in scenarios}
    fig, axes = plt.subplots(1, len(scenarios), figsize=(4.6 * len(scenarios), 3.8), dpi=110, squeeze=False)
    for ax, scenario in zip(axes[0], scenarios):
        c = curves[scenario]
        ax.plot(c["env_steps"], c["success"], marker="o", label="PPO, goal reward\n(greedy, worlds not trained on)")
        p = table[(table["scenario"] == scenario) & (table["task reward used"] == "no")].iloc[0]
        ax.scatter([p["training env steps"]], [p["success"]], color="tab:red", marker="s", s=60, zorder=3,
                   label=f"IMP agent + goal planner\n({p['training env steps']} intrinsic steps, no reward)")
        ax.set_ylim(-0.05, 1.05)
        ax.set_xlabel("environment steps trained")
        ax.set_ylabel("success")
        ax.set_title(scenario)
        ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(out / "fig_ppo_vs_planner.png")
    plt.close(fig)
    return out / "fig_ppo_vs_planner.png"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scenarios", nargs="+", help="default: scenario1 scenario2 scenario3 (with --plot, compare.csv's)")
    ap.add_argument("--ppo-steps", type=int, nargs="+", default=[8192, 16384, 32768],
                    help="PPO's environment steps, one per scenario (or one for all)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--eval-every", type=int, default=2, help="PPO's updates between evaluations")
    ap.add_argument("--agents", type=int, default=4, help="IMP agents trained for the planner")
    ap.add_argument("--intrinsic-steps", type=int, default=6000)
    ap.add_argument("--tests", type=int, default=8, help="extrinsic tests per agent and scenario")
    ap.add_argument("--out", help="the folder written (default: a new one in the temporary directory)")
    ap.add_argument("--plot", action="store_true", help="only draw the figure again from OUT's files")
    a = ap.parse_args(argv)
    if a.plot:
        if not a.out:
            ap.error("--plot draws the figure of an earlier comparison again: give its folder, --out")
        print(plot(Path(a.out), a.scenarios))
        return 0
    a.scenarios = a.scenarios or ["scenario1", "scenario2", "scenario3"]
    out = ppo.output_folder(a.out, "afford-ppo-compare-")
    print(f"writing into {out}", flush=True)
    budgets = a.ppo_steps * len(a.scenarios) if len(a.ppo_steps) == 1 else a.ppo_steps
    if len(budgets) != len(a.scenarios):
        raise SystemExit("--ppo-steps: one value, or one per scenario")

    planner = afford.run("base", system="IMP", reps=a.agents, steps=a.intrinsic_steps, seed=a.seed,
                         extrinsic_reps=a.tests, scenarios=a.scenarios, keep_logs="none", out=out / "planner",
                         replace=True)
    rows = []
    for scenario, steps in zip(a.scenarios, budgets):
        tests = planner.extrinsic[planner.extrinsic["scenario"] == scenario]
        solved = tests[tests["success"] == 1]
        rows.append({"scenario": scenario, "learner": "IMP agent + goal planner",
                     "training env steps": a.intrinsic_steps, "task reward used": "no",
                     "success": float(tests["success"].mean()), "episodes": len(tests),
                     "median steps to success": float(solved["completion"].median()) if len(solved) else math.nan})
        args = ppo.parse_args(["--scenario", scenario, "--total-steps", str(steps), "--seed", str(a.seed),
                               "--eval-every", str(a.eval_every), "--out", str(out / f"ppo-{scenario}")])
        result = ppo.train(args)
        curve = pd.read_csv(out / f"ppo-{scenario}" / "ppo_eval.csv")
        first = curve[curve["success"] >= 0.9]
        rows.append({"scenario": scenario, "learner": "PPO (goal reward)", "training env steps": result["env_steps"],
                     "task reward used": "yes", "success": result["final_success"],
                     "episodes": args.eval_episodes, "median steps to success": result["final_median_steps"],
                     "env steps to 90% success": int(first["env_steps"].iloc[0]) if len(first) else None,
                     "weights": result["weights_checksum"]})
    table = pd.DataFrame(rows)
    table.to_csv(out / "compare.csv", index=False)
    cells = table.fillna("-").astype(str)
    (out / "compare.md").write_text("\n".join(["| " + " | ".join(cells.columns) + " |",
                                               "|" + "---|" * len(cells.columns)] +
                                              ["| " + " | ".join(r) + " |" for r in cells.values.tolist()]) + "\n")

    plot(out, a.scenarios)
    print(table.to_string(index=False))
    print(out / "compare.csv")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

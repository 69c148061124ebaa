"""afford.env's batched form against single environments: environment steps per second.

    bench/run.sh env [--worlds 16] [--steps 2000] [--reps 3] [--threads 1,2] [--grid 5] [--out DIR]

The same worlds (seeds 1..N), the same actions (drawn once from a seeded generator), stepped as N
FlatAffordEnv in a Python loop and as one AffordVectorEnv (one call of the C++ core per step, the GIL
released) on each number of threads. Episodes of run.steps = 500 end and restart on the way. Checks that
both gave the same rewards. Then what each form's check of a step's action against its space (check_in) costs
against its step (the best of 7 timings of each). docs/performance.md reports it.
"""
import argparse
import json
import statistics
import sys
import time
import timeit
from pathlib import Path

import numpy as np

from afford.env import AffordEnv, AffordVectorEnv, FlatAffordEnv, check_in


def check_cost(n: int) -> dict:
    """Microseconds of each form's check of an action, and of its step (each the best of 7 timings)."""
    def best(f, number):
        return min(timeit.repeat(f, number=number, repeat=7)) / number * 1e6
    settings = {"run.steps": 10**8}
    flat, plain = FlatAffordEnv(world="base", seed=1, set=settings), AffordEnv(world="base", seed=1, set=settings)
    vec = AffordVectorEnv(n, world="base", seed=1, set=settings)
    for e in (flat, plain, vec):
        e.reset(seed=1)
    acts, look = np.arange(n, dtype=np.int64) % vec.single_action_space.n, np.array([-1.0, -1.0])
    forms = {"FlatAffordEnv": (flat, 7), "AffordEnv": (plain, {"act": 2, "look": look}),
             f"AffordVectorEnv ({n})": (vec, acts)}
    out = {}
    for name, (env, action) in forms.items():
        check, step = best(lambda: check_in(env.action_space, action), 2000), best(lambda: env.step(action), 200)
        out[name] = {"check_us": round(check, 2), "step_us": round(step, 1), "share": round(check / step, 4)}
    return out


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--worlds", type=int, default=16)
    p.add_argument("--steps", type=int, default=2000, help="steps of every world")
    p.add_argument("--reps", type=int, default=3)
    p.add_argument("--threads", default="1,2")
    p.add_argument("--grid", type=int, default=5)
    p.add_argument("--out", default="out/bench-env")
    a = p.parse_args()
    settings = {"run.steps": 500}
    n = a.worlds
    actions = np.random.default_rng(1).integers(0, 5 + 4 * a.grid * a.grid, (a.steps, n))
    results = {"worlds": n, "steps": a.steps, "grid": a.grid, "single": [], "batched": {}}

    def singles():
        envs = [FlatAffordEnv(world="base", seed=1 + i, set=settings, grid=a.grid) for i in range(n)]
        for i, e in enumerate(envs):
            e.reset(seed=1 + i)
        rewards = np.zeros(n)
        start = time.perf_counter()
        for t in range(a.steps):
            for i, e in enumerate(envs):
                _, r, te, tr, _ = e.step(int(actions[t, i]))
                rewards[i] += r
                if te or tr:
                    e.reset()
        return n * a.steps / (time.perf_counter() - start), rewards

    def batched(threads):
        env = AffordVectorEnv(n, world="base", seed=1, set=settings, grid=a.grid, threads=threads)
        env.reset(seed=1)
        rewards = np.zeros(n)
        start = time.perf_counter()
        for t in range(a.steps):
            _, r, *_ = env.step(actions[t])
            rewards += r
        return n * a.steps / (time.perf_counter() - start), rewards

    threads = [int(t) for t in a.threads.split(",")]
    for _ in range(a.reps):
        speed, base = singles()
        results["single"].append(round(speed))
        for th in threads:
            speed, rewards = batched(th)
            if not np.array_equal(rewards, base):
                print(f"the batched form ({th} threads) gave other rewards than the single environments")
                return 1
            results["batched"].setdefault(str(th), []).append(round(speed))
    single = statistics.median(results["single"])
    print(f"{n} worlds x {a.steps} steps, grid {a.grid}: env-steps/s (median of {a.reps}); the same rewards")
    print(f"  {n} FlatAffordEnv in a loop: {single:.0f}  {results['single']}")
    for th, v in results["batched"].items():
        m = statistics.median(v)
        print(f"  AffordVectorEnv, {th} thread(s): {m:.0f}  {v}  ({m / single:.2f} x)")
    results["check"] = check_cost(n)
    print("the check of a step's action against the action space, against the step (best of 7):")
    for name, c in results["check"].items():
        print(f"  {name}: check {c['check_us']} us, step {c['step_us']} us ({100 * c['share']:.1f}%)")
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

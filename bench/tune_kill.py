"""bench/run.sh tune-kill: a study whose workers are killed (SIGKILL) at random moments and started again, and
what is left of it checked (docs/performance.md#a-study-whose-workers-are-killed, docs/operating.md#locks).

W workers (`afford tune` processes) share a study of T trials; K times, one of them is killed and at once started
again with the same command. A kill is aimed: inside the journal's lock (Optuna's appends: the worker is seen
holding study.journal's flock in /proc/locks, stopped with SIGSTOP, seen still holding it, then killed), inside
the study's claim (study.lock: counting, asking for a trial and claiming it, the report), inside the claim
between asking for a trial and claiming it (stopped in the claim while the journal holds a running trial that
names no worker), or anywhere (after a random delay, whatever the worker is doing). Then the workers run to the
end and the journal is checked. Floors (exit 1 on any): every kill made; every worker ends within --wait seconds
of the last kill (none waits for good), none failing; the study has its T trials finished, each counted once
(each trial stopped short retried exactly once, none finished twice); none RUNNING or WAITING; every journal
line whole JSON.

    bench/run.sh tune-kill [--trials 20] [--workers 2] [--kills 30] [--journal-kills 10] [--claim-kills 5]
                           [--unclaimed-kills 5] [--steps 20000] [--prune-warmup 0.5] [--seed 1] [--wait 600]
                           [--out DIR]
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

import afford

AFFORD = Path(__file__).resolve().parents[1] / "build" / "bin" / "afford"
PARAMS = ["motivation.leak=log:0.01:0.9", "predictors.affordance.learning_rate=log:0.01:1"]


def holders(path: Path) -> set[int]:
    """The processes holding a flock on `path` (its waiters aside), from /proc/locks."""
    st = os.stat(path)
    device = f"{os.major(st.st_dev):02x}:{os.minor(st.st_dev):02x}:{st.st_ino}"
    out = set()
    for line in Path("/proc/locks").read_text().splitlines():
        f = line.split()
        if len(f) >= 6 and f[1] == "FLOCK" and f[5] == device:  # ("N: -> FLOCK ..." is a waiter: f[1] is "->")
            out.add(int(f[4]))
    return out


def stopped(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] in ("T", "t")
    except OSError:
        return False


def unclaimed(journal: Path) -> set[int]:
    """The running trials that name no worker (asked for, not yet claimed), by id: Optuna's journal replayed as
    far as that goes (a trial's id is its place among the trials made; a trial made with no state is running)."""
    state, named = [], set()
    for line in journal.read_bytes().splitlines():
        if not _json(line):
            continue
        log = json.loads(line)
        op = log.get("op_code")
        if op == 4:  # CREATE_TRIAL
            state.append(log.get("state", 0))
            if "worker" in (log.get("user_attrs") or {}):
                named.add(len(state) - 1)
        elif op == 6:  # SET_TRIAL_STATE_VALUES
            state[log["trial_id"]] = log["state"]
        elif op == 8 and "worker" in log.get("user_attr", {}):  # SET_TRIAL_USER_ATTR
            named.add(log["trial_id"])
    return {i for i, s in enumerate(state) if s == 0 and i not in named}  # (0: TrialState.RUNNING)


def aim(worker: subprocess.Popen, path: Path, seconds: float, inside=lambda: True) -> bool:
    """`worker` stopped (SIGSTOP) while it holds `path`'s flock (and `inside()` holds): True; False when it did
    not within `seconds` (or ended)."""
    end = time.monotonic() + seconds
    while time.monotonic() < end and worker.poll() is None:
        try:
            if worker.pid in holders(path):
                os.kill(worker.pid, signal.SIGSTOP)
                while worker.poll() is None and not stopped(worker.pid):
                    time.sleep(0.0002)
                if worker.pid in holders(path) and inside():
                    return True
                os.kill(worker.pid, signal.SIGCONT)
        except FileNotFoundError:  # (the study's files not made yet)
            pass
        time.sleep(0.0002)
    return False


class Workers:
    def __init__(self, command: list[str], logs: Path):
        self.command, self.logs, self.started = command, logs, 0
        logs.mkdir(parents=True, exist_ok=True)

    def start(self) -> subprocess.Popen:
        self.started += 1
        with open(self.logs / f"worker-{self.started:03d}.txt", "w") as out:
            return subprocess.Popen(self.command, stdout=out, stderr=subprocess.STDOUT)


def check(folder: Path, trials: int) -> dict:
    """What the journal says once every worker has ended."""
    journal = (folder / "study.journal").read_bytes()
    lines = journal.split(b"\n")
    bad_lines = sum(1 for line in lines[:-1] if not _json(line)) + (lines[-1] != b"")
    df = afford.load_study(folder).trials
    lost = df[df["stopped"].isin(["worker lost", "interrupted"])]
    finished = df[df["state"].isin(["COMPLETE", "PRUNED"]) | ((df["state"] == "FAIL") & df["error"].notna())]
    retries = df["retry_of"].dropna().astype(int).value_counts().to_dict()
    return {"trials_in_journal": len(df), "finished": len(finished),
            "complete": int((df["state"] == "COMPLETE").sum()), "pruned": int((df["state"] == "PRUNED").sum()),
            "failed_saying_why": int(((df["state"] == "FAIL") & df["error"].notna()).sum()),
            "stopped_short": len(lost), "running": int((df["state"] == "RUNNING").sum()),
            "waiting": int((df["state"] == "WAITING").sum()),
            "retried_not_once": sorted(int(n) for n in lost["number"] if retries.get(int(n), 0) != 1),
            "retries_of_finished": sorted(int(n) for n in retries if int(n) in set(finished["number"])),
            "folders_twice": int(finished["folder"].duplicated().sum()),
            "journal_lines": len(lines) - 1, "journal_bad_lines": bad_lines}


def _json(line: bytes) -> bool:
    try:
        json.loads(line)
        return True
    except ValueError:
        return False


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--trials", type=int, default=20)
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--kills", type=int, default=30)
    p.add_argument("--journal-kills", type=int, default=10, help="of the kills, those inside the journal's lock")
    p.add_argument("--claim-kills", type=int, default=5, help="of the kills, those inside the study's claim")
    p.add_argument("--unclaimed-kills", type=int, default=5,
                   help="of the kills, those between asking for a trial and claiming it")
    p.add_argument("--steps", type=int, default=20000)
    p.add_argument("--prune-warmup", type=float, default=0.5, help="the study's (a trial runs this share of its "
                   "steps before it may be pruned: the study outlasts the kills)")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--wait", type=float, default=600, help="seconds the workers have to end after the last kill")
    p.add_argument("--out", default="out/bench-tune-kill")
    a = p.parse_args()
    aimed = a.journal_kills + a.claim_kills + a.unclaimed_kills
    if aimed > a.kills:
        sys.exit("--journal-kills, --claim-kills and --unclaimed-kills are kills of --kills")
    out = Path(a.out)
    folder = out / "study"
    if folder.exists():
        sys.exit(f"{folder} exists: give a new --out")
    command = [str(AFFORD), "tune", "base", "--out", str(folder), "--trials", str(a.trials), "--steps", str(a.steps),
               "--seed", str(a.seed), "--prune-warmup", str(a.prune_warmup), "--keep-logs", "none"]
    for param in PARAMS:
        command += ["--param", param]
    kinds = (["journal"] * a.journal_kills + ["claim"] * a.claim_kills + ["unclaimed"] * a.unclaimed_kills +
             ["any"] * (a.kills - aimed))
    kinds = [kinds[i] for i in np.random.default_rng([a.seed, 0x6b696c6c]).permutation(len(kinds))]
    workers = Workers(command, out / "logs")
    began = time.monotonic()
    live = [workers.start() for _ in range(a.workers)]
    kills, missed, ended = [], [], []  # ended: the exit status of each worker that ended on its own
    for k, kind in enumerate(kinds):
        for attempt in range(5):  # (an aimed kill: the worker ended first, or held no such lock for a minute)
            rng = np.random.default_rng([a.seed, k, attempt, 0x6b696c6c])
            ended += [w.returncode for w in live if w.poll() is not None]  # (its trials finished or under way)
            live = [w for w in live if w.returncode is None]
            if not live:
                break
            victim = live[int(rng.integers(len(live)))]
            time.sleep(float(rng.uniform(0.2, 4.0)))  # (a random moment; an aimed kill aims from there)
            journal = folder / "study.journal"
            before = unclaimed(journal) if kind == "unclaimed" and journal.exists() else set()

            def inside():  # (an unclaimed kill: a trial asked for since the aim began, and not claimed)
                return kind != "unclaimed" or bool(unclaimed(journal) - before)
            lock = journal if kind == "journal" else folder / "study.lock"
            if kind != "any" and not aim(victim, lock, 60, inside):
                if victim.poll() is None:
                    os.kill(victim.pid, signal.SIGCONT)
                continue
            if victim.poll() is not None:
                continue
            victim.kill()
            victim.wait()
            live[live.index(victim)] = workers.start()
            kills.append({"kill": k, "kind": kind, "attempt": attempt, "at_s": round(time.monotonic() - began, 2)})
            break
        else:
            missed.append({"kill": k, "kind": kind})
        if not live:
            print(f"the study ended after {len(kills)} kills: give more --steps", file=sys.stderr)
            break
    last_kill = time.monotonic()
    hung = []
    for w in live:
        try:
            ended.append(w.wait(timeout=max(1.0, a.wait - (time.monotonic() - last_kill))))
        except subprocess.TimeoutExpired:
            hung.append(w.pid)
            w.kill()
            w.wait()
    wall = time.monotonic() - began
    said = "".join(f.read_text() for f in sorted((out / "logs").iterdir()))
    result = {"trials": a.trials, "workers": a.workers, "steps": a.steps, "prune_warmup": a.prune_warmup,
              "seed": a.seed,
              "kills": len(kills), "missed": missed,
              "by_kind": {x: sum(1 for k in kills if k["kind"] == x) for x in ("journal", "claim", "unclaimed", "any")},
              "ended_on_their_own": len(ended), "failed_on_their_own": sum(1 for c in ended if c != 0),
              "workers_started": workers.started, "hung": hung, "wall_seconds": round(wall, 1),
              "seconds_after_last_kill": round(time.monotonic() - last_kill, 1),
              "unclaimed_found": said.count("its worker died before claiming it"),
              "lost_found": said.count(") is gone: it runs again"),
              **check(folder, a.trials), "kill_log": kills}
    floors = {"every kill made": len(kills) == a.kills,
              "no worker waits for good": not hung,
              "no worker failed": result["failed_on_their_own"] == 0,
              "the study's trials finished": result["finished"] == a.trials,
              "each counted once": not result["retried_not_once"] and not result["retries_of_finished"]
              and not result["folders_twice"],
              "none running or waiting": result["running"] == 0 and result["waiting"] == 0,
              "the journal whole": result["journal_bad_lines"] == 0}
    result["floors"] = floors
    (out / "result.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps({k: v for k, v in result.items() if k != "kill_log"}, indent=2))
    for name, ok in floors.items():
        print(f"{'PASS' if ok else 'FAIL'}: {name}")
    return 0 if all(floors.values()) else 1


if __name__ == "__main__":
    sys.exit(main())

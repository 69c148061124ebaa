#!/usr/bin/env bash
# Benchmarks (docs/performance.md).
#   bench/run.sh [--steps N] [--reps R] [--out DIR]
#     the intrinsic phase: steps per second over udpm and memq and their ratio,
#     log bytes per step, peak memory per process;
#   bench/run.sh boundaries [--tests K] [--runs R] [--run-steps S] [--transports udpm,memq]
#                           [--parts extrinsic,short,main] [--train-steps N] [--out DIR]
#     run boundaries, logs kept and not: extrinsic tests per second and their
#     wall times, short runs per minute, the main job's wall time; PASS/FAIL
#     against the floors (exit 1 on a FAIL).
#   bench/run.sh replay [--experiment E] [--system S] [--steps N] [--reps R] [--transports udpm,memq] [--out DIR]
#     the memory options of issue 11 (replay, revisits): steps per second on / off per transport (floor 0.7,
#     exit 1 below it), the predictors' peak memory, the checkpoint's size.
#   bench/run.sh auth [--steps N] [--reps R] [--floor F] [--out DIR]
#     an authenticated bus: steps per second over udpm with a bus key against without (floor 0.9,
#     exit 1 below it), and the time to tag one message by size.
#   bench/run.sh logger-faults [N] [FAULT ...]
#     the logger killed and started again after the run's last step or 6 s later, or paused past
#     close_timeout_ms or 20 s, N times at random steps and seeds (bench/logger_faults.sh): how many runs
#     completed, replayed and equal an undisturbed run (in out/logger-faults).
#   bench/run.sh loss [--reps R] [--seed S] [--rates "0.01 0.05 0.20"] [--out DIR]
#     packet loss: how much longer a run takes when datagrams are dropped at random (floor: 5% loss at
#     most 3 times as long, median over seeds; exit 1 above it). Root; a private network namespace.
#   bench/run.sh python [--steps N] [--reps R] [--floor F] [--transports memq,udpm] [--out DIR]
#     components written in Python (ports of the paper's motivation and affordance predictor) against the
#     all-C++ run: steps per second and their ratio (floor 0.5 for the motivation; exit 1 below it), checksums.
#   bench/run.sh full [--runs N] [--steps S] [--jobs J] [--reps R] [--transports udpm,memq] [--floor F] [--out DIR]
#     a full machine: N runs at --jobs = cores over each transport, steps per second in all and per run, the
#     ratio udpm / memq (floor 0.8; exit 1 below it), and wake-ups per step of each kind of process.
#   bench/run.sh long [--lengths 10000,100000,1000000] [--seed S] [--kill PROCESS] [--kill-at STEP] [--no-replay]
#                     [--speed-reps R] [--system IMP|GOALS] [--out DIR]
#     runs of any length (IMP's, or the goals agent's): steps per second and every process's peak memory at each length, the log's size
#     beside what `afford experiment` said, the log replayed (the shortest run R times: its median steps/s is
#     the speed floor's base); with --kill, the longest run again with a process
#     killed past --kill-at and restarted: its catch-up time and weights. PASS/FAIL against the floors (exit 1).
#   bench/run.sh watch [--steps N] [--reps R] [--floor F] [--page local|remote] [--out DIR]
#     a run watched by afford watch's page (in headless Chromium here, or elsewhere: a client of its stream)
#     against it unwatched, over udpm: the same weights checksum, and steps per second at least F (0.95) of
#     unwatched (median of R pairs; exit 1 below).
#   bench/run.sh watch-hold [--idle 1000] [--dribble 100] [--stalled N] [--kept N] [--unread N] [--seconds S]
#                           [--port P] [--watcher-files N] [--afford PROGRAM] [--out DIR]
#     afford watch's page held by clients that do not finish (idle, dribbling a head, stalled, kept alive,
#     never reading the stream), reopened as the server closes them: GET / answered within 1 s throughout,
#     the watcher at most 64 MB above its start, a second watcher on the port refused (exit 1 otherwise).
#   bench/run.sh env [--worlds N] [--steps S] [--reps R] [--threads 1,2] [--grid G] [--out DIR]
#     afford.env's batched form (AffordVectorEnv: N worlds in one call of the C++ core) against N single
#     environments in a Python loop: environment steps per second, and the same rewards; what the check of an
#     action against the action space costs against a step, in each form.
#   bench/run.sh tune [--trials 24] [--workers 2] [--steps 6000] [--param KEY=SPEC ...] [--seed S] [--out DIR]
#     afford tune: a study by W workers sharing a journal file, with pruning and without: every trial finished,
#     none twice, the intrinsic steps pruning saves (floor 30%), the best trial replayed (exit 1 below a floor).
#   bench/run.sh tune-kill [--trials 20] [--workers 2] [--kills 30] [--journal-kills 10] [--claim-kills 5]
#                          [--unclaimed-kills 5] [--steps 20000] [--prune-warmup 0.5] [--seed S] [--out DIR]
#     afford tune's workers killed (SIGKILL) at random moments, inside the journal's lock, the study's claim and
#     between asking for a trial and claiming it too, and started again: no worker waits for good, every trial
#     counted once, none left running (exit 1 if not).
#   bench/run.sh goals-cost [--steps 6000] [--pairs 3] [--runs 8] [--jobs 2] [--rounds 3] [--parts goals,full]
#                           [--afford PROGRAM ...] [--out DIR]
#     a GOALS step beside an IMP step (pairs of runs, udpm and memq: medians, GOALS / IMP, floor 0.5 over udpm), and
#     --runs IMP runs at --jobs over udpm beside memq (median walls, udpm / memq, floor 0.61); several --afford
#     builds measured in turn, side by side (bench/goals_cost.py; exit 1 below a floor).
#   bench/run.sh goals-chain LOG [--first STEP] [--last STEP]
#     a GOALS run's log (kept with --keep-logs all): the links of a step's chain of messages, DECISION to the
#     next DECISION, as the logger heard them (medians, means, shares; bench/goals_chain.py).
#   bench/run.sh reproduction [--reps R] [--ext-reps K] [--jobs J] [--transport memq|udpm] [--out DIR] [WHAT ...]
#     the whole reproduction (scripts/reproduce.sh WHAT, default all, its report in DIR): wall time beside its
#     critical path and the share of the time the cores were busy.
#   bench/run.sh table [--steps N] [--seed S] [--experiment E] [--set KEY=VALUE ...]
#     the table world's cost a step in the environment process (bench/table_bench.cpp): a motor primitive's
#     physics, the camera's frame and its segmentation, in ms; physics steps an action; and the eye's verdict
#     on each action beside the simulation's, per action (JSON).
set -euo pipefail
cd "$(dirname "$0")/.."
[[ ${1:-} == table ]] && { shift; [[ -x build/bin/afford-table-bench ]] || scripts/setup.sh;
  exec build/bin/afford-table-bench "$@"; }
[[ ${1:-} == loss ]] && { shift; exec bench/loss.sh "$@"; }
[[ ${1:-} == logger-faults ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  exec bench/logger_faults.sh build out/logger-faults "$@"; }
[[ ${1:-} == watch ]] && { shift; exec bench/watch.sh "$@"; }
[[ ${1:-} == watch-hold ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh; exec /usr/bin/python3 bench/watch_hold.py "$@"; }
[[ ${1:-} == python ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  PYTHONPATH=build/python exec /usr/bin/python3 bench/python_bench.py "$@"; }
[[ ${1:-} == env ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  PYTHONPATH=build/python exec /usr/bin/python3 bench/env_bench.py "$@"; }
[[ ${1:-} == tune ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  PYTHONPATH=build/python exec /usr/bin/python3 bench/tune_bench.py "$@"; }
[[ ${1:-} == tune-kill ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  PYTHONPATH=build/python exec /usr/bin/python3 bench/tune_kill.py "$@"; }
[[ ${1:-} == reproduction ]] && { shift; exec /usr/bin/python3 bench/reproduction.py "$@"; }
[[ ${1:-} == long ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh; exec /usr/bin/python3 bench/long_run.py "$@"; }
[[ ${1:-} == goals-cost ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  exec /usr/bin/python3 bench/goals_cost.py "$@"; }
[[ ${1:-} == goals-chain ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  exec /usr/bin/python3 bench/goals_chain.py "$@"; }
[[ ${1:-} == full ]] && { shift; [[ -x build/bin/afford ]] || scripts/setup.sh;
  exec /usr/bin/python3 bench/full_machine.py "$@"; }
[[ -x build/bin/afford-bench ]] || scripts/setup.sh
exec build/bin/afford-bench "$@"

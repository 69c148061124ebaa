#!/usr/bin/env bash
# Regenerate the paper's results with the paper's repetition counts and write
# docs/results.md (our tables and figures beside the paper's).
#   scripts/reproduce.sh deterministic   base, late1, late2, late3: 10 intrinsic runs per
#                                        system, 10 tests of each scenario per run (Tables
#                                        1, 2, 4-6; Figures 5-10); about 5 min on 2 cores
#   scripts/reproduce.sh stochastic      stochastic, utility, forward-models, search-reduction
#                                        with the counts of their files (Table 7, 8;
#                                        Figures 11-14); about 2 min on 2 cores
#   scripts/reproduce.sh beyond          beyond the paper (issue 11): late1-3 with experience
#                                        replay and revisits, beside the paper's agent, and
#                                        random-tables (every system, 20 tables, with and without
#                                        them); (issue 12) attention, multi-step, world-size on
#                                        generated scenarios; (issue 28) base, late1 and
#                                        forward-models with the authors' eye (eye.fovea:
#                                        true_centre); about 12 min on 2 cores
#   scripts/reproduce.sh goals           the agent that sets its own goals (issue 41) beside IMP:
#                                        goals, goals-late1, goals-multi-step, goals-stochastic,
#                                        goals-forward-models, goals-random-tables; about 10 min
#   scripts/reproduce.sh all             all four
#   scripts/reproduce.sh NAME...         only these experiments (e.g. late3 utility)
# Environment: JOBS (runs at a time, default: cores), REPS and EXT_REPS (default: the
# paper's counts), OUT (default out/reproduce), KEEP_LOGS (all, first or none; default
# first: the logs of the first run of each system; all keeps every run's and test's log,
# which `afford explain LOG_ROOT` summarises), KEEP_CHECKPOINTS (all, first or none; default all),
# REPORT (default docs/results.md; its figures go to the folder of the same name without .md).
# Trained agents are stored by content in OUT/logs/agents and reused by the experiments that
# share them (REUSE=0 trains every one again). TRANSPORT (default memq) is how each job slot
# hosts the processes: memq, the same nodes in the afford process on LCM's in-process bus, each
# slot's kept from run to run (about 15 min for `all` on 2 cores); udpm, real processes over UDP
# multicast (the same results, about twice as long: docs/performance.md). The page is written from every experiment
# folder present under OUT, so parts may run at different times. An experiment with a
# failed run is still summarised and plotted; the script then exits with status 1.
set -euo pipefail
cd "$(dirname "$0")/.."
deterministic=(base late1 late2 late3)
stochastic=(stochastic utility forward-models search-reduction)
beyond=(late1-memory late2-memory late3-memory random-tables attention multi-step world-size
        base-true-centre late1-true-centre forward-models-true-centre)
goals=(goals goals-late1 goals-multi-step goals-stochastic goals-forward-models goals-random-tables)
[[ $# -eq 0 ]] && set -- deterministic
experiments=()
for what in "$@"; do
  case $what in
    deterministic) experiments+=("${deterministic[@]}") ;;
    stochastic) experiments+=("${stochastic[@]}") ;;
    beyond) experiments+=("${beyond[@]}") ;;
    goals) experiments+=("${goals[@]}") ;;
    all) experiments+=("${deterministic[@]}" "${stochastic[@]}" "${beyond[@]}" "${goals[@]}") ;;
    *)
      case " ${deterministic[*]} ${stochastic[*]} ${beyond[*]} ${goals[*]} " in
        *" $what "*) experiments+=("$what") ;;
        *) echo "usage: scripts/reproduce.sh deterministic|stochastic|beyond|goals|all|EXPERIMENT... (unknown: $what)" >&2; exit 2 ;;
      esac ;;
  esac
done
# Experiments that share their intrinsic runs train each agent once (the store in
# $out/logs/agents): forward-models keeps the checkpoint after 4000 actions that the
# others do not, so it goes first in the queue and stochastic, utility and search-reduction
# take its agents (goals-forward-models likewise for goals-stochastic).
ordered=()
for exp in "${experiments[@]}"; do [[ $exp == *forward-models ]] && ordered+=("$exp"); done
for exp in "${experiments[@]}"; do [[ $exp != *forward-models ]] && ordered+=("$exp"); done
experiments=("${ordered[@]}")
scripts/setup.sh
out=${OUT:-out/reproduce}
mkdir -p "$out"
start=$SECONDS
prefix=$(date +%Y%m%d-%H%M%S)
# One queue for them all (afford experiment --plan): their runs and tests share the job slots, and an
# agent two of them share is trained once, by the first listed that needs it.
plan=$out/plan.yaml
echo "# written by scripts/reproduce.sh $*" > "$plan"
for exp in "${experiments[@]}"; do
  rm -rf "${out:?}/$exp"
  line=$exp
  case " ${deterministic[*]} late1-memory late2-memory late3-memory base-true-centre late1-true-centre " in
    *" $exp "*) line+=" --system all --extrinsic-reps ${EXT_REPS:-10}" ;;
    *) [[ -n ${EXT_REPS:-} && $exp != stochastic && $exp != random-tables ]] && line+=" --extrinsic-reps $EXT_REPS" ;;
  esac
  echo "- $line" >> "$plan"
done
args=(--jobs "${JOBS:-$(nproc)}" --keep-logs "${KEEP_LOGS:-first}" --keep-checkpoints "${KEEP_CHECKPOINTS:-all}"
      --out "$out" --log-root "$out/logs" --run-prefix "$prefix" --transport "${TRANSPORT:-memq}")
[[ ${REUSE:-1} == 0 ]] && args+=(--no-reuse-agents)
[[ -n ${REPS:-} ]] && args+=(--reps "$REPS")
status=0
queued=$SECONDS
build/bin/afford experiment --plan "$plan" "${args[@]}" || status=$?
queued=$((SECONDS - queued))
for exp in "${experiments[@]}"; do
  if [[ -f $out/$exp/summary.json ]]; then build/bin/afford plot "$out/$exp"; fi
done
dirs=()
for exp in "${deterministic[@]}" "${stochastic[@]}" "${beyond[@]}" "${goals[@]}"; do
  [[ -f $out/$exp/summary.json ]] && dirs+=("$out/$exp")
done
# The report states what each folder ran (read from its summary.json); the note says how they were made.
invocation="scripts/reproduce.sh $*"
for var in REPS EXT_REPS JOBS; do if [[ -n ${!var:-} ]]; then invocation="$var=${!var} $invocation"; fi; done
note="Regenerated by \`scripts/reproduce.sh\` from the experiment folders under \`$out\` (the last invocation: \`$invocation\`, on $(nproc) cores, its experiments side by side in one queue of job slots: each one's wall time runs from the queue's start to its own end, and the row \"all\" is the queue's). Unless REPS or EXT_REPS are set, it runs the paper's counts: for the deterministic experiments 10 intrinsic runs per system (seeds from 1) and 10 tests of every scenario with each trained agent; for the stochastic ones, the counts of their experiment files. The world follows the authors' code: continuous positions, shapes drawn from their real centres, late objects at random free places, the eye's window placed as theirs ([model.md](model.md#positions))."
[[ -f docs/results-pixel.md ]] && note+=" The same reproduction in the earlier pixel world is kept in [results-pixel.md](results-pixel.md)."
report=${REPORT:-docs/results.md}
build/bin/afford report "${dirs[@]}" --out "$report" --figures "${report%.md}" --note "$note" --wall-seconds "$queued"
echo "$report written; this invocation took $((SECONDS - start)) s"
if [[ $status -ne 0 ]]; then
  echo "the queue exited with status $status: the experiments it names above had failed runs (see their summary.json failed_runs)" >&2
  exit 1
fi

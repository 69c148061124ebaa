#!/usr/bin/env bash
# Submit an afford experiment to a Slurm cluster: a job array of N shards
# (`afford experiment ... --shard i/N`, one job per shard, each with the cores
# Slurm gives it), then a job that runs once they have all ended (afterany) and merges
# their folders into the whole experiment's (`afford merge`). docs/cluster.md.
#
# With --tune, a study instead (`afford tune`): N array tasks, each a worker of the one study in --out (they
# share its journal file, so the file system must be one every node sees), then a job that writes its report.
#
# Usage: scripts/slurm-submit.sh [options] -- EXPERIMENT-ARGUMENTS...
#        scripts/slurm-submit.sh --tune --out DIR [options] -- TUNE-ARGUMENTS...
#   --shards N        how many shards (array tasks; with --tune, workers); default 4
#   --out DIR         the merged experiment's folder; shards go to DIR/shard-<i>,
#                     the jobs' scripts and output to DIR/slurm; default out/<experiment>-<stamp>
#   --log-root DIR    the runs' logs and stored agents, on a file system every node sees; default logs
#   --run-prefix P    the run ids' first part; default the date-time
#   --afford PATH     the afford executable; default build/bin/afford of this tree
#   --sbatch ARGS     more sbatch options for every job (quoted), e.g. "--partition=cpu --cpus-per-task=8 --time=2:00:00"
#   --wait            wait until the merge (report) job has ended, and exit with its status
#   --tune            the arguments are `afford tune`'s (an experiment, --param ..., --trials ...; not --out)
# EXPERIMENT-ARGUMENTS are what `afford experiment` takes (a name or --config FILE,
# --system, --reps, --set, ...), but not --out, --log-root, --run-prefix or --shard.
# Without --jobs, each shard runs ${SLURM_CPUS_PER_TASK:-1} runs at a time.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"

shards=4 out="" log_root=logs prefix="" afford="$here/build/bin/afford" wait=0 tune=0
sbatch_args=()
die() { echo "slurm-submit: $*" >&2; exit 2; }
while (($#)); do
  case "$1" in
    --shards) shards="${2:?--shards needs a number}"; shift 2 ;;
    --out) out="${2:?--out needs a folder}"; shift 2 ;;
    --log-root) log_root="${2:?--log-root needs a folder}"; shift 2 ;;
    --run-prefix) prefix="${2:?--run-prefix needs a value}"; shift 2 ;;
    --afford) afford="${2:?--afford needs a path}"; shift 2 ;;
    --sbatch) read -r -a more <<<"${2:?--sbatch needs options}"; sbatch_args+=("${more[@]}"); shift 2 ;;
    --wait) wait=1; shift ;;
    --tune) tune=1; shift ;;
    --) shift; break ;;
    -h|--help) awk 'NR > 1 && /^#/ { sub(/^# ?/, ""); print; next } NR > 1 { exit }' "$0"; exit 0 ;;
    *) die "unknown option '$1' (the experiment's arguments come after --)" ;;
  esac
done
(($#)) || die "give the experiment's arguments after --, e.g. -- base --system IMP --reps 10"
[[ "$shards" =~ ^[1-9][0-9]*$ ]] || die "--shards must be a positive number, not '$shards'"
[[ -x "$afford" ]] || die "no afford executable at $afford (build it: scripts/setup.sh, or give --afford)"
command -v sbatch >/dev/null || die "no sbatch on PATH: is this a Slurm login node?"
wait_arg=(); ((wait)) && wait_arg=(--wait)
# Submit the job array of script $1 (its tasks: $2, their output: $3), then script $4 once they have all ended
# (afterany; it makes $5); exit with the second sbatch's status (with --wait, the job's).
submit_array_then() {
  local array after status
  array=$(sbatch --parsable --chdir="$PWD" --array="0-$((shards - 1))" "${sbatch_args[@]}" "$1")
  array="${array%%;*}"
  echo "slurm-submit: $2: job array $array (${shards} tasks), output in $3"
  set +e
  after=$(sbatch --parsable --chdir="$PWD" --dependency="afterany:$array" "${wait_arg[@]}" "${sbatch_args[@]}" "$4")
  status=$?
  set -e
  echo "slurm-submit: $5 job ${after%%;*}; watch with: squeue -j $array,${after%%;*}"
  exit $status
}
if ((tune)); then
  [[ -n "$out" ]] || die "--tune needs --out: the study's folder, on a file system every node sees"
  for a in "$@"; do
    case "$a" in --out|--out=*) die "give the study's folder as slurm-submit.sh's --out, not after --" ;; esac
  done
  mkdir -p "$out/slurm"
  out="$(cd "$out" && pwd)" afford="$(cd "$(dirname "$afford")" && pwd)/$(basename "$afford")"
  args="$(printf ' %q' "$@")"
  cat >"$out/slurm/worker.sbatch" <<SCRIPT
#!/usr/bin/env bash
#SBATCH --job-name=afford-tune
#SBATCH --output=$out/slurm/worker-%a.out
# Worker \$SLURM_ARRAY_TASK_ID of $shards of the study \`afford tune$args\` in $out (scripts/slurm-submit.sh).
set -euo pipefail
exec $(printf '%q' "$afford") tune$args --out $(printf '%q' "$out")
SCRIPT
  cat >"$out/slurm/report.sbatch" <<SCRIPT
#!/usr/bin/env bash
#SBATCH --job-name=afford-tune-report
#SBATCH --output=$out/slurm/report.out
# The report of the study in $out, once its workers have ended (scripts/slurm-submit.sh).
set -euo pipefail
exec $(printf '%q' "$afford") tune --out $(printf '%q' "$out") --report
SCRIPT
  echo "slurm-submit: report: a job after the workers; the study's report will be $out/report.md"
  submit_array_then "$out/slurm/worker.sbatch" workers "$out/slurm/worker-<i>.out" "$out/slurm/report.sbatch" report
fi

jobs_given=0
for a in "$@"; do
  case "$a" in
    --out|--out=*|--log-root|--log-root=*|--run-prefix|--run-prefix=*|--shard|--shard=*|--resume)
      die "'$a' is for slurm-submit.sh itself (or not for a submitted experiment): see --help" ;;
    --jobs|--jobs=*|-j|-j*) jobs_given=1 ;;
  esac
done

[[ -n "$prefix" ]] || prefix="$(date +%Y%m%d-%H%M%S)"
name="$1"; [[ "$name" == -* ]] && name=experiment
name="$(basename "${name%.yaml}")"
[[ -n "$out" ]] || out="out/$name-$prefix"
mkdir -p "$out/slurm" "$log_root"
out="$(cd "$out" && pwd)" log_root="$(cd "$log_root" && pwd)" afford="$(cd "$(dirname "$afford")" && pwd)/$(basename "$afford")"
[[ -e "$out/experiment.json" ]] && die "$out holds an experiment already: choose another --out"

args="$(printf ' %q' "$@")"
jobs_arg=""; ((jobs_given)) || jobs_arg=' --jobs "${SLURM_CPUS_PER_TASK:-1}"'
cat >"$out/slurm/shard.sbatch" <<SCRIPT
#!/usr/bin/env bash
#SBATCH --job-name=afford-$name
#SBATCH --output=$out/slurm/shard-%a.out
# Shard \$SLURM_ARRAY_TASK_ID of $shards of \`afford experiment$args\` (scripts/slurm-submit.sh).
set -euo pipefail
exec $(printf '%q' "$afford") experiment$args$jobs_arg --shard "\$SLURM_ARRAY_TASK_ID/$shards" \\
  --run-prefix $(printf '%q' "$prefix") --out "$out/shard-\$SLURM_ARRAY_TASK_ID" --log-root $(printf '%q' "$log_root") \\
  --progress lines
SCRIPT
shard_dirs=""
for ((i = 0; i < shards; i++)); do shard_dirs+=" $(printf '%q' "$out/shard-$i")"; done
cat >"$out/slurm/merge.sbatch" <<SCRIPT
#!/usr/bin/env bash
#SBATCH --job-name=afford-$name-merge
#SBATCH --output=$out/slurm/merge.out
# Merge the $shards shards of \`afford experiment$args\` (scripts/slurm-submit.sh).
set -euo pipefail
exec $(printf '%q' "$afford") merge$shard_dirs --out $(printf '%q' "$out")
SCRIPT

echo "slurm-submit: merge: a job after them all; the experiment's summary will be $out/summary.json"
submit_array_then "$out/slurm/shard.sbatch" shards "$out/slurm/shard-<i>.out" "$out/slurm/merge.sbatch" merge

#!/usr/bin/env bash
# slurm.sh: farm a raylab render out to Slurm as a job array, then merge it.
#
# Usage:
#   tools/farm/slurm.sh --tiles N [OPTIONS] -o OUT.png|OUT.exr -- RENDER_ARGS...
#   tools/farm/slurm.sh --sample-chunks K --spp S [--tiles N] [OPTIONS] -o OUT -- RENDER_ARGS...
#   tools/farm/slurm.sh --frames A..B [OPTIONS] -o OUT-%04d.png -- RENDER_ARGS...
#
# Modes (RENDER_ARGS are passed to `raylab render` as they are):
#   --tiles N           task i renders `--tile i/N` into WORKDIR/part-i.exr; a merge job
#                       (--dependency=afterok on the array) runs `raylab merge` into OUT.
#   --sample-chunks K --spp S
#                       task i renders `--spp S --samples A..B`, chunk i of K equal sample
#                       ranges (give --spp to the tool, not in RENDER_ARGS; in other modes
#                       the tool's --spp is simply passed on). With --tiles N as well there
#                       are N*K tasks: task i is tile i%N of chunk i/N.
#   --frames A..B       task i renders `--frames A+i` to the -o pattern (a frame-number field
#                       such as %04d); no merge job, the tool checks every frame at the end.
#
# Options:
#   --retries R         each task retries a render that fails or is killed by a signal up to
#                       R times (default 2); the tool also resubmits tasks that end without
#                       success (e.g. an `scancel JOB_3`) up to R times.
#   --workdir DIR       parts, job scripts, logs/ and status/ (default: OUT's directory,
#                       `NAME.farm`); must be on a file system every node sees. Its old
#                       parts and status are removed first.
#   --raylab PATH       the raylab binary, as the nodes see it (default: raylab on PATH,
#                       else target/release/raylab of this checkout)
#   --cpus-per-task C   Slurm CPUs per task, also passed as `raylab --threads C`
#                       unless RENDER_ARGS has --threads (default 1)
#   --partition P       Slurm partition (default: the cluster's default)
#   --sbatch-opt OPT    extra sbatch option, e.g. --sbatch-opt=--time=1:00:00 (repeatable)
#   --name NAME         Slurm job name (default raylab-farm)
#   --poll SEC          seconds between squeue polls (default 2)
#   -h, --help          this help
#
# How it works: every array task runs WORKDIR/task.sh, which retries the render and
# writes WORKDIR/status/task-ID.ok on success (task-ID.failed when it gives up). The
# merge job (WORKDIR/merge.sh) refuses to run unless every .ok exists. The tool polls
# `squeue` (no sacct: it needs slurmdbd) and prints `tasks: 2 running, 1 pending, 1 done`.
# When the array ends with tasks lacking an .ok and no .failed (cancelled, node lost,
# time limit), afterok can never fire, so the tool resubmits just those ids
# (`sbatch --array=3`) with a fresh merge job depending on them.
#
# Exit: 0 when OUT (every frame in --frames mode) is written; 1 with one line on stderr
# when a task fails for good, tasks stay incomplete after R resubmissions or the merge
# fails; 2 on bad arguments; 130/143 when interrupted (the submitted jobs are cancelled).
#
# Example (4 tiles on the default partition, 2 CPUs each):
#   tools/farm/slurm.sh --tiles 4 --cpus-per-task 2 -o box.png -- --integrator path --spp 256
set -euo pipefail

die() { echo "slurm.sh: $*" >&2; exit 1; }
usage_error() { echo "slurm.sh: $* (see --help)" >&2; exit 2; }
usage() { sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; }

tiles=1 chunks=1 spp="" frames="" retries=2 workdir="" raylab="" cpus=1 partition=""
name=raylab-farm poll=2 out="" sbatch_extra=() render_args=()
while [ $# -gt 0 ]; do
  opt=$1
  # Accept both `--opt value` and `--opt=value`.
  if [[ $opt == --*=* ]]; then val=${opt#*=}; opt=${opt%%=*}; set -- "$opt" "$val" "${@:2}"; fi
  case $opt in
    -h|--help) usage; exit 0 ;;
    --) shift; render_args=("$@"); break ;;
  esac
  [ $# -ge 2 ] || usage_error "$opt needs a value"
  case $opt in
    --tiles) tiles=$2 ;;
    --sample-chunks) chunks=$2 ;;
    --spp) spp=$2 ;;
    --frames) frames=$2 ;;
    --retries) retries=$2 ;;
    --workdir) workdir=$2 ;;
    --raylab) raylab=$2 ;;
    --cpus-per-task) cpus=$2 ;;
    --partition) partition=$2 ;;
    --sbatch-opt) sbatch_extra+=("$2") ;;
    --name) name=$2 ;;
    --poll) poll=$2 ;;
    -o|--output) out=$2 ;;
    *) usage_error "unknown option $opt" ;;
  esac
  shift 2
done

is_uint() { [[ $1 =~ ^[0-9]+$ ]]; }
for v in tiles chunks retries cpus; do is_uint "${!v}" || usage_error "--${v} must be a number"; done
[ "$tiles" -ge 1 ] && [ "$chunks" -ge 1 ] && [ "$cpus" -ge 1 ] || usage_error "counts must be at least 1"
[ -n "$out" ] || usage_error "-o OUT is required"
[[ $poll =~ ^[0-9]+(\.[0-9]+)?$ ]] || usage_error "--poll must be a number of seconds"
for a in "${render_args[@]}"; do
  case $a in
    --tile|--tile=*|--samples|--samples=*|--frames|--frames=*|-o|--output|--output=*)
      usage_error "$a is set by the tool: leave it out of RENDER_ARGS" ;;
  esac
done
has_arg() { local a; for a in "${render_args[@]}"; do [[ $a == "$1" || $a == "$1="* ]] && return 0; done; return 1; }

# frame_file PATTERN F: PATTERN's first %d / %0Nd field replaced by F, as raylab does.
frame_file() {
  local pre=${1%%\%*} rest=${1#*%} digits
  digits=${rest%%[!0-9]*}
  printf '%s%0*d%s' "$pre" "${digits:-0}" "$2" "${rest#"${digits}d"}"
}

if [ -n "$frames" ]; then
  [ "$tiles" -eq 1 ] && [ "$chunks" -eq 1 ] || usage_error "--frames cannot be combined with --tiles/--sample-chunks"
  if [[ $frames =~ ^([0-9]+)\.\.([0-9]+)$ ]]; then first=${BASH_REMATCH[1]} end=${BASH_REMATCH[2]}
  elif is_uint "$frames"; then first=$frames end=$((frames + 1))
  else usage_error "--frames takes A..B"; fi
  [ "$end" -gt "$first" ] || usage_error "--frames A..B needs B > A"
  [[ $out =~ %[0-9]*d ]] || usage_error "--frames needs a frame-number field in -o, e.g. out-%04d.png"
  mode=frames ntasks=$((end - first))
else
  [ "$tiles" -gt 1 ] || [ "$chunks" -gt 1 ] || usage_error "give --tiles N, --sample-chunks K or --frames A..B"
  [[ $out == *.png || $out == *.exr ]] || usage_error "-o must be .png or .exr"
  if [ "$chunks" -gt 1 ]; then
    is_uint "$spp" && [ "$spp" -ge "$chunks" ] || usage_error "--sample-chunks K needs --spp S with S >= K"
  fi
  mode=parts ntasks=$((tiles * chunks))
  first=0 end=0
fi
if [ -n "$spp" ]; then
  ! has_arg --spp || usage_error "--spp is given twice (to the tool and in RENDER_ARGS)"
  # With --sample-chunks each task adds it next to its --samples.
  [ "$chunks" -gt 1 ] || render_args+=(--spp "$spp")
fi
threads=$cpus
! has_arg --threads || threads=""

# Absolute paths: the jobs may start in another directory on another node.
abspath() { local d; d=$(dirname -- "$1"); mkdir -p -- "$d"; printf '%s/%s' "$(cd -- "$d" && pwd -P)" "$(basename -- "$1")"; }
if [ -z "$raylab" ]; then
  raylab=$(command -v raylab || true)
  [ -n "$raylab" ] || raylab="$(dirname -- "$0")/../../target/release/raylab"
fi
[ -x "$raylab" ] || usage_error "raylab binary not found at $raylab (use --raylab PATH)"
raylab=$(abspath "$raylab")
out=$(abspath "$out")
if [ -z "$workdir" ]; then
  # out.png -> out.farm, frame-%04d.png -> frame.farm
  base=$(basename -- "$out" | sed -E 's/\.[^.]*$//; s/[-_.]?%[0-9]*d//')
  workdir="$(dirname -- "$out")/$base.farm"
fi
mkdir -p -- "$workdir"
workdir=$(cd -- "$workdir" && pwd -P)
command -v sbatch >/dev/null && command -v squeue >/dev/null || die "sbatch/squeue not found: is this a Slurm login node?"

# A fresh start: parts, checkpoints or .ok files of an earlier render would be mixed in.
rm -rf -- "$workdir/status" "$workdir/logs"
rm -f -- "$workdir"/part-*.exr "$workdir"/.part-*.raylab-checkpoint
mkdir -p -- "$workdir/status" "$workdir/logs"

# The settings shared by the job scripts, as bash assignments at their top (sbatch copies
# a job's script to the node's spool: it cannot source a file beside itself).
settings=$(
  echo '#!/usr/bin/env bash'
  echo "# Written by tools/farm/slurm.sh on $(date -u +%FT%TZ)."
  echo '# shellcheck disable=SC2034 # (settings shared by task.sh and merge.sh)'
  printf 'raylab=%q workdir=%q out=%q mode=%q ntasks=%q\n' "$raylab" "$workdir" "$out" "$mode" "$ntasks"
  printf 'tiles=%q chunks=%q spp=%q first=%q retries=%q threads=%q\n' "$tiles" "$chunks" "$spp" "$first" "$retries" "$threads"
  if [ ${#render_args[@]} -gt 0 ]; then printf 'render_args=(%s)\n' "$(printf '%q ' "${render_args[@]}")"
  else echo 'render_args=()'; fi
)

# The array task: one render, retried. Kept in the work dir so a task can be rerun by hand:
# SLURM_ARRAY_TASK_ID=3 bash task.sh
{ echo "$settings"; cat; } > "$workdir/task.sh" <<'EOF'
set -uo pipefail
id=${SLURM_ARRAY_TASK_ID:?not an array task}
args=("${render_args[@]}")
if [ "$mode" = frames ]; then
  frame=$((first + id)) target=$out
  args+=(--frames "$frame")
  # Where raylab writes this frame (its first %d / %0Nd field), to clear a stale one.
  pre=${out%%\%*} rest=${out#*%}; digits=${rest%%[!0-9]*}
  printf -v stale '%s%0*d%s' "$pre" "${digits:-0}" "$frame" "${rest#"${digits}d"}"
else
  tile=$((id % tiles)) chunk=$((id / tiles)) target=$workdir/part-$id.exr stale=$target
  [ "$tiles" -gt 1 ] && args+=(--tile "$tile/$tiles")
  [ "$chunks" -gt 1 ] && args+=(--spp "$spp" --samples "$((chunk * spp / chunks))..$(((chunk + 1) * spp / chunks))")
fi
[ -n "$threads" ] && args+=(--threads "$threads")
rm -f -- "$workdir/status/task-$id.ok" "$workdir/status/task-$id.failed"

# Slurm stops a job (scancel, time limit) by sending SIGTERM to its processes; raylab then
# saves its samples and exits 143. Such a job must not retry (the retry would be killed
# after KillWait anyway): the tool resubmits it. The batch shell is not always signalled,
# so also ask slurmctld whether this job is still RUNNING.
# (Not forwarded to raylab: it has its own, and a second signal makes it abort unsaved.)
stopping=0
trap 'stopping=1' TERM INT
job_ending() {
  [ "$stopping" = 1 ] && return 0
  local state
  # (This element by ARRAYJOB_TASK: SLURM_JOB_ID of one element may be the array's id.)
  state=$(squeue -h -j "${SLURM_ARRAY_JOB_ID:-0}_$id" -o %T 2>/dev/null) || return 1
  [ -n "$state" ] && [ "$state" != RUNNING ]
}

rc=1
for ((attempt = 1; attempt <= retries + 1; attempt++)); do
  # A part written by an interrupted attempt holds fewer samples: never leave it behind.
  # (raylab's .NAME.raylab-checkpoint stays, so the next attempt resumes bit-identically.)
  rm -f -- "$stale"
  echo "task $id attempt $attempt on $(hostname -s) at $(date +%T): raylab render ${args[*]} -o $target"
  "$raylab" render "${args[@]}" -o "$target" &
  pid=$!
  # wait returns early when a trapped signal arrives: wait again for the real status.
  wait "$pid"; rc=$?
  while kill -0 "$pid" 2>/dev/null; do wait "$pid"; rc=$?; done
  pid=
  if [ "$rc" = 0 ]; then
    touch "$workdir/status/task-$id.ok"
    echo "task $id done at $(date +%T)"
    exit 0
  fi
  if [ "$rc" = 2 ]; then
    echo "task $id: raylab refused its arguments (exit 2): not retrying"
    break
  fi
  if job_ending; then
    echo "task $id: the job is being stopped (raylab exit $rc): not retrying"
    exit "$rc"
  fi
  echo "task $id: attempt $attempt failed with exit $rc"
done
echo "$rc" > "$workdir/status/task-$id.failed"
exit "$rc"
EOF

# The merge job: only on a complete set of .ok files, never on whatever parts exist.
{ echo "$settings"; cat; } > "$workdir/merge.sh" <<'EOF'
set -euo pipefail
missing=() parts=()
for ((i = 0; i < ntasks; i++)); do
  [ -e "$workdir/status/task-$i.ok" ] || missing+=("$i")
  parts+=("$workdir/part-$i.exr")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "merge: refusing to merge, no .ok for task(s) ${missing[*]}" >&2
  exit 1
fi
rm -f -- "$workdir/status/merge.ok"
"$raylab" merge "${parts[@]}" -o "$out"
touch "$workdir/status/merge.ok"
EOF
chmod +x "$workdir/task.sh" "$workdir/merge.sh"

jobs_submitted=()
cancel_all() { # (bounded: scancel waits long for a controller that is down)
  [ ${#jobs_submitted[@]} -eq 0 ] || timeout 20 scancel "${jobs_submitted[@]}" 2>/dev/null || true
}
trap 'echo "slurm.sh: interrupted: cancelling ${jobs_submitted[*]:-nothing}" >&2; cancel_all; exit 130' INT
trap 'echo "slurm.sh: terminated: cancelling ${jobs_submitted[*]:-nothing}" >&2; cancel_all; exit 143' TERM

sbatch_common=(--parsable --job-name="$name" --chdir="$PWD" --cpus-per-task="$cpus")
[ -z "$partition" ] || sbatch_common+=(--partition="$partition")
sbatch_common+=("${sbatch_extra[@]}")

submit() { # submit VAR SBATCH_ARGS...: sets VAR to the new job's id
  local var=$1 id
  shift
  id=$(sbatch "${sbatch_common[@]}" "$@" 2> "$workdir/logs/.sbatch.err") ||
    die "sbatch ${sbatch_common[*]} $* failed: $(tail -n 1 "$workdir/logs/.sbatch.err")"
  id=${id%%;*}
  jobs_submitted+=("$id")
  printf -v "$var" '%s' "$id"
}

# queue_states JOB: the states of JOB's (array) jobs still known to squeue, one a line.
# squeue forgets finished jobs after MinJobAge and then says "Invalid job id": also done.
queue_states() {
  local err tries=0
  while :; do
    if states=$(squeue -h -r -j "$1" -o %T 2> "$workdir/logs/.squeue.err"); then return 0; fi
    err=$(cat "$workdir/logs/.squeue.err")
    if [[ $err == *"Invalid job id"* ]]; then states=""; return 0; fi
    tries=$((tries + 1))
    [ "$tries" -lt 30 ] || die "squeue keeps failing: $err"
    sleep "$poll"
  done
}
count_files() { find "$workdir/status" -name "task-*.$1" | wc -l; }

# wait_job JOB LABEL: poll until JOB has left the queue, printing progress when it changes.
wait_job() {
  local last="" line running pending failed
  while :; do
    queue_states "$1"
    running=$(grep -cE '^(RUNNING|COMPLETING|CONFIGURING)$' <<< "$states" || true)
    pending=$(grep -cE '^(PENDING|REQUEUED|RESIZING|SUSPENDED)$' <<< "$states" || true)
    if [ "$2" = tasks ]; then
      line="tasks: $running running, $pending pending, $(count_files ok) done"
      failed=$(count_files failed)
      [ "$failed" = 0 ] || line+=", $failed failed"
    else
      line=${states:-finished}
      line="$2 job $1: ${line//$'\n'/ }"
      line=${line,,}
    fi
    [ "$line" = "$last" ] || echo "$line"
    last=$line
    [ -n "$states" ] || return 0
    sleep "$poll"
  done
}

ids="0-$((ntasks - 1))"
round=0
merge_job="" array_job=""
echo "farming $ntasks task(s) ($mode) in $workdir"
while :; do
  submit array_job --array="$ids" --output="$workdir/logs/task-%A_%a.out" "$workdir/task.sh"
  echo "submitted array job $array_job (tasks $ids)"
  if [ "$mode" = parts ]; then
    # kill-on-invalid-dep: if a task is cancelled, afterok can never fire and the merge job
    # is cancelled instead of pending forever; we then submit a new one below.
    submit merge_job --dependency="afterok:$array_job" --kill-on-invalid-dep=yes \
      --output="$workdir/logs/merge-%j.out" "$workdir/merge.sh"
    echo "submitted merge job $merge_job (afterok:$array_job)"
  fi
  wait_job "$array_job" tasks
  missing=() failed=()
  for ((i = 0; i < ntasks; i++)); do
    [ -e "$workdir/status/task-$i.ok" ] && continue
    missing+=("$i")
    [ -e "$workdir/status/task-$i.failed" ] && failed+=("$i")
  done
  [ ${#missing[@]} -gt 0 ] || break
  [ -z "$merge_job" ] || scancel "$merge_job" 2>/dev/null || true
  if [ ${#failed[@]} -gt 0 ]; then
    i=${failed[0]}
    log=$(ls -t "$workdir"/logs/task-*_"$i".out | head -n 1)
    why=$(grep -h '^error' "$log" | tail -n 1 || true)
    die "task(s) ${failed[*]} failed for good; task $i: raylab exit $(cat "$workdir/status/task-$i.failed")${why:+ ($why)}; log: $log"
  fi
  round=$((round + 1))
  [ "$round" -le "$retries" ] || die "task(s) ${missing[*]} still unfinished after $retries resubmission(s) (cancelled or killed?); logs in $workdir/logs"
  ids=$(IFS=,; echo "${missing[*]}")
  echo "array job $array_job ended without task(s) $ids (cancelled, killed or lost): resubmitting them ($round/$retries)"
done

if [ "$mode" = parts ]; then
  wait_job "$merge_job" merge
  if [ ! -e "$workdir/logs/merge-$merge_job.out" ]; then
    # Cancelled before it ran although every task has its .ok (a task cancelled just
    # after it finished fails afterok): merge now, without a dependency.
    submit merge_job --output="$workdir/logs/merge-%j.out" "$workdir/merge.sh"
    echo "merge job was cancelled unrun: submitted merge job $merge_job"
    wait_job "$merge_job" merge
  fi
  [ -e "$workdir/status/merge.ok" ] && [ -e "$out" ] ||
    die "merge job $merge_job did not write $out; log: $workdir/logs/merge-$merge_job.out"
  echo "done: $out (parts and logs in $workdir)"
else
  # The "done" check: every frame has its .ok and its file.
  for ((f = first; f < end; f++)); do
    file=$(frame_file "$out" "$f")
    [ -s "$file" ] || die "frame $f has an .ok but no file $file"
  done
  echo "done: $ntasks frame(s) $(frame_file "$out" "$first") .. $(frame_file "$out" $((end - 1)))"
fi

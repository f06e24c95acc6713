#!/usr/bin/env bash
# End-to-end test of tools/farm/slurm.sh on a real one-node Slurm cluster on localhost.
#
#   bash .ci/slurm-test.sh [--then CMD ARGS...]
#
# Needs root (it starts munged, slurmctld and slurmd). Installs Debian's slurm-wlm and
# munge when missing; exits 0 with "skipping the Slurm test" only if that install fails.
# RAYLAB=path/to/raylab picks the binary (default target/release/raylab, built with
# `cargo build --release --locked` when missing). Everything (munge key and socket,
# slurm.conf, state, spool, logs, renders) lives in one temp dir, on private ports, and
# is torn down on exit, failure or not. --then runs CMD with the cluster still up
# (SLURM_CONF exported) after the tests, e.g. `--then tools/farm_scaling.sh`.
#
# a. 4 tiles of the lab box; one array element is cancelled (scancel JOB_2) while it
#    renders: the tool must resubmit it and merge only afterwards. The PNG and an EXR
#    merge of the parts must be byte-identical to one `raylab render`.
# b. an 8-frame turntable of the bunny (--frames 0..8), each frame byte-identical to a
#    single `raylab render --frames 0..8`.
# c. 2 sample chunks of --spp 8, byte-identical to one render.
# Before the cluster starts, tools/farm/k8s_local.py runs deploy/k8s/raylab-tiles-job.yaml
# locally (the Kubernetes Indexed Job's task-id contract), also byte-compared.
set -euo pipefail
cd "$(dirname "$0")/.."

then_cmd=()
if [ "${1:-}" = --then ]; then shift; then_cmd=("$@"); [ $# -gt 0 ] || { echo "--then needs a command" >&2; exit 2; }
elif [ $# -gt 0 ]; then echo "usage: bash .ci/slurm-test.sh [--then CMD ARGS...]" >&2; exit 2; fi

fail() { echo "SLURM TEST FAILED: $*" >&2; exit 1; }
step() { echo "== $*"; }

RAYLAB=${RAYLAB:-target/release/raylab}
if [ ! -x "$RAYLAB" ]; then
  step "building raylab"
  cargo build --release --locked
fi
RAYLAB=$(cd "$(dirname "$RAYLAB")" && pwd)/$(basename "$RAYLAB")
export RAYLAB # for --then
bunny=$PWD/assets/models/stanford-bunny.obj
[ -f "$bunny" ] || fail "$bunny is missing"

step "k8s: the Kubernetes Indexed Job manifest, run locally (tools/farm/k8s_local.py)"
python3 tools/farm/k8s_local.py --raylab "$RAYLAB" deploy/k8s/raylab-tiles-job.yaml ||
  fail "tools/farm/k8s_local.py: the manifest's tiles do not merge into the single render"

[ "$(id -u)" = 0 ] || fail "must run as root (it installs packages, starts munged, slurmctld and slurmd)"
if ! command -v slurmctld >/dev/null || ! command -v slurmd >/dev/null ||
  ! command -v sbatch >/dev/null || ! command -v munged >/dev/null; then
  step "installing slurm-wlm and munge"
  if ! { export DEBIAN_FRONTEND=noninteractive && apt-get update -qq &&
    apt-get install -y -qq --no-install-recommends slurm-wlm munge; }; then
    echo "skipping the Slurm test: cannot install slurm-wlm/munge"
    exit 0
  fi
fi

tmp=$(mktemp -d /tmp/raylab-slurm-test.XXXXXX)
chmod 755 "$tmp" # munged wants its socket's directory searchable by all
daemons=() farm_pid=""
cleanup() {
  local rc=$? pid i
  trap - EXIT INT TERM
  set +e
  # A farm run still in the background (test a) cancels its jobs on SIGTERM.
  [ -z "$farm_pid" ] || { kill -TERM "$farm_pid" 2>/dev/null && wait "$farm_pid" 2>/dev/null; }
  if [ ${#daemons[@]} -gt 0 ]; then
    # Cancel what is left, let slurmd reap it, then stop the daemons we started.
    if [ -n "${SLURM_CONF:-}" ] && squeue -h >/dev/null 2>&1; then
      squeue -h -o %A | sort -u | xargs -r scancel
      for ((i = 0; i < 50; i++)); do [ -z "$(squeue -h 2>/dev/null)" ] && break; sleep 0.2; done
    fi
    for ((i = ${#daemons[@]} - 1; i >= 0; i--)); do kill -TERM "${daemons[i]}" 2>/dev/null; done
    for pid in "${daemons[@]}"; do
      for ((i = 0; i < 50; i++)); do kill -0 "$pid" 2>/dev/null || break; sleep 0.2; done
      kill -KILL "$pid" 2>/dev/null
      wait "$pid" 2>/dev/null
    done
  fi
  if [ "$rc" != 0 ] && [ -d "$tmp/log" ]; then
    echo "--- last lines of the daemons' logs" >&2
    tail -n 5 "$tmp"/log/* >&2
  fi
  rm -rf "$tmp"
  exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

step "starting munged, slurmctld and slurmd in $tmp"
mkdir -p "$tmp/munge" "$tmp/state" "$tmp/spool" "$tmp/log"
# A private key and socket: this works beside (and never disturbs) a system munged.
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
munged --foreground --force --socket="$tmp/munge/munge.socket" --key-file="$tmp/munge/munge.key" \
  --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
  --log-file="$tmp/log/munged.log" > /dev/null 2>&1 &
daemons+=($!)
for ((i = 0; i < 50; i++)); do [ -S "$tmp/munge/munge.socket" ] && break; sleep 0.1; done
munge -S "$tmp/munge/munge.socket" -n | unmunge -S "$tmp/munge/munge.socket" > /dev/null ||
  fail "munged does not answer"

host=$(hostname -s)
export SLURM_CONF=$tmp/slurm.conf
# Private ports so that a system Slurm on this machine is left alone. KillWait=5 makes a
# cancelled task end quickly; MinJobAge keeps finished jobs visible to squeue for a while.
cat > "$SLURM_CONF" <<EOF
ClusterName=raylabtest
SlurmctldHost=$host
SlurmUser=root
SlurmctldPort=16817
SlurmdPort=16818
AuthType=auth/munge
AuthInfo=socket=$tmp/munge/munge.socket
CredType=cred/munge
MpiDefault=none
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
ReturnToService=2
KillWait=5
MinJobAge=120
SchedulerParameters=sched_interval=1
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/log/slurmctld.log
SlurmdLogFile=$tmp/log/slurmd.log
NodeName=$host CPUs=2 State=UNKNOWN
PartitionName=debug Nodes=$host Default=YES MaxTime=INFINITE State=UP
EOF
slurmctld -D > "$tmp/log/slurmctld.out" 2>&1 &
daemons+=($!)
slurmd -D > "$tmp/log/slurmd.out" 2>&1 &
daemons+=($!)
for ((i = 0; i < 150; i++)); do
  [ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" = idle ] && break
  sleep 0.2
done
[ "$(sinfo -h -n "$host" -o %t 2>/dev/null)" = idle ] || fail "the node did not come up idle: $(sinfo 2>&1 | tail -n 1)"
sinfo

farm=(tools/farm/slurm.sh --raylab "$RAYLAB" --poll 0.3)

step "a. 4 tiles of the lab box, cancelling one array element while it renders"
# 128 spp: long enough (~1 s a tile) to cancel tile 2 mid-render.
args=(--integrator path --spp 128 --width 200 --height 200)
"${farm[@]}" --tiles 4 --name rl-tiles --workdir "$tmp/a" -o "$tmp/a/farm.png" -- "${args[@]}" \
  > "$tmp/a.log" 2>&1 &
farm_pid=$!
for ((i = 0; i < 600; i++)); do
  grep -qs 'attempt 1' "$tmp"/a/logs/task-*_2.out && break
  kill -0 "$farm_pid" 2>/dev/null || break
  sleep 0.1
done
element=$(squeue -h -r -n rl-tiles -t RUNNING -o %i | grep '_2$' || true)
[ -n "$element" ] || { cat "$tmp/a.log"; fail "array element 2 was never seen running"; }
echo "scancel $element"
scancel "$element"
wait "$farm_pid" || { farm_pid=""; cat "$tmp/a.log"; fail "the farm run failed"; }
farm_pid=""
cat "$tmp/a.log"
grep -q 'without task(s) 2 .*resubmitting' "$tmp/a.log" || fail "the cancelled task 2 was not resubmitted"
mapfile -t merges < <(sed -n 's/^submitted merge job \([0-9]*\) .*/\1/p' "$tmp/a.log")
[ ${#merges[@]} = 2 ] || fail "expected 2 merge jobs (the first one cancelled), got ${#merges[*]}"
[ ! -e "$tmp/a/logs/merge-${merges[0]}.out" ] || fail "merge job ${merges[0]} ran although task 2 was cancelled"
grep -q '^merged 4 parts' "$tmp/a/logs/merge-${merges[1]}.out" || fail "merge job ${merges[1]} did not merge"
"$RAYLAB" render "${args[@]}" -q -o "$tmp/a/ref.png"
"$RAYLAB" render "${args[@]}" -q -o "$tmp/a/ref.exr"
"$RAYLAB" merge -q "$tmp"/a/part-{0..3}.exr -o "$tmp/a/farm.exr"
cmp "$tmp/a/farm.png" "$tmp/a/ref.png" || fail "a: the farmed PNG differs from the single render"
cmp "$tmp/a/farm.exr" "$tmp/a/ref.exr" || fail "a: the merged EXR differs from the single render"
echo "a: ok (PNG and EXR byte-identical)"

step "b. an 8-frame turntable of the bunny, one task per frame"
args=("$bunny" --integrator path --spp 4 --width 96 --height 72 --orbit 45)
"${farm[@]}" --frames 0..8 --name rl-frames --workdir "$tmp/b/work" -o "$tmp/b/farm/f-%04d.png" -- "${args[@]}" ||
  fail "the frames farm run failed"
mkdir -p "$tmp/b/ref"
"$RAYLAB" render "${args[@]}" --frames 0..8 -q -o "$tmp/b/ref/f-%04d.png"
for f in {0..7}; do
  name=$(printf 'f-%04d.png' "$f")
  cmp "$tmp/b/farm/$name" "$tmp/b/ref/$name" || fail "b: frame $f differs from the single --frames 0..8 run"
done
echo "b: ok (8 frames byte-identical)"

step "c. 2 sample chunks of --spp 8"
args=(--integrator path --width 200 --height 200)
"${farm[@]}" --sample-chunks 2 --spp 8 --name rl-chunks --workdir "$tmp/c" -o "$tmp/c/farm.png" -- "${args[@]}" ||
  fail "the sample-chunks farm run failed"
"$RAYLAB" render "${args[@]}" --spp 8 -q -o "$tmp/c/ref.png"
cmp "$tmp/c/farm.png" "$tmp/c/ref.png" || fail "c: the merged chunks differ from the single render"
echo "c: ok (byte-identical)"

if [ ${#then_cmd[@]} -gt 0 ]; then
  step "running ${then_cmd[*]} with the cluster up"
  "${then_cmd[@]}"
fi
echo "slurm test: all ok"

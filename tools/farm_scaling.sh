#!/usr/bin/env bash
# farm_scaling.sh: how well does a raylab render split into tiles scale on this machine?
#
#   tools/farm_scaling.sh [--procs "1 2 4 8"] [--repeat R] [--raylab PATH] [--no-slurm]
#                         [-- RENDER_ARGS...]
#
# For each P in --procs it renders the image as P tiles (`--tile i/P --threads 1`), all P
# processes launched at once, times the render phase (launch to last exit), then times
# `raylab merge` and checks the merged PNG is byte-identical to a single render. Each
# configuration runs R times (default 3) and the fastest is kept: other load on the
# machine only ever slows a run down. It also times one single-process render with
# every core, and a task's fixed cost: the same scene at --spp 1 on an 8x8 image
# (process start, scene load, BVH build, writing the part). When `sinfo` answers, the
# same render also goes through tools/farm/slurm.sh (4 tiles, 1 and 2 CPUs per task),
# timed from submission to the merged image. Prints Markdown tables.
#
# RENDER_ARGS default to the lab box: --integrator path --spp 64 --width 320 --height 320
set -euo pipefail
cd "$(dirname "$0")/.."

procs="1 2 4 8" repeat=3 raylab=${RAYLAB:-target/release/raylab} slurm=auto
render_args=(--integrator path --spp 64 --width 320 --height 320)
while [ $# -gt 0 ]; do
  case $1 in
    --procs) procs=$2; shift 2 ;;
    --repeat) repeat=$2; shift 2 ;;
    --raylab) raylab=$2; shift 2 ;;
    --no-slurm) slurm=no; shift ;;
    --) shift; [ $# -eq 0 ] || render_args=("$@"); break ;;
    -h|--help) sed -n '2,/^set -euo/{/^set -euo/d;s/^# \{0,1\}//;p}' "$0"; exit 0 ;;
    *) echo "farm_scaling.sh: unknown option $1 (see --help)" >&2; exit 2 ;;
  esac
done
[ -x "$raylab" ] || { echo "farm_scaling.sh: no raylab at $raylab (cargo build --release)" >&2; exit 2; }
raylab=$(cd "$(dirname "$raylab")" && pwd)/$(basename "$raylab")
cores=$(nproc)
tmp=$(mktemp -d /tmp/raylab-farm-scaling.XXXXXX)
trap 'rm -rf "$tmp"' EXIT

now() { date +%s.%N; }
calc() { awk "BEGIN { printf \"%.${2:-2}f\", ($1) }"; }
min() { printf '%s\n' "$@" | sort -g | head -n 1; }
max() { printf '%s\n' "$@" | sort -g | tail -n 1; }

# The reference image, and the single-process times.
"$raylab" render "${render_args[@]}" -q -o "$tmp/ref.png"
t_all=()
for ((r = 0; r < repeat; r++)); do
  s=$(now); "$raylab" render "${render_args[@]}" --threads "$cores" -q -o "$tmp/all.png"; t_all+=("$(calc "$(now) - $s" 3)")
done

# The fixed cost of a task: RENDER_ARGS without --spp/--width/--height, on 8x8 at 1 spp.
small=() skip=0
for a in "${render_args[@]}"; do
  if [ "$skip" = 1 ]; then skip=0; continue; fi
  case $a in --spp|--width|--height) skip=1 ;; --spp=*|--width=*|--height=*) ;; *) small+=("$a") ;; esac
done
t_start=()
for ((r = 0; r < repeat + 2; r++)); do
  s=$(now)
  "$raylab" render "${small[@]}" --spp 1 --width 8 --height 8 --tile 0/2 --threads 1 -q -o "$tmp/tiny.exr"
  t_start+=("$(calc "$(now) - $s" 3)")
done

# P tile processes at once, each timing itself (for the spread between tasks).
rows=()
for p in $procs; do
  best="" best_merge="" spread="" same=yes
  for ((r = 0; r < repeat; r++)); do
    rm -f "$tmp"/part-*.exr "$tmp"/task-*.time
    s=$(now)
    pids=()
    for ((i = 0; i < p; i++)); do
      (
        ts=$(now)
        "$raylab" render "${render_args[@]}" --tile "$i/$p" --threads 1 -q -o "$tmp/part-$i.exr"
        calc "$(now) - $ts" 3 > "$tmp/task-$i.time"
        times > "$tmp/task-$i.cpu" # line 2: the user and system time of raylab
      ) &
      pids+=($!)
    done
    for pid in "${pids[@]}"; do wait "$pid"; done
    wall=$(calc "$(now) - $s" 3)
    parts=() times=()
    for ((i = 0; i < p; i++)); do parts+=("$tmp/part-$i.exr"); times+=("$(cat "$tmp/task-$i.time")"); done
    # Total CPU seconds of the P tasks: "0m1.234s 0m0.056s" lines, summed.
    cpu=$(for ((i = 0; i < p; i++)); do sed -n 2p "$tmp/task-$i.cpu"; done |
      awk '{ for (f = 1; f <= 2; f++) { split($f, t, /[ms]/); sum += t[1] * 60 + t[2] } } END { printf "%.2f", sum }')
    s=$(now)
    "$raylab" merge -q "${parts[@]}" -o "$tmp/merged.png"
    merge=$(calc "$(now) - $s" 3)
    cmp -s "$tmp/merged.png" "$tmp/ref.png" || same=NO
    if [ -z "$best" ] || [ "$(calc "$wall < $best" 0)" = 1 ]; then
      best=$wall spread="$(min "${times[@]}")–$(max "${times[@]}")" best_cpu=$cpu
    fi
    [ -n "$best_merge" ] && [ "$(calc "$merge >= $best_merge" 0)" = 1 ] || best_merge=$merge
  done
  rows+=("$p|$best|$spread|$best_cpu|$best_merge|$same")
done
t1=${rows[0]#*|}; t1=${t1%%|*}
[ "${procs%% *}" = 1 ] || t1=""

echo
echo "### raylab tile farm on one machine ($cores cores, $(uname -m))"
echo
echo "Render: \`raylab render ${render_args[*]}\`, split with \`--tile i/P --threads 1\`,"
echo "P processes started at once; best of $repeat runs."
echo
echo "| processes P | render wall (s) | task times (s) | task CPU total (s) | speed-up | efficiency | merge (s) | merged = single render |"
echo "|---:|---:|---:|---:|---:|---:|---:|:---:|"
for row in "${rows[@]}"; do
  IFS='|' read -r p wall spread cpu merge same <<< "$row"
  used=$((p < cores ? p : cores))
  if [ -n "$t1" ]; then
    speed="$(calc "$t1 / $wall")×" eff="$(calc "100 * $t1 / ($wall * $used)" 0)%"
  else
    speed=- eff=-
  fi
  echo "| $p | $wall | $spread | $cpu | $speed | $eff | $merge | $same |"
done
echo
echo "- speed-up = T(1) / T(P); efficiency = T(1) / (T(P) × min(P, cores)): 100% means every"
echo "  core that P single-threaded processes can use did useful work. Task CPU total (user +"
echo "  system of the P processes) shows the work the split adds, whatever else loads the machine."
echo "- load average during the runs: $(cut -d' ' -f1-3 /proc/loadavg) (other processes share the cores)."
echo "- one process with $cores threads (no split): $(min "${t_all[@]}") s."
echo "- a task's fixed cost (start, scene load, BVH build, write; \`--spp 1\`, 8x8): $(min "${t_start[@]}") s" \
  "(median $(printf '%s\n' "${t_start[@]}" | sort -g | sed -n "$(((${#t_start[@]} + 1) / 2))p") s)."

if [ "$slurm" = auto ] && command -v sinfo >/dev/null && sinfo -h >/dev/null 2>&1; then
  echo
  echo "### through tools/farm/slurm.sh (4 tiles; submission to merged image)"
  echo
  echo "| CPUs per task | wall (s) | merged = single render |"
  echo "|---:|---:|:---:|"
  for c in 1 2; do
    s=$(now)
    if tools/farm/slurm.sh --tiles 4 --cpus-per-task "$c" --poll 0.2 --raylab "$raylab" \
      --workdir "$tmp/slurm-$c" -o "$tmp/slurm-$c.png" -- "${render_args[@]}" > "$tmp/slurm-$c.log" 2>&1; then
      wall=$(calc "$(now) - $s")
      cmp -s "$tmp/slurm-$c.png" "$tmp/ref.png" && same=yes || same=NO
    else
      wall="failed: $(tail -n 1 "$tmp/slurm-$c.log")" same=-
    fi
    echo "| $c | $wall | $same |"
  done
fi

#!/usr/bin/env bash
# usage: callgrind_counts.sh [--repo DIR] BINARY [BINARY_B]
#
# Instruction counts of three small single-threaded renders under Valgrind's
# callgrind: a measure of a build's speed that does not depend on the machine's
# load (repeatable to the instruction from run to run), for checking that a
# refactor leaves the speed unchanged.
#
# With one binary it prints each workload's total instruction count (callgrind's
# "Collected", the same as "I refs"); with two it prints both and the ratio B/A.
# The renders run in DIR (default: the current folder), the repository root,
# since the helmet is loaded from assets/; their images go to a temporary
# folder that is removed afterwards. Run it under `nice -n 10` on a shared
# machine; all three take about 10 s under Valgrind.
#
# Repeatability: `--threads 1` sizes the render's own pool, but raylab also uses
# rayon's global pool (film work), which has one thread per core and whose
# work stealing and idle spinning change the count by up to ~0.05 % from run
# to run. The renders therefore run with RAYON_NUM_THREADS=1, which leaves
# ~0.002 % (mutex contention between the remaining threads, hash seeds).
# Differences below ~0.01 % are noise.
#
# The workloads (arguments after `raylab`):
#   box-path    render --integrator path --spp 4 --width 120 --height 120 --threads 1 -o x.png
#   box-direct  render --spp 4 --width 200 --height 200 --threads 1 -o y.png
#   helmet      render assets/models/DamagedHelmet/DamagedHelmet.gltf --spp 1 --width 160 --threads 1 -o z.png
#               (mostly loading: decoding the textures, building the BVH)
#   helmet-8spp render assets/models/DamagedHelmet/DamagedHelmet.gltf --spp 8 --width 320 --threads 1 -o w.png
#               (the same load, and about twice its instructions in path tracing)
#
# Exit status: 0, or 1 when a render fails (its error is printed) or the
# count cannot be read from Valgrind's output.

set -euo pipefail

usage() { sed -n '2p' "$0" | sed 's/^# //' >&2; exit 2; }

repo=.
while [ $# -gt 0 ]; do
  case "$1" in
    --repo) [ $# -ge 2 ] || usage; repo=$2; shift 2 ;;
    -h|--help) sed -n '2,/^$/p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    --) shift; break ;;
    -*) usage ;;
    *) break ;;
  esac
done
[ $# -eq 1 ] || [ $# -eq 2 ] || usage
command -v valgrind >/dev/null || { echo "error: valgrind not found" >&2; exit 1; }

bins=()
for b in "$@"; do
  [ -x "$b" ] || { echo "error: $b: not an executable" >&2; exit 1; }
  bins+=("$(cd "$(dirname "$b")" && pwd)/$(basename "$b")")
done
cd "$repo"

tmp=$(mktemp -d "${TMPDIR:-/tmp}/callgrind_counts.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

names=(box-path box-direct helmet helmet-8spp)
workload() {
  case "$1" in
    box-path)   echo "render --integrator path --spp 4 --width 120 --height 120 --threads 1 -o $tmp/x.png" ;;
    box-direct) echo "render --spp 4 --width 200 --height 200 --threads 1 -o $tmp/y.png" ;;
    helmet)     echo "render assets/models/DamagedHelmet/DamagedHelmet.gltf --spp 1 --width 160 --threads 1 -o $tmp/z.png" ;;
    helmet-8spp) echo "render assets/models/DamagedHelmet/DamagedHelmet.gltf --spp 8 --width 320 --threads 1 -o $tmp/w.png" ;;
  esac
}

# count BINARY NAME: prints the instruction count of the workload.
count() {
  local bin=$1 name=$2 log=$tmp/valgrind.log n
  # shellcheck disable=SC2046  # the workload's words are split on purpose (no spaces in paths)
  if ! RAYON_NUM_THREADS=1 valgrind --tool=callgrind --callgrind-out-file="$tmp/callgrind.out" \
        "$bin" $(workload "$name") >"$tmp/stdout" 2>"$log"; then
    echo "error: $name with $bin failed:" >&2
    grep -v '^==[0-9]*==' "$log" | tail -n 3 >&2
    return 1
  fi
  n=$(sed -n 's/^==[0-9]*== Collected : *\([0-9]*\).*/\1/p' "$log")
  [ -n "$n" ] || { echo "error: no 'Collected' line in valgrind's output for $name" >&2; return 1; }
  echo "$n"
}

echo "# callgrind_counts.sh: instructions (callgrind 'Collected'), --threads 1, RAYON_NUM_THREADS=1, in $(pwd)"
for i in "${!bins[@]}"; do
  label=A; [ "$i" -eq 1 ] && label=B
  echo "# $label: ${bins[$i]} (sha256 $(sha256sum "${bins[$i]}" | cut -c1-16))"
done
for n in "${names[@]}"; do echo "# $n: raylab $(workload "$n" | sed "s|$tmp/||")"; done

status=0
if [ ${#bins[@]} -eq 1 ]; then
  printf '%-12s %16s %8s\n' workload instructions seconds
  for n in "${names[@]}"; do
    t0=$(date +%s%N)
    c=$(count "${bins[0]}" "$n") || { status=1; c=FAILED; }
    printf '%-12s %16s %8.1f\n' "$n" "$c" "$(awk -v a="$t0" -v b="$(date +%s%N)" 'BEGIN { print (b - a) / 1e9 }')"
  done
else
  printf '%-12s %16s %16s %10s\n' workload A B B/A
  for n in "${names[@]}"; do
    a=$(count "${bins[0]}" "$n") || { status=1; a=FAILED; }
    b=$(count "${bins[1]}" "$n") || { status=1; b=FAILED; }
    if [ "$a" != FAILED ] && [ "$b" != FAILED ]; then
      r=$(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.6f", b / a }')
      printf '%-12s %16s %16s %10.6f\n' "$n" "$a" "$b" "$r"
    else
      printf '%-12s %16s %16s %10s\n' "$n" "$a" "$b" -
    fi
  done
fi
exit $status

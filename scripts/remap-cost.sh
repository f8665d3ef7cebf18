#!/usr/bin/env bash
# The cost of one remap as a cost model counts it: instructions, conditional branches and mispredicted ones
# (cachegrind's branch simulator), per remap of a benchmark set. On a shared machine timings drift by tens of
# per cent from minute to minute; these counts repeat to the last digit, so two builds compare at once.
#
#   bash scripts/remap-cost.sh [jittered|sheared] [PARTICLES] [first|second]   (defaults: jittered 100000 first)
#
# Runs build/bin/remap_cost (built with -DRSPH_BUILD_BENCHMARKS=ON; RSPH_BUILD_DIR picks another build) under
# cachegrind with one and with three remaps, on one thread, and prints the difference over two, then where it
# goes: the functions (inlined code counted where it lands) with the most instructions.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RSPH_BUILD_DIR:-$root/build}
layout=${1:-jittered}
particles=${2:-100000}
order=${3:-first}
tool=$build/bin/remap_cost
[[ -x $tool ]] || { echo "remap-cost: $tool is missing; build with -DRSPH_BUILD_BENCHMARKS=ON" >&2; exit 1; }
if ! command -v valgrind >/dev/null; then
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq valgrind >/dev/null
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for remaps in 1 3; do
  OMP_NUM_THREADS=1 valgrind --tool=cachegrind --cache-sim=no --branch-sim=yes \
    --cachegrind-out-file="$work/out.$remaps" "$tool" "$layout" "$particles" "$remaps" "$order" >"$work/stdout.$remaps" \
    2>"$work/log.$remaps" || { cat "$work/log.$remaps" >&2; exit 1; }
done
count() {  # count LABEL LOG: the first number after the label
  sed -n "s/^==[0-9]*== $1: *\([0-9,]*\).*/\1/p" "$2" | head -1 | tr -d ,
}
per_remap() { echo $((($(count "$1" "$work/log.3") - $(count "$1" "$work/log.1")) / 2)); }
ir=$(per_remap "I *refs")
branches=$(per_remap "Branches")
mispredicts=$(per_remap "Mispredicts")
n=$(awk '{print $1; exit}' "$work/stdout.3")  # the set's own count (a whole square of sites)
awk -v ir="$ir" -v b="$branches" -v m="$mispredicts" -v n="$n" -v l="$layout" 'BEGIN {
  printf "remap of %s %s, per remap: %.1f M instructions, %.2f M branches, %.3f M mispredicted (cachegrind)\n", l, n, ir / 1e6, b / 1e6, m / 1e6
  printf "per old particle: %.0f instructions, %.1f branches, %.2f mispredicted\n", ir / n, b / n, m / n }'
cg_diff "$work/out.1" "$work/out.3" >"$work/diff" 2>/dev/null
cg_annotate --show=Ir,Bcm --auto=no "$work/diff" 2>/dev/null | /usr/bin/python3 "$root/scripts/cost_by_function.py" "$n"

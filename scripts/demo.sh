#!/usr/bin/env bash
# The main job: builds rsph, runs the demo (Sod's shock tube in 1D and 2D) and draws out/demo/sod.png.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RSPH_BUILD_DIR:-$root/build}
bash "$root/scripts/build.sh" -DRSPH_BUILD_TESTS=OFF -DRSPH_BUILD_BENCHMARKS=OFF
out=$root/out/demo
"$build/bin/rsph-sod" --dim 1 --overwrite --out "$out/sod-1d"
"$build/bin/rsph-sod" --dim 2 --overwrite --out "$out/sod-2d"
/usr/bin/python3 "$root/scripts/plot_sod.py" "$out/sod-1d" "$out/sod-2d" --png "$out/sod.png"

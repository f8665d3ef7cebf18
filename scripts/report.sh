#!/usr/bin/env bash
# Builds rsph's programs and writes the report, out/report/index.html: every test of the paper with RSPH (both
# remaps) and plain SPH, errors against exact or reference solutions, and what each run cost. Arguments go to
# scripts/report.py: --quick (about 3 minutes), --full (the paper's sizes, hours), --only TEST[,TEST], --out DIR.
# Runs already in the output folder with the same flags are kept.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RSPH_BUILD_DIR:-$root/build}
bash "$root/scripts/setup-deps.sh"
# the programs at -O3 (a build folder CI configured at -O1 is brought back): the report times them
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O3 -DNDEBUG" -DRSPH_BUILD_EXAMPLES=ON \
  >/dev/null
cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" --target rsph_programs
exec /usr/bin/python3 "$root/scripts/report.py" --bin "$build/bin" "$@"

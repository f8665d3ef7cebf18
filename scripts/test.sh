#!/usr/bin/env bash
# Builds rsph with its tests and examples and runs the whole CTest suite (reduced, CI-sized runs).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RSPH_BUILD_DIR:-$root/build}
bash "$root/scripts/build.sh" -DRSPH_BUILD_TESTS=ON -DRSPH_BUILD_EXAMPLES=ON -DRSPH_BUILD_BENCHMARKS=ON
cd "$build"
ctest --output-on-failure -j "$(nproc 2>/dev/null || echo 2)"

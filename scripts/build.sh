#!/usr/bin/env bash
# Configures and builds rsph (Release, -O3) into ${RSPH_BUILD_DIR:-build}; extra arguments go to CMake and come
# after the defaults, so they may replace them (scripts/test.sh does in CI). The flags are given on every call,
# so that a build folder once configured otherwise is brought back to them.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bash "$root/scripts/setup-deps.sh"
build=${RSPH_BUILD_DIR:-$root/build}
jobs=$(nproc 2>/dev/null || echo 2)
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O3 -DNDEBUG" "$@" >/dev/null
cmake --build "$build" -j "$jobs"

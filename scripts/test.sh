#!/usr/bin/env bash
# Builds rsph with its tests and examples and runs the whole CTest suite (reduced, CI-sized runs). In CI
# (CI=true), or with RSPH_SANITIZE=1, the unit tests are first built and run under AddressSanitizer and
# UndefinedBehaviorSanitizer in a build of their own (${RSPH_SANITIZE_DIR:-build-sanitize}).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${RSPH_BUILD_DIR:-$root/build}
jobs=$(nproc 2>/dev/null || echo 2)
if [ "${CI:-}" = "true" ] || [ "${RSPH_SANITIZE:-}" = 1 ]; then
  bash "$root/scripts/setup-deps.sh"
  sanitize=${RSPH_SANITIZE_DIR:-$root/build-sanitize}
  # -O1 keeps the sanitized build short (9 min on 2 cores); its tests but the [long] physics runs (whose code the
  # others cover, and which ctest runs below) then take about 3 min
  cmake -S "$root" -B "$sanitize" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-O1 -DNDEBUG" \
    -DRSPH_SANITIZE=ON -DRSPH_BUILD_EXAMPLES=OFF -DRSPH_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$sanitize" -j "$jobs" --target rsph_tests
  echo "rsph: the unit tests under AddressSanitizer and UndefinedBehaviorSanitizer"
  OMP_NUM_THREADS=2 "$sanitize/bin/rsph_tests" "~[long]"
fi
bash "$root/scripts/build.sh" -DRSPH_BUILD_TESTS=ON -DRSPH_BUILD_EXAMPLES=ON -DRSPH_BUILD_BENCHMARKS=ON
cd "$build"
ctest --output-on-failure -j "$jobs"

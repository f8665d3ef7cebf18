#!/usr/bin/env bash
# The main job: builds rsph and runs every test of the paper at a size that takes about three minutes in all
# on two cores (scripts/report.sh --quick), writing out/report/index.html with its figures and tables.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
exec bash "$root/scripts/report.sh" --quick "$@"

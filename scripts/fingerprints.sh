#!/usr/bin/env bash
# Runs every run of tests/fingerprints/runs.txt on one thread and compares its last snapshot with the
# stored fingerprint; --write stores new ones instead (a change that must alter bits, in its own commit).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
bin=${RSPH_BUILD_DIR:-$root/build}/bin
write=0
[ "${1:-}" = "--write" ] && write=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failed=0
while read -r name prog args; do
  case "$name" in "" | \#*) continue ;; esac
  # shellcheck disable=SC2086
  "$bin/$prog" $args --out "$work/$name" --threads 1 --quiet >/dev/null
  if [ $write = 1 ]; then
    /usr/bin/python3 "$root/scripts/fingerprint.py" "$work/$name" >"$root/tests/fingerprints/$name.txt"
    echo "wrote tests/fingerprints/$name.txt"
  else
    /usr/bin/python3 "$root/scripts/fingerprint.py" "$work/$name" --check "$root/tests/fingerprints/$name.txt" ||
      failed=1
  fi
done <"$root/tests/fingerprints/runs.txt"
exit $failed

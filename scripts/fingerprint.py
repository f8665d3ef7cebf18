#!/usr/bin/python3
"""Fingerprint of a run's last snapshots: one line per dataset and attribute, with the SHA-256 of its bytes.

    fingerprint.py OUT_DIR            prints the fingerprint of the last snap_NNNNN.h5 of OUT_DIR and of
                                      each folder below it that holds snapshots (one per case)
    fingerprint.py OUT_DIR --check F  exits 1 (naming each difference) unless it equals the one in F

Two runs with the same fingerprint wrote every field of their last snapshots to the bit."""
import argparse
import glob
import hashlib
import os
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import load  # noqa: E402


def last_snapshots(folder):
    """The last snapshot of every folder at or below `folder` that holds any, in sorted order."""
    found = []
    for here, dirs, _ in os.walk(folder):
        dirs.sort()
        snaps = sorted(glob.glob(os.path.join(here, "snap_*.h5")))
        if snaps:
            found.append(snaps[-1])
    if not found:
        sys.exit(f"fingerprint: no snap_NNNNN.h5 in or below {folder}")
    return found


def fingerprint(path, folder):
    lines = [f"file {os.path.relpath(path, folder)}"]
    fields, attributes = load(path)
    for name in sorted(attributes):
        value = np.asarray(attributes[name])
        lines.append(f"attr {name} {value.dtype.str} {hashlib.sha256(value.tobytes()).hexdigest()}")
    for name in sorted(fields):
        data = np.ascontiguousarray(fields[name])
        shape = "x".join(str(s) for s in data.shape)
        lines.append(f"data {name} {data.dtype.str} {shape} {hashlib.sha256(data.tobytes()).hexdigest()}")
    return lines


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--check", metavar="FILE", help="the expected fingerprint")
    args = ap.parse_args()
    got = [line for path in last_snapshots(args.folder) for line in fingerprint(path, args.folder)]
    if not args.check:
        print("\n".join(got))
        return
    with open(args.check) as f:
        want = [line.rstrip("\n") for line in f if line.strip() and not line.startswith("#")]
    if got == want:
        print(f"fingerprint: {args.folder} matches {args.check} ({len(got)} lines)")
        return
    for line in sorted(set(want) - set(got)):
        print(f"expected: {line}")
    for line in sorted(set(got) - set(want)):
        print(f"got:      {line}")
    sys.exit(f"fingerprint: {args.folder} differs from {args.check}")


if __name__ == "__main__":
    main()

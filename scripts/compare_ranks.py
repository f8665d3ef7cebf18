#!/usr/bin/python3
"""Runs one program at several rank counts and checks that the answers do not depend on the count: the integer
results (particles, steps, regularizations, and on a multi-level lattice the particles per level) equal, the headline figures of summary.json equal to 1e-8 relative,
and every field of every particle of the last snapshot equal to 1e-10 (--field-tolerance) relative to the
field's largest value, particles matched by identity (plain SPH) or by position (after a remap, whose new particles are numbered rank
by rank). Exit status 0 when all agree, 1 otherwise.

  compare_ranks.py --ranks 1,2,4 --figures shock_radius,peak_density -- build/bin/rsph-sedov --preset quick --dim 2

With --relay 4@0.03,2@0.06,1 the run is also made in stages: on 4 ranks until it passes t = 0.03, where it stops
with a checkpoint (--stop-at), resumed from that checkpoint on 2 ranks until 0.06, and finished on 1; the finished
relay is compared with the first --ranks run as above.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import h5py
import numpy as np

ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1", "OMPI_MCA_rmaps_base_oversubscribe": "1",
       "OMPI_MCA_btl_vader_single_copy_mechanism": "none", "OMP_NUM_THREADS": "1"}
INTEGERS = ("particles", "steps", "regularizations")
FIELDS = ("x", "v", "m", "rho", "h", "P", "u")


def run(mpiexec, ranks, cmd, out):
    env = dict(os.environ, **ENV)
    full = [mpiexec, "-n", str(ranks)] + cmd + ["--out", out, "--overwrite", "--no-plot", "--quiet"]
    proc = subprocess.run(full, capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(full)} failed ({proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def relay(mpiexec, stages, cmd, out):
    """The run made in stages, each "RANKS@TIME" but the last (RANKS) resumed from the one before."""
    env = dict(os.environ, **ENV)
    for k, stage in enumerate(stages):
        ranks, _, stop = stage.partition("@")
        start = cmd + ["--out", out, "--overwrite"] if k == 0 else [cmd[0], "--resume", out]
        full = [mpiexec, "-n", ranks] + start + ["--no-plot", "--quiet", "--stop-at", stop or "0"]
        proc = subprocess.run(full, capture_output=True, text=True, env=env)
        expected = 0 if k == len(stages) - 1 else 5
        if proc.returncode != expected or (expected == 5 and "--resume" not in proc.stderr):
            sys.exit(f"{' '.join(full)} exited {proc.returncode}, not {expected}:\n{proc.stdout}\n{proc.stderr}")
        print(f"relay: {ranks} ranks" + (f" until t = {stop}, checkpoint written" if stop else " to the end"))
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def last_snapshot(folder):
    """The last snapshot of the folder, or of its last subfolder that holds any (a program writing one per case)."""
    names = sorted(os.path.join(os.path.relpath(d, folder), n) for d, _, files in os.walk(folder) for n in files
                   if n.startswith("snap_") and n.endswith(".h5"))
    if not names:
        sys.exit(f"{folder} holds no snapshot")
    with h5py.File(os.path.join(folder, names[-1]), "r") as f:
        fields = {k: np.array(f[k]) for k in FIELDS + ("id",) if k in f}
    fields["id"] = fields["id"].reshape(-1)
    return fields


def matched(a, b, by_id):
    """b's rows in the order of a's particles."""
    if by_id:
        where = {i: k for k, i in enumerate(b["id"])}
        return np.array([where[i] for i in a["id"]])
    order = []
    for x in a["x"]:
        order.append(int(np.argmin(((b["x"] - x) ** 2).sum(axis=1))))
    return np.array(order)


def compare(reference, other, ranks, figures, by_id, tolerance):
    problems = []
    for key in INTEGERS:
        if key in reference[0] and reference[0][key] != other[0][key]:
            problems.append(f"{key}: {reference[0][key]} on 1 rank, {other[0][key]} on {ranks}")
    if "levels" in reference[0]:  # the particles per level the last remap left, the whole run's on every rank
        finals = [[e["final"] for e in s["levels"]["per_level"]] for s in (reference[0], other[0])]
        if finals[0] != finals[1]:
            problems.append(f"particles per level: {finals[0]} on 1 rank, {finals[1]} on {ranks}")
    for key in figures:
        r, o = reference[0][key], other[0][key]
        if abs(o - r) > 1e-8 * max(abs(r), 1e-300):
            problems.append(f"{key}: {r!r} on 1 rank, {o!r} on {ranks} ({abs(o - r) / abs(r):.2e} relative)")
    a, b = reference[1], other[1]
    if len(a["x"]) != len(b["x"]):
        return problems + [f"the last snapshot holds {len(a['x'])} particles on 1 rank, {len(b['x'])} on {ranks}"]
    rows = matched(a, b, by_id)
    worst = 0.0
    for f in FIELDS:
        if f in a:
            scale = max(np.abs(a[f]).max(), 1e-300)
            worst = max(worst, float(np.abs(a[f] - b[f][rows]).max() / scale))
    print(f"{ranks} ranks: largest field difference {worst:.2e} of the field's scale; figures " +
          ", ".join(f"{k} {other[0][k]!r}" for k in figures))
    if worst > tolerance:
        problems.append(f"a field differs by {worst:.2e} of its scale on {ranks} ranks")
    return problems


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--mpiexec", default="mpiexec")
    ap.add_argument("--ranks", default="1,2,4")
    ap.add_argument("--figures", default="", help="summary.json figures that must agree to 1e-8")
    ap.add_argument("--by-id", action="store_true", help="match particles by identity (no remap numbers them anew)")
    ap.add_argument("--field-tolerance", type=float, default=1e-10,
                    help="largest field difference relative to the field's scale (an unstable flow amplifies the "
                         "last bits of sums made in another order, and may need more)")
    ap.add_argument("--relay", default="", help="also make the run in stages across rank counts, each resumed "
                    "from the last one's checkpoint: R1@T1,R2@T2,...,Rn (see above)")
    ap.add_argument("cmd", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    cmd = a.cmd[1:] if a.cmd and a.cmd[0] == "--" else a.cmd
    figures = [f for f in a.figures.split(",") if f]
    counts = [int(r) for r in a.ranks.split(",")]
    with tempfile.TemporaryDirectory() as tmp:
        results = {}
        for n in counts:
            out = os.path.join(tmp, f"ranks{n}")
            results[n] = (run(a.mpiexec, n, cmd, out), last_snapshot(out))
        problems = []
        for n in counts[1:]:
            problems += compare(results[counts[0]], results[n], n, figures, a.by_id, a.field_tolerance)
        if a.relay:
            out = os.path.join(tmp, "relay")
            stages = a.relay.split(",")
            finished = (relay(a.mpiexec, stages, cmd, out), last_snapshot(out))
            problems += compare(results[counts[0]], finished, "->".join(s.split("@")[0] for s in stages), figures,
                                a.by_id, a.field_tolerance)
    for p in problems:
        print("differs:", p)
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Snapshots carry what a reader needs: check_snapshot_metadata.py OUT DISK_PROGRAM KH_PROGRAM

Runs a one-orbit disk and a quick Kelvin-Helmholtz run into OUT and reads their last snapshots back with
rsph_plot.load: the box and its edges, the equation of state and its constants, the unit system, the star's
and planet's positions (on the unit circle about their centre of mass) and the particle identities (unique;
the disk's gas that stays keeps its own from one step to the next, a remap gives every particle a new one)."""
import glob
import os
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from rsph_plot import load  # noqa: E402


def fail(message):
    sys.exit("check_snapshot_metadata: " + message)


def text(value):
    return value.decode() if isinstance(value, bytes) else str(value)


def main():
    out, disk, kh = sys.argv[1:]
    runs = {"disk": [disk, "--preset", "quick", "--orbits", "1", "--snapshot-every", "1"],
            "kh": [kh, "--preset", "quick"]}
    for name, cmd in runs.items():
        p = subprocess.run([*cmd, "--quiet", "--overwrite", "--out", os.path.join(out, name)], capture_output=True,
                           text=True)
        if p.returncode != 0:
            fail(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr}")

    fields, attrs = load(sorted(glob.glob(os.path.join(out, "disk", "snap_*.h5")))[-1])
    if text(attrs["edges"]) != "open,open" or list(attrs["periodic"]) != [0.0, 0.0]:
        fail(f"disk edges {attrs['edges']} / {attrs['periodic']}")
    if not text(attrs["eos"]).startswith("locally isothermal") or attrs["eos_cs_over_vK"] != 0.05:
        fail(f"disk gas {attrs['eos']}, c_s/v_K {attrs.get('eos_cs_over_vK')}")
    if "a = 1" not in text(attrs["units"]):
        fail(f"disk units {attrs['units']}")
    star, planet = attrs["object_star"], attrs["object_planet"]
    if abs(np.linalg.norm(planet - star) - 1.0) > 1e-12:
        fail(f"star {star} and planet {planet} are not one orbit radius apart")
    ids = fields["id"]
    if len(np.unique(ids)) != len(ids) or len(ids) != len(fields["m"]):
        fail("disk particle identities are not one per particle and unique")
    if ids.min() < len(ids):
        fail(f"after the remaps of an orbit the smallest identity is {ids.min()}: the start's were not renewed")

    fields, attrs = load(sorted(glob.glob(os.path.join(out, "kh", "snap_*.h5")))[-1])
    if text(attrs["edges"]) != "periodic,reflecting" or list(attrs["periodic"]) != [1.0, 0.0]:
        fail(f"KH edges {attrs['edges']}")
    if not text(attrs["eos"]).startswith("ideal gas") or abs(attrs["eos_gamma"] - 5.0 / 3.0) > 1e-15:
        fail(f"KH gas {attrs['eos']}, gamma {attrs.get('eos_gamma')}")
    if not (np.array_equal(attrs["box_lo"], [-0.5, 0.0]) and np.array_equal(attrs["box_hi"], [0.5, 0.5])):
        fail(f"KH box {attrs['box_lo']} .. {attrs['box_hi']}")
    print("check_snapshot_metadata: the disk's and KH's snapshots carry box, edges, gas, units, bodies and ids")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The figures disk_vs_fargo3d.py reads from the cuts of Figs. 13 and 14 (cut_figures), on cuts made up with
known features: a gap at r = 1.05 between bumps at r = 0.7 and 1.5 opposite the planet; along the orbit the
planet's envelope at 0, gas gathered 30 % above the floor 60 degrees ahead (L4) and 10 % above it behind (L5).

Usage: check_disk_cuts.py WORK
"""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from disk_vs_fargo3d import cut_figures  # noqa: E402


def bump(x, centre, width):
    return math.exp(-((x - centre) / width) ** 2)


def main():
    work = sys.argv[1]
    os.makedirs(work, exist_ok=True)
    with open(os.path.join(work, "cut_phi_pi.csv"), "w") as f:
        f.write("r,sigma_over_sigma0\n")
        for i in range(841):
            r = 0.4 + 2.1 * i / 840
            f.write(f"{r},{1.0 - 0.8 * bump(r, 1.05, 0.1) + 1.5 * bump(r, 0.7, 0.05) + 0.7 * bump(r, 1.5, 0.08)}\n")
    with open(os.path.join(work, "cut_r_a.csv"), "w") as f:
        f.write("phi,sigma_over_sigma0\n")
        for i in range(512):
            phi = -math.pi + 2.0 * math.pi * (i + 0.5) / 512
            d = math.degrees(phi)
            sigma = 0.4 * (1.0 + 0.3 * bump(d, 60.0, 8.0) + 0.1 * bump(d, -60.0, 8.0)) + 30.0 * bump(d, 0.0, 2.0)
            f.write(f"{phi},{sigma}\n")
    c = cut_figures(work)
    checks = [
        ("gap's least", c["gap"][0], 0.2, 0.01), ("gap's radius", c["gap"][1], 1.05, 0.01),
        ("inner peak", c["inner"][0], 2.5, 0.01), ("inner peak's radius", c["inner"][1], 0.7, 0.01),
        ("outer peak", c["outer"][0], 1.7, 0.01), ("outer peak's radius", c["outer"][1], 1.5, 0.01),
        ("floor along the orbit", c["floor"], 0.4, 1e-6), ("L4 over the floor", c["L4"], 1.3, 0.005),
        ("L5 over the floor", c["L5"], 1.1, 0.005),
    ]
    bad = [f"{name}: {got:.4f}, expected {want} within {tol}" for name, got, want, tol in checks
           if not abs(got - want) <= tol]
    if bad:
        sys.exit("check_disk_cuts:\n" + "\n".join(bad))
    print("check_disk_cuts: every figure of the cuts as made")


if __name__ == "__main__":
    main()

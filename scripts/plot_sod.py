#!/usr/bin/python3
"""Draws rho, v and P of every particle over the exact solution for one or more rsph-sod output folders.

Usage: plot_sod.py OUT_DIR [OUT_DIR ...] --png FILE
"""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    fig, axes = plt.subplots(len(args.dirs), 3, figsize=(13, 3.6 * len(args.dirs)), squeeze=False)
    for row, d in zip(axes, args.dirs):
        parts = read_csv(os.path.join(d, "particles.csv"))
        exact = read_csv(os.path.join(d, "exact.csv"))
        s = read_summary(d)
        method = s.get("method", "sph")
        if method == "rsph":
            lattice = f"levels 0-{s['max_level']}" if s.get("max_level", 0) > 0 else "uniform lattice"
            name = f"{method_label(s)}, {lattice}"
        else:
            name = "grad-h SPH"
        for ax, key, label, err in zip(row, ["rho", "v", "P"], [r"$\rho$", "$v_x$", "$P$"], ["L1_rho", "L1_v", "L1_P"]):
            ax.plot(parts["x"], parts[key], ".", ms=2, color="tab:blue", label="particles")
            ax.plot(exact["x"], exact[key], "-", lw=1, color="k", label="exact")
            ax.set_xlabel("x")
            ax.set_ylabel(label)
            ax.set_title(f"{name}, {s['dim']}D, {s['particles']} particles:\nL1 = {s[err]:.2e}", fontsize=9)
        row[0].legend(fontsize=8)
        row[2].text(0.02, 0.05, f"{s['steps']} steps, {s['wall_seconds']:.2f} s\n"
                    f"{s['particle_updates_per_second']:.3g} particle updates/s", transform=row[2].transAxes,
                    fontsize=8)
    fig.suptitle("Sod shock tube at t = 0.2 (cubic spline, alpha = 1, beta = 2) vs exact solution")
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

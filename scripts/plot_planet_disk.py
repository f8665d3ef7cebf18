#!/usr/bin/python3
"""Figures 12-15 of the paper from rsph-planet-disk output folders: the log Sigma map in (r, phi) with
the wake of linear theory, Sigma / Sigma_0 opposite the planet and along its orbit, the azimuthal
average, and the gap depth over time with each run's cost.

  python3 scripts/plot_planet_disk.py out/disk-low [out/disk-med ...] --png out/disk.png
"""
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from rsph_plot import FARGO3D_LABEL, FARGO3D_PROFILE, folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def label(summary):
    dim = "3D " if summary.get("dim", 2) == 3 else ""
    return (f"{dim}{method_label(summary)}, {summary['eos']}, N={summary['particles_initial']}, "
            f"{summary['orbits']:g} orbits, {summary['wall_seconds']:.0f} s")


def main():
    args = folders_and_png(__doc__)
    runs = [(d, read_summary(d)) for d in args.dirs]
    n = len(runs)
    fig = plt.figure(figsize=(13, 4.2 * n + 4.2))
    grid = fig.add_gridspec(n + 1, 3)
    for i, (d, s) in enumerate(runs):
        m = read_csv(f"{d}/map.csv")
        r = np.unique(m["r"])
        phi = np.unique(m["phi"])
        sigma = np.array(m["sigma_over_sigma0"]).reshape(len(r), len(phi))
        ax = fig.add_subplot(grid[i, 0:2])
        mesh = ax.pcolormesh(r, phi, np.log10(np.maximum(sigma.T, 1e-3)), shading="nearest", cmap="viridis",
                             vmin=-1.5, vmax=0.5)
        w = read_csv(f"{d}/wake.csv")
        wr, wp = np.array(w["r"]), np.array(w["phi"])
        jumps = np.where(np.abs(np.diff(wp)) > math.pi)[0] + 1  # no line across the wrap
        for seg_r, seg_p in zip(np.split(wr, jumps), np.split(wp, jumps)):
            ax.plot(seg_r, seg_p, "w--", lw=0.8)
        if os.path.exists(f"{d}/wake_crossings.csv"):  # the crest traced from the planet (paper::wake_crossings)
            x = read_csv(f"{d}/wake_crossings.csv")
            ax.plot(x["r"], x["phi_measured"], "r.", ms=2)
        ax.set_xlabel("r / a")
        ax.set_ylabel("phi - phi_p")
        ax.set_title(f"log10 Sigma/Sigma_0: {label(s)}", fontsize=9)
        fig.colorbar(mesh, ax=ax)
        ax = fig.add_subplot(grid[i, 2])
        c = read_csv(f"{d}/cut_r_a.csv")
        ax.plot(c["phi"], c["sigma_over_sigma0"], lw=1)
        ax.set_xlabel("phi - phi_p (r = a)")
        ax.set_yscale("log")  # the planet's envelope and the gap's floor (L4, L5 at +-1.05) both in view
        ax.set_ylabel("Sigma / Sigma_0")
        ax.set_title("along the orbit (Fig. 14)", fontsize=9)
    ax_cut = fig.add_subplot(grid[n, 0])
    ax_avg = fig.add_subplot(grid[n, 1])
    ax_gap = fig.add_subplot(grid[n, 2])
    for d, s in runs:
        c = read_csv(f"{d}/cut_phi_pi.csv")
        ax_cut.plot(c["r"], c["sigma_over_sigma0"], lw=1, label=label(s))
        p = read_csv(f"{d}/profile.csv")
        ax_avg.plot(p["r"], p["sigma_over_sigma0"], lw=1)
        t = read_csv(f"{d}/timeline.csv")
        ax_gap.plot(t["orbit"], t["gap_depth"], lw=1,
                    label=f"{s['particle_updates_per_second'] / 1e6:.2f} M updates/s")
    if os.path.exists(FARGO3D_PROFILE):
        ref = read_csv(FARGO3D_PROFILE)
        ax_avg.plot(ref["r"], ref["sigma_over_sigma0"], "k-", lw=1.5, label=FARGO3D_LABEL + ", orbit 100")
        ax_avg.legend(fontsize=7)
    ax_cut.set_xlabel("r / a (phi = phi_p + pi)")
    ax_cut.set_ylabel("Sigma / Sigma_0")
    ax_cut.set_title("opposite the planet (Fig. 13)", fontsize=9)
    ax_cut.legend(fontsize=7)
    ax_avg.set_xlabel("r / a")
    ax_avg.set_ylabel("<Sigma> / Sigma_0")
    ax_avg.set_title("azimuthal average (Fig. 15)", fontsize=9)
    ax_gap.set_xlabel("planet orbits")
    ax_gap.set_ylabel("gap depth: min <Sigma>/Sigma_0, 0.8 < r < 1.2")
    ax_gap.set_title("gap depth over time, and cost", fontsize=9)
    ax_gap.legend(fontsize=7)
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The binned radial profiles of density, velocity and pressure over the Sedov-Taylor solution, and accuracy
against cost, for one or more rsph-sedov output folders.

Usage: plot_sedov.py DIR [DIR ...] --png FILE
"""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    fig, axes = plt.subplots(1, 4, figsize=(19, 4.5))
    a_rho, a_v, a_p, a_cost = axes
    first = read_summary(args.dirs[0])
    for k, d in enumerate(args.dirs):
        s = read_summary(d)
        p = read_csv(os.path.join(d, "profile.csv"))
        if k == 0:
            a_rho.plot(p["r"], p["rho_exact"], "k-", lw=1, label="exact (binned)")
            a_v.plot(p["r"], p["v_exact"], "k-", lw=1)
            a_p.plot(p["r"], p["P_exact"], "k-", lw=1)
        label = f"{method_label(s)} {s['dim']}D n={s['n']} {s['kernel']}"
        a_rho.plot(p["r"], p["rho"], ".-", ms=3, lw=0.8, label=label)
        a_v.plot(p["r"], p["v"], ".-", ms=3, lw=0.8)
        a_p.plot(p["r"], p["P"], ".-", ms=3, lw=0.8)
        a_cost.scatter([s["wall_seconds"]], [s["L1_rho"]], label=label)
        a_cost.annotate(f"R {s['shock_radius']:.3f}", (s["wall_seconds"], s["L1_rho"]), fontsize=7)
    for a, name in ((a_rho, r"$\rho$"), (a_v, "$v_r$"), (a_p, "P")):
        a.axvline(first["shock_radius_exact"], color="0.6", lw=0.8, ls=":")
        a.set_xlabel("r")
        a.set_ylabel(name)
    a_rho.legend(fontsize=7)
    a_cost.set_xscale("log")
    a_cost.set_yscale("log")
    a_cost.set_xlabel("wall seconds")
    a_cost.set_ylabel(r"L1($\rho$), bins out to 1.5 R")
    a_cost.set_title("accuracy against cost")
    a_cost.legend(fontsize=7)
    fig.suptitle(f"Sedov-Taylor blast, t = {first['time']:.4g} (exact shock radius {first['shock_radius_exact']:.3f})")
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

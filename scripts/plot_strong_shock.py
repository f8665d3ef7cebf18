#!/usr/bin/python3
"""Density and velocity of every particle over the exact solution (Fig. 4 analogue) for one or more
rsph-strong-shock output folders, and accuracy against cost.

Usage: plot_strong_shock.py DIR [DIR ...] --png FILE
"""
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    fig, (a_rho, a_v, a_cost) = plt.subplots(1, 3, figsize=(16, 4.5))
    exact = read_csv(os.path.join(args.dirs[0], "exact.csv"))
    a_rho.plot(exact["x"], exact["rho"], "k-", lw=1, label="exact")
    a_v.plot(exact["x"], exact["v"], "k-", lw=1, label="exact")
    for d in args.dirs:
        s = read_summary(d)
        p = read_csv(os.path.join(d, "particles.csv"))
        label = f"{method_label(s)} a={s['alpha']:g} b={s['beta']:g} ({s['particles']} particles)"
        a_rho.plot(p["x"], p["rho"], ".", ms=1.5, label=label)
        a_v.plot(p["x"], p["v"], ".", ms=1.5, label=label)
        a_cost.scatter([s["wall_seconds"]], [s["L1_rho"]], label=label)
        a_cost.annotate(f"shock {s['shock_position']:.3f}\npenetration {s['penetration_fraction']:.2f}",
                        (s["wall_seconds"], s["L1_rho"]), fontsize=7)
    a_rho.set_xlim(0.3, 1.0)
    a_v.set_xlim(0.3, 1.0)
    a_rho.set_xlabel("x")
    a_v.set_xlabel("x")
    a_rho.set_ylabel(r"$\rho$")
    a_v.set_ylabel("$v_x$")
    a_rho.legend(fontsize=7, markerscale=5)
    a_cost.set_xscale("log")
    a_cost.set_xlabel("wall seconds")
    a_cost.set_ylabel(r"L1($\rho$)")
    a_cost.set_title("accuracy against cost")
    fig.suptitle("Strong shock (pressure ratio 1e10), t = 2.5e-6")
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

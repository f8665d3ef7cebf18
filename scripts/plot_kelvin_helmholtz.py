#!/usr/bin/python3
"""Density maps at t = tau_KH (the analogue of Fig. 5) and mode amplitude against time for
rsph-kelvin-helmholtz output folders.

Usage: plot_kelvin_helmholtz.py DIR [DIR ...] --png FILE
"""
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, load, method_label, read_csv, read_summary, save_figure  # noqa: E402


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    n = len(args.dirs)
    fig = plt.figure(figsize=(6.5 * min(n, 2), 3.4 * ((n + 1) // 2) + 3.6))
    grid = fig.add_gridspec((n + 1) // 2 + 1, 2)
    amp_ax = fig.add_subplot(grid[-1, :])
    for i, d in enumerate(args.dirs):
        s = read_summary(d)
        label = f"{method_label(s)}, alpha_u = {s['alpha_u']:g}, 1/dx = {s['cells']}"
        if "h_over_dx" in s:  # older summaries lack it
            label += f", {'h/dx' if s['method'] == 'rsph' else 'eta'} = {s['h_over_dx']:g}"
        ax = fig.add_subplot(grid[i // 2, i % 2])
        fields, attrs = load(os.path.join(d, "snap_00001.h5"))
        x, rho, t = fields["x"], fields["rho"], attrs["time"]
        size = 60000.0 / len(rho)
        sc = ax.scatter(x[:, 0], x[:, 1], c=rho, s=size, cmap="viridis", vmin=1, vmax=10, linewidths=0)
        ax.set_xlim(-0.5, -0.5 + s.get("wavelengths", 6) / 6)  # the box holds `wavelengths` of 1/6
        ax.set_ylim(0, 0.5)
        ax.set_aspect("equal")
        narrow = s.get("wavelengths", 6) < 6  # a narrow box: the title in three lines, else two
        title = f"{label}:\nt = {t:.2f}, {s['particles']} particles, {s['wall_seconds']:.0f} s"
        if "overturned_fraction" in s:
            title += f",{chr(10) if narrow else ' '}{100 * s['overturned_fraction']:.0f} % overturned"
        ax.set_title(title, fontsize=9)
        fig.colorbar(sc, ax=ax, fraction=0.025)
        amp = read_csv(os.path.join(d, "amplitude.csv"))
        amp_ax.plot(amp["time"], amp["amplitude"], label=label)
        tau = s["tau_KH"]
    sigma = 2 * math.pi / tau
    t_lin = [0.05 * tau, 0.6 * tau]
    amp_ax.plot(t_lin, [0.01 * math.exp(sigma * (tt - t_lin[0])) for tt in t_lin], "k:", label="linear theory slope")
    amp_ax.set_yscale("log")
    amp_ax.set_ylim(3e-3, 0.5)
    amp_ax.set_xlabel("t")
    amp_ax.set_ylabel("mode amplitude (McNally et al. 2012)")
    amp_ax.legend(fontsize=8)
    save_figure(fig, args.png, dpi=100)


if __name__ == "__main__":
    main()

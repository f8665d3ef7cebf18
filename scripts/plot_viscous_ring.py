#!/usr/bin/python3
"""Surface density of the viscous ring against radius at each snapshot (mean over azimuth with its range)
over the analytic solution at the prescribed viscosity (Fig. 8-10 analogue), for one or more
rsph-viscous-ring output folders.

Usage: plot_viscous_ring.py DIR [DIR ...] --png FILE
"""
import glob
import os
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def profiles(folder):
    files = glob.glob(os.path.join(folder, "profile_*.csv"))
    return sorted(files, key=lambda p: int(re.search(r"profile_(\d+)", p).group(1)))


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    fig, axes = plt.subplots(1, len(args.dirs), figsize=(6 * len(args.dirs), 4.2), squeeze=False, sharey=True)
    for ax, d in zip(axes[0], args.dirs):
        s = read_summary(d)
        for i, path in enumerate(profiles(d)):
            p = read_csv(path)
            tau = s["snapshots"][i]["tau"] if i < len(s.get("snapshots", [])) else None
            line = ax.plot(p["x"], p["sigma_mean"], lw=1, label=f"tau = {tau:g}" if tau is not None else None)[0]
            ax.fill_between(p["x"], p["sigma_min"], p["sigma_max"], color=line.get_color(), alpha=0.2, lw=0)
            ax.plot(p["x"], p["sigma_exact"], "k--", lw=0.8, label="analytic, nu_s" if i == 0 else None)
        cycle = "no regularization" if s["cycle"] == 0 else f"c_r = {s['cycle']:g}"
        ax.set_title(f"{method_label(s) if s['cycle'] else 'SPH'}, {cycle}, h/dx = {s['h_over_dx']:g}: "
                     f"nu_eff/nu_s = {s['nu_eff_over_nu_s']:.3f},\nnoise {s['noise_error']:.3f}, "
                     f"{s['wall_seconds']:.0f} s", fontsize=9)
        ax.set_xlabel("R / R_0")
        ax.set_xlim(0, 2)
    axes[0][0].set_ylabel("Sigma (mean over azimuth; band: min-max)")
    axes[0][0].legend(fontsize=7)
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

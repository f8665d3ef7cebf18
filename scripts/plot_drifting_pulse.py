#!/usr/bin/python3
"""Four panels like Fig. 2 of the paper: co-moving density profiles after 0..400 regularizations.

Usage: plot_drifting_pulse.py OUT_DIR [--png FILE]
"""
import argparse
import glob
import os
import re

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import read_csv, read_summary, save_figure  # noqa: E402


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--png")
    args = ap.parse_args()
    summary = read_summary(args.out)
    shifts = sorted(summary["cases"], key=float)
    fig, axes = plt.subplots(1, len(shifts), figsize=(3.6 * len(shifts), 3.4), sharey=True, squeeze=False)
    styles = ["-", ":", "--", "-.", (0, (3, 1, 1, 1, 1, 1))]
    for ax, shift in zip(axes[0], shifts):
        files = glob.glob(os.path.join(args.out, f"shift_{shift}", "profile_*.csv"))
        files.sort(key=lambda p: int(re.search(r"profile_(\d+)", p).group(1)))
        for style, path in zip(styles * 3, files):
            n = int(re.search(r"profile_(\d+)", path).group(1))
            p = read_csv(path)
            rows = sorted(zip(p["x"], p["rho"]))
            ax.plot([r[0] for r in rows], [r[1] for r in rows], linestyle=style, color="k", lw=1, label=f"{n}")
        widths = summary["cases"][shift]["width_mass"]
        last = max(widths, key=int)
        ax.set_title(f"$T_{{reg}} v_d/\\Delta$ = {shift}\nwidth {widths['0']:.2f} -> {widths[last]:.2f} $\\Delta$",
                     fontsize=9)
        ax.set_xlabel(r"$x/\Delta$ (co-moving)")
        c = 0.5 * summary["cells"]
        ax.set_xlim(c - 12, c + 12)
    axes[0][0].set_ylabel(r"$\rho$")
    axes[0][0].legend(title="regularizations", fontsize=7)
    png = args.png or os.path.join(args.out, "drifting_pulse.png")
    save_figure(fig, png)


if __name__ == "__main__":
    main()

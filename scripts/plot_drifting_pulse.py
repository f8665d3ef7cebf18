#!/usr/bin/python3
"""Four panels like Fig. 2 of the paper: co-moving density profiles after 0..400 regularizations (in 2D and 3D
the densest particle at each x, through the pulse's centre).

Usage: plot_drifting_pulse.py DIR [DIR ...] [--png FILE]   (a row per folder; FILE defaults to
DIR/drifting_pulse.png of the first)
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
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--png")
    args = ap.parse_args()
    summaries = [read_summary(d) for d in args.dirs]
    shifts = sorted(summaries[0]["cases"], key=float)
    fig, axes = plt.subplots(len(args.dirs), len(shifts), figsize=(3.6 * len(shifts), 3.4 * len(args.dirs)),
                             sharey=True, squeeze=False)
    for row, out, summary in zip(axes, args.dirs, summaries):
        draw_row(row, out, summary, shifts)
    png = args.png or os.path.join(args.dirs[0], "drifting_pulse.png")
    save_figure(fig, png)


def draw_row(axes, out, summary, shifts):
    styles = ["-", ":", "--", "-.", (0, (3, 1, 1, 1, 1, 1))]
    for ax, shift in zip(axes, shifts):
        files = glob.glob(os.path.join(out, f"shift_{shift}", "profile_*.csv"))
        files.sort(key=lambda p: int(re.search(r"profile_(\d+)", p).group(1)))
        for style, path in zip(styles * 3, files):
            n = int(re.search(r"profile_(\d+)", path).group(1))
            p = read_csv(path)
            rows = sorted(zip(p["x"], p["rho"]))
            if summary.get("dim", 1) > 1:  # a square or cube: the densest particle at each x, through its centre
                densest = {}
                for x, rho in rows:
                    densest[round(x, 6)] = max(rho, densest.get(round(x, 6), rho))
                rows = sorted(densest.items())
            ax.plot([r[0] for r in rows], [r[1] for r in rows], linestyle=style, color="k", lw=1, label=f"{n}")
        widths = summary["cases"][shift]["width_mass"]
        last = max(widths, key=int)
        ax.set_title(f"{summary.get('remap', 'first')}-order remap, $T_{{reg}} v_d/\\Delta$ = {shift}\n"
                     f"width {widths['0']:.2f} -> {widths[last]:.2f} $\\Delta$", fontsize=9)
        ax.set_xlabel(r"$x/\Delta$ (co-moving)")
        c = 0.5 * summary["cells"]
        ax.set_xlim(c - 12, c + 12)
    axes[0].set_ylabel(r"$\rho$")
    axes[0].legend(title="regularizations", fontsize=7)


if __name__ == "__main__":
    main()

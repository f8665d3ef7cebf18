#!/usr/bin/python3
"""The density at the sensor against time over the undamped linear wave and the fitted decay e^(-2 pi gamma t/P)
of eq. (11), for one or more rsph-linear-wave output folders.

Usage: plot_linear_wave.py DIR [DIR ...] --png FILE
"""
import math
import os

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from rsph_plot import folders_and_png, method_label, read_csv, read_summary, save_figure  # noqa: E402


def label(s):
    what = method_label(s) if s.get("r", 0) > 0 else f"SPH, alpha = {s.get('alpha', 0):g}"
    return f"{what}, lambda = {s['wavelength_cells']} dx, r = {s['r']:g}, h/dx = {s['h_over_dx']:g}"


def main():
    args = folders_and_png(__doc__.splitlines()[0])
    fig, ax = plt.subplots(figsize=(9, 4.2))
    for d in args.dirs:
        s = read_summary(d)
        sensor = read_csv(os.path.join(d, "sensor.csv"))
        t, drho = sensor["time"], sensor["delta_rho"]
        period = t[-1] / s["periods"]
        first = [abs(v) for tt, v in zip(t, drho) if tt < period]
        amp = max(first)
        tp = [tt / period for tt in t]
        line = ax.plot(tp, [v / amp for v in drho], lw=0.8,
                       label=f"{label(s)}: gamma = {s['gamma']:.3g}, {s['wall_seconds']:.1f} s")[0]
        decay = [math.exp(-2 * math.pi * s["gamma"] * x) for x in tp]
        ax.plot(tp, decay, "--", color=line.get_color(), lw=1)
        ax.plot(tp, [-v for v in decay], "--", color=line.get_color(), lw=1)
    ax.axhline(1, color="k", lw=0.8, label="exact (undamped)")
    ax.axhline(-1, color="k", lw=0.8)
    ax.set_xlabel("t / wave period")
    ax.set_ylabel("delta rho at the sensor / first-period peak")
    ax.set_title("linear sound wave (paper §3.1); dashed: decay of eq. (11) with the measured gamma", fontsize=9)
    ax.legend(fontsize=7, loc="lower left")
    save_figure(fig, args.png)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Sweep driver for rsph-kelvin-helmholtz: runs RSPH without conductivity over a grid of 1/Delta and h/Delta
(one thread per run, --jobs runs at a time; runs whose summary.json exists are kept unless --rerun),
writes sweep.csv (cells, h_over_dx, amplification, peak, growth_rate, energy_error, wall_seconds) and
sweep.png: M(tau_KH)/M(0) and the peak against h/Delta, one line per 1/Delta, and amplification against
wall seconds. The README's h/Delta table comes from

  sweep_kelvin_helmholtz.py --out out/kh-scan --cells 128,192,256 --h-over-dx 1.0,1.1,1.2

Extra flags after -- go to every run (e.g. -- --reg-steps 24 --courant 0.15).
"""
import argparse
import concurrent.futures as cf
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import floats, read_csv, run_example, save_figure  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BIN = os.path.join(HERE, "..", "build", "bin", "rsph-kelvin-helmholtz")


def main():
    argv = sys.argv[1:]
    extra = argv[argv.index("--") + 1:] if "--" in argv else []
    argv = argv[: argv.index("--")] if "--" in argv else argv
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--binary", default=DEFAULT_BIN)
    ap.add_argument("--cells", default="128,256", help="1/Delta values")
    ap.add_argument("--h-over-dx", default="1.0,1.1,1.2", help="h/Delta values, crossed with --cells")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--rerun", action="store_true")
    args = ap.parse_args(argv)
    if not os.path.exists(args.binary):
        sys.exit(f"{args.binary} not found: build the examples first (scripts/build.sh)")
    grid = [(int(c), h) for c in floats(args.cells) for h in floats(args.h_over_dx)]
    if not grid:
        sys.exit("nothing to run: --cells and --h-over-dx must name at least one value each")

    def one(run):
        cells, hdx = run
        out = os.path.join(args.out, f"cells{cells}_hdx{hdx:g}")
        s = run_example(args.binary, out, ["--cells", cells, "--h-over-dx", hdx] + extra, rerun=args.rerun)
        amp = read_csv(os.path.join(out, "amplitude.csv"))["amplitude"]
        return {"cells": cells, "h_over_dx": hdx, "amplification": s["amplification"],
                "peak": max(amp) / amp[0], "growth_rate": s["growth_rate"], "energy_error": s["energy_error"],
                "wall_seconds": s["wall_seconds"]}

    os.makedirs(args.out, exist_ok=True)
    with cf.ThreadPoolExecutor(max_workers=max(1, args.jobs)) as pool:
        rows = list(pool.map(one, grid))
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    print(f"wrote {os.path.join(args.out, 'sweep.csv')}")

    fig, (ax, cost) = plt.subplots(1, 2, figsize=(11, 4))
    for cells in sorted({r["cells"] for r in rows}):
        line = sorted((r for r in rows if r["cells"] == cells), key=lambda r: r["h_over_dx"])
        hs = [r["h_over_dx"] for r in line]
        p = ax.plot(hs, [r["amplification"] for r in line], marker="o", label=f"1/dx = {cells}, at tau_KH")
        ax.plot(hs, [r["peak"] for r in line], marker="^", ls="--", color=p[0].get_color(), label=f"1/dx = {cells}, peak")
        cost.plot([r["wall_seconds"] for r in line], [r["amplification"] for r in line], marker="o",
                  color=p[0].get_color(), label=f"1/dx = {cells}")
    for a in (ax, cost):
        a.axhline(5.0, color="k", ls=":", lw=0.8)
        a.set_ylabel("M / M(0)")
        a.legend(fontsize=8)
    ax.set_xlabel("h / Delta")
    ax.set_title("RSPH, no conductivity: the seeded mode against h/Delta")
    cost.set_xscale("log")
    cost.set_xlabel("wall seconds (one thread)")
    cost.set_title("amplification at tau_KH against cost")
    save_figure(fig, os.path.join(args.out, "sweep.png"))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Sweep driver for rsph-viscous-ring: runs any subset of the paper's §4 parameter study in parallel
(one thread per run, --jobs runs at a time), skips runs whose summary.json exists (--rerun to redo),
and draws the analogues of Figs. 7-9 (profiles at tau* = 0.090 against the analytic and fitted
solutions), Fig. 10 (nu_eff / nu_s against c_r, h/Delta and h, min-max over time as error bars),
Fig. 11 (noise error against the same), and accuracy against cost for every run.

Examples:
  sweep_viscous_ring.py --out out/ring                                   # the paper's full study (many hours)
  sweep_viscous_ring.py --out out/ring-quick --preset quick --hs 0.04,0.05,0.06 --h 0.04
  sweep_viscous_ring.py --out out/ring --plot-only
"""
import argparse
import concurrent.futures as cf
import csv
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import floats, read_csv, run_example, save_figure  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BIN = os.path.join(HERE, "..", "build", "bin", "rsph-viscous-ring")


def run_name(cycle, hdx, h, viscosity, max_bin=0, lattice="square"):
    bins = f"_bins{max_bin}" if max_bin > 0 else ""
    hexagons = "_hex" if lattice == "hexagonal" else ""
    return f"c{cycle}_hdx{hdx:g}_h{h:g}_{viscosity}{bins}{hexagons}"


def errorbar(ax, xs, runs, key, label):
    pts = sorted((x, r) for x, r in zip(xs, runs) if r is not None)
    if not pts:
        return
    x = [p[0] for p in pts]
    if key == "nu":
        y = [p[1]["nu_eff_over_nu_s"] for p in pts]
        lo = [p[1]["nu_eff_over_nu_s"] - p[1]["nu_eff_min"] / p[1]["nu_s"] for p in pts]
        hi = [p[1]["nu_eff_max"] / p[1]["nu_s"] - p[1]["nu_eff_over_nu_s"] for p in pts]
        ax.errorbar(x, y, yerr=[lo, hi], marker="o", capsize=3, label=label)
    else:
        ax.plot(x, [p[1]["noise_error"] for p in pts], marker="o", label=label)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--binary", default=DEFAULT_BIN)
    ap.add_argument("--cycles", default="1,2,4,8,16,32", help="c_r values (units of 40 steps)")
    ap.add_argument("--h-over-dx", default="1.0,1.2,1.4,1.6,1.8,2.0", help="h/Delta values, crossed with --cycles")
    ap.add_argument("--h", type=float, default=0.02, help="h of the c_r x h/Delta grid")
    ap.add_argument("--hs", default="0.015,0.02,0.025,0.03,0.035,0.04", help="h values at c_r = 4, h/Delta = 1.6")
    ap.add_argument("--no-regularization", action="store_true", help="also run c_r = 0 (plain SPH) at each h/Delta")
    ap.add_argument("--viscosity", default="mg", help="mg or ns")
    ap.add_argument("--preset", default="paper", help="passed on: quick uses nu = 4.8e-4")
    ap.add_argument("--max-bin", type=int, default=0, help="passed on: individual time steps (mg only)")
    ap.add_argument("--lattice", default="square", help="passed on: square or hexagonal")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--rerun", action="store_true")
    ap.add_argument("--plot-only", action="store_true")
    args = ap.parse_args()
    if not args.plot_only and not os.path.exists(args.binary):
        sys.exit(f"sweep_viscous_ring: {args.binary} not found; build first (scripts/build.sh)")

    cycles = [int(c) for c in floats(args.cycles)]
    hdxs = floats(args.h_over_dx)
    hs = floats(args.hs)
    grid = [(c, r, args.h) for c in cycles for r in hdxs]
    grid += [(4, 1.6, h) for h in hs]
    if args.no_regularization:
        grid += [(0, r, args.h) for r in hdxs]
    grid = sorted(set(grid), key=lambda g: (-g[1] ** 2 / g[2] ** 2, g))  # the costliest first
    results = {}
    futures = {}
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        for c, r, h in grid:
            folder = os.path.join(args.out, run_name(c, r, h, args.viscosity, args.max_bin, args.lattice))
            if args.plot_only:
                if os.path.exists(os.path.join(folder, "summary.json")):
                    with open(os.path.join(folder, "summary.json")) as f:
                        results[(c, r, h)] = json.load(f)
                continue
            cli = ["--cycle", c, "--h-over-dx", r, "--h", h, "--viscosity", args.viscosity, "--preset", args.preset,
                   "--max-bin", args.max_bin, "--lattice", args.lattice]
            futures[pool.submit(run_example, args.binary, folder, cli, args.rerun)] = (c, r, h)
        for fut in cf.as_completed(futures):
            key = futures[fut]
            try:
                results[key] = fut.result()
                s = results[key]
                print(f"c_r={key[0]:>2} h/dx={key[1]:.1f} h={key[2]:.3f}: nu_eff/nu_s={s['nu_eff_over_nu_s']:.3f} "
                      f"noise={s['noise_error']:.3e} {s['wall_seconds']:.0f} s", flush=True)
            except RuntimeError as e:
                print(e, file=sys.stderr)
    if not results:
        sys.exit("sweep_viscous_ring: no finished runs")

    table = os.path.join(args.out, "sweep.csv")
    with open(table, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["cycle", "h_over_dx", "h", "nu_eff_over_nu_s", "nu_eff_min_over_nu_s", "nu_eff_max_over_nu_s",
                    "noise_error", "particles_mean", "steps", "regularizations", "wall_seconds", "cpu_seconds"])
        for (c, r, h), s in sorted(results.items()):
            w.writerow([c, r, h, s["nu_eff_over_nu_s"], s["nu_eff_min"] / s["nu_s"], s["nu_eff_max"] / s["nu_s"],
                        s["noise_error"], s["particles_mean"], s["steps"], s["regularizations"], s["wall_seconds"],
                        s["cpu_seconds"]])

    h0 = args.h
    fig, axes = plt.subplots(3, 2, figsize=(11, 12))
    for col, key, label in ((0, "nu", r"$\nu_{eff}/\nu_s$"), (1, "noise", "noise error")):
        ax = axes[0][col]
        for r in hdxs:
            xs = [c for c in cycles]
            errorbar(ax, xs, [results.get((c, r, h0)) for c in xs], key, f"h/Δ={r:g}")
        ax.set_xscale("log", base=2)
        ax.set_xlabel("regularization cycle $c_r$ (×40 steps)")
        ax = axes[1][col]
        for c in cycles:
            errorbar(ax, hdxs, [results.get((c, r, h0)) for r in hdxs], key, f"$c_r$={c}")
        ax.set_xlabel("h/Δ")
        ax = axes[2][col]
        errorbar(ax, hs, [results.get((4, 1.6, h)) for h in hs], key, "$c_r$=4, h/Δ=1.6")
        ax.set_xlabel("h ($R_0$)")
        for a in axes[:, col]:
            a.set_ylabel(label)
            if key == "nu":
                a.axhline(1.0, color="k", lw=0.8, ls=":")
            else:
                a.set_yscale("log")
            if a.get_legend_handles_labels()[0]:
                a.legend(fontsize=7)
    fig.suptitle(f"Viscous ring: effective viscosity (Fig. 10) and noise (Fig. 11), h = {h0:g} in the top rows")
    save_figure(fig, os.path.join(args.out, "fig10_fig11_nu_eff_noise.png"), dpi=120)

    # Figs. 7-9: profiles at the second snapshot (tau* = 0.090 by default)
    panels = [("c_r", [(c, 1.6, h0) for c in cycles]), ("h/Δ", [(4, r, h0) for r in hdxs]),
              ("h", [(4, 1.6, h) for h in hs])]
    fig, axes = plt.subplots(len(panels), 1, figsize=(8, 12))
    for ax, (name, keys) in zip(axes, panels):
        for i, key in enumerate(k for k in keys if k in results):
            folder = os.path.join(args.out, run_name(*key, args.viscosity, args.max_bin, args.lattice))
            p = read_csv(os.path.join(folder, "profile_2.csv"))
            value = {"c_r": key[0], "h/Δ": key[1], "h": key[2]}[name]
            line, = ax.plot(p["x"], p["sigma_mean"], lw=1.2, label=f"{name}={value:g}")
            ax.fill_between(p["x"], p["sigma_min"], p["sigma_max"], color=line.get_color(), alpha=0.15)
            ax.plot(p["x"], p["sigma_fit"], ls="-.", lw=0.8, color=line.get_color())
            if i == 0:
                ax.plot(p["x"], p["sigma_exact"], "k--", lw=1.0, label="analytic")
        ax.set_xlim(0.2, 1.8)
        ax.set_xlabel("R / $R_0$")
        ax.set_ylabel(r"$\Sigma$")
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=7)
    fig.suptitle(r"Profiles at the second snapshot: mean, min-max band, fit (dash-dot), analytic (dashed)")
    save_figure(fig, os.path.join(args.out, "fig7_9_profiles.png"), dpi=120)

    # accuracy against cost
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.5))
    for (c, r, h), s in sorted(results.items()):
        marker = "o" if h == h0 else "s"
        axes[0].scatter(s["wall_seconds"], abs(s["nu_eff_over_nu_s"] - 1.0), marker=marker)
        axes[0].annotate(f"{c},{r:g},{h:g}", (s["wall_seconds"], abs(s["nu_eff_over_nu_s"] - 1.0)), fontsize=6)
        axes[1].scatter(s["wall_seconds"], s["noise_error"], marker=marker)
        axes[1].annotate(f"{c},{r:g},{h:g}", (s["wall_seconds"], s["noise_error"]), fontsize=6)
    axes[0].set_ylabel(r"$|\nu_{eff}/\nu_s - 1|$")
    axes[1].set_ylabel("noise error")
    for a in axes:
        a.set_xlabel("wall seconds (one thread)")
        a.set_xscale("log")
        a.set_yscale("log")
    fig.suptitle("Viscous ring: accuracy against cost (labels: c_r, h/Δ, h)")
    save_figure(fig, os.path.join(args.out, "accuracy_vs_cost.png"), dpi=120)
    print(f"wrote {table}")


if __name__ == "__main__":
    main()

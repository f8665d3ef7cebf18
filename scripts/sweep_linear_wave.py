#!/usr/bin/python3
"""Sweep driver for rsph-linear-wave: runs any subset of the paper's Fig. 3 settings (and the stability
scan) in parallel, collects every summary.json into CSV, and draws gamma against lambda/Delta (Fig. 3),
the stability map, and accuracy against cost.

Examples:
  sweep_linear_wave.py --out out/linear-wave                       # Fig. 3 for lambda <= 48 Delta
  sweep_linear_wave.py --out out/lw --wavelengths 12,24,48,96,192   # the full figure (hours)
  sweep_linear_wave.py --out out/lw --stability-only
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
from rsph_plot import floats, run_example, save_figure  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_BIN = os.path.join(HERE, "..", "build", "bin", "rsph-linear-wave")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--binary", default=DEFAULT_BIN)
    ap.add_argument("--wavelengths", default="12,24,48", help="lambda/Delta values (paper: 12,24,48,96,192)")
    ap.add_argument("--r", default="0.75,1.25,2.25,4.25,8.25,16.25", help="RSPH T_reg/P_w values")
    ap.add_argument("--alphas", default="0,0.1,0.3,1.0", help="plain SPH alpha values (beta = 2 alpha)")
    ap.add_argument("--periods", type=int, default=100)
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    ap.add_argument("--stability-only", action="store_true")
    ap.add_argument("--no-stability", action="store_true")
    ap.add_argument("--stability-h", default="1.0,1.2,1.5,2.0")
    ap.add_argument("--stability-wavelength", type=int, default=24)
    ap.add_argument("--stability-periods", type=int, default=20)
    args = ap.parse_args()
    if not os.path.exists(args.binary):
        sys.exit(f"sweep_linear_wave: {args.binary} not found; build first (scripts/build.sh)")

    jobs = []
    if not args.stability_only:
        for lam in [int(x) for x in floats(args.wavelengths)]:
            for r in floats(args.r):
                jobs.append(("rsph", f"r={r:g}", lam, ["--wavelength", lam, "--r", r, "--periods", args.periods]))
            for a in floats(args.alphas):
                jobs.append(("sph", f"alpha={a:g}", lam,
                             ["--wavelength", lam, "--r", 0, "--alpha", a, "--periods", args.periods]))
    if not args.no_stability:
        for kern in ["cubic", "quintic"]:
            for h in floats(args.stability_h):
                jobs.append(("stability", f"{kern} h/D={h:g}", args.stability_wavelength,
                             ["--wavelength", args.stability_wavelength, "--r", 0, "--kernel", kern, "--h-over-dx", h,
                              "--jitter", 1e-4, "--periods", args.stability_periods]))
    os.makedirs(args.out, exist_ok=True)
    results = []
    with cf.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = {}
        for kind, setting, lam, a in jobs:
            sub = os.path.join(args.out, kind, setting.replace(" ", "_").replace("/", ""), f"lambda_{lam}")
            futures[pool.submit(run_example, args.binary, sub, a)] = (kind, setting, lam)
        for fut in cf.as_completed(futures):
            kind, setting, lam = futures[fut]
            s = fut.result()
            results.append((kind, setting, lam, s))
            print(f"{kind:9} {setting:18} lambda={lam:4}: gamma={s['gamma']:+.3e} phase={s['phase_error']:+.2e} "
                  f"noise x{s['velocity_noise_growth']:.3g} amp x{s['amplitude_growth']:.3g} {s['wall_seconds']:.1f} s "
                  f"(cpu {s['cpu_seconds']:.1f} s)",
                  flush=True)
    results.sort(key=lambda t: (t[0], t[1], t[2]))
    with open(os.path.join(args.out, "sweep.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["kind", "setting", "wavelength_cells", "gamma", "phase_error", "amplitude_growth",
                    "velocity_noise_growth", "wall_seconds", "cpu_seconds", "steps", "particles"])
        for kind, setting, lam, s in results:
            w.writerow([kind, setting, lam, s["gamma"], s["phase_error"], s["amplitude_growth"],
                        s["velocity_noise_growth"], s["wall_seconds"], s["cpu_seconds"], s["steps"], s["particles"]])

    fig3 = [r for r in results if r[0] != "stability"]
    if fig3:
        fig, (ax, ax2) = plt.subplots(1, 2, figsize=(12, 4.5))
        for kind, style in [("rsph", "-o"), ("sph", ":s")]:
            for setting in sorted({r[1] for r in fig3 if r[0] == kind}, key=lambda t: float(t.split("=")[1])):
                pts = sorted((r[2], r[3]["gamma"]) for r in fig3 if r[0] == kind and r[1] == setting)
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style, ms=4, label=f"{kind.upper()} {setting}")
        ax.set_xscale("log", base=2)
        ax.set_yscale("symlog", linthresh=1e-5)
        ax.set_xlabel(r"$\lambda/\Delta$")
        ax.set_ylabel(r"damping rate $\gamma$ (eq. 11)")
        ax.set_title(f"Fig. 3 analogue: {args.periods} periods, quintic kernel, h/$\\Delta$ = 1.2")
        ax.legend(fontsize=7, ncol=2)
        for kind, marker in [("rsph", "o"), ("sph", "s")]:
            pts = [r for r in fig3 if r[0] == kind]
            ax2.scatter([r[3]["cpu_seconds"] for r in pts], [abs(r[3]["gamma"]) for r in pts], marker=marker,
                        label=kind.upper())
        ax2.set_xscale("log")
        ax2.set_yscale("log")
        ax2.set_xlabel("CPU seconds (one thread)")
        ax2.set_ylabel(r"$|\gamma|$ (error: any damping or growth)")
        ax2.set_title("accuracy against cost")
        ax2.legend()
        save_figure(fig, os.path.join(args.out, "fig3_damping.png"))
    stab = [r for r in results if r[0] == "stability"]
    if stab:
        kernels = ["cubic", "quintic"]
        hs = sorted({float(r[1].split("=")[1]) for r in stab})
        grid = [[float("nan")] * len(hs) for _ in kernels]
        for _, setting, _, s in stab:
            kern, h = setting.split(" ")[0], float(setting.split("=")[1])
            g = max(s["velocity_noise_growth"], s["amplitude_growth"], 1.0 / max(s["amplitude_growth"], 1e-300))
            grid[kernels.index(kern)][hs.index(h)] = g
        fig, ax = plt.subplots(figsize=(6, 3))
        import math
        im = ax.imshow([[math.log10(g) for g in row] for row in grid], cmap="RdYlGn_r", vmin=0, vmax=3, aspect="auto")
        ax.set_xticks(range(len(hs)), [f"{h:g}" for h in hs])
        ax.set_yticks(range(len(kernels)), kernels)
        for i, row in enumerate(grid):
            for j, g in enumerate(row):
                ax.text(j, i, f"x{g:.3g}", ha="center", va="center", fontsize=8)
        ax.set_xlabel(r"h/$\Delta$")
        ax.set_title("plain SPH, no viscosity: growth of noise or amplitude\n(log10 colour; > 2 = unstable)",
                     fontsize=9)
        fig.colorbar(im, ax=ax)
        save_figure(fig, os.path.join(args.out, "stability_map.png"))
    print(f"wrote {args.out}/sweep.csv")


if __name__ == "__main__":
    main()

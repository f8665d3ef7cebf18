#!/usr/bin/python3
"""The planet disk against FARGO3D: for each run folder of rsph-planet-disk (summary.json, profile.csv), the
azimuthal average's L1 against FARGO3D's converged 768 x 256 profile over 0.6-2.0 and each region, the gap depth
and the CPU time, and the figures of the cuts of Figs. 13 and 14 (cut_figures); writes markdown tables and draws
error against cost, a point per run, a line per lattice and remap, FARGO3D's three resolutions as points on the
same chart, and the profiles over FARGO3D's.

  disk_vs_fargo3d.py out/disk_square out/disk_rings_first out/disk_rings_second --png disk_vs_fargo3d.png
"""
import argparse
import math
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import (FARGO3D_LABEL, FARGO3D_PROFILE, FARGO3D_REGIONS, fargo3d_l1s, fargo3d_runs,  # noqa: E402
                       read_csv, read_summary, save_figure)


def run_row(folder):
    s = read_summary(folder)
    prof = read_csv(os.path.join(folder, "profile.csv"))
    l1 = fargo3d_l1s(prof["r"], prof["sigma_over_sigma0"])
    label = f"{s.get('method', 'rsph')} {s.get('lattice', 'square')} {s.get('remap', '')}".strip()
    if s.get("max_steps", 160) != 160:  # Appendix A's cap on the steps between remaps, the paper's 160 in §5
        label += " remap every block" if s["max_steps"] == 1 else f" max-steps {s['max_steps']}"
    if s.get("rsph_alpha", 0.0) > 0.0:
        label += f" switched viscosity {s['rsph_alpha']:g}/{s['rsph_beta']:g}"
    return {"folder": folder, "label": label, "particles": s["particles_initial"], "orbits": s["orbits"],
            "cpu": s["cpu_seconds"], "gap": s["gap_depth"], "l1": l1, "profile": prof, "cuts": cut_figures(folder)}


def cut_figures(folder):
    """The cuts of Figs. 13 and 14: opposite the planet (cut_phi_pi.csv) the gap's least Sigma/Sigma0 over
    0.8-1.2 and the largest beside it (0.6-0.9, 1.2-1.8), each with its radius; along the orbit (cut_r_a.csv) the
    largest Sigma within 40-80 degrees ahead of the planet (L4) and behind it (L5), over the median of the orbit
    farther than 100 degrees from the planet: above 1, gas gathered at the Lagrange points."""
    opp = read_csv(os.path.join(folder, "cut_phi_pi.csv"))
    pairs = list(zip(opp["r"], opp["sigma_over_sigma0"]))

    def extreme(lo, hi, pick):
        return pick(((v, r) for r, v in pairs if lo <= r <= hi), default=(float("nan"), float("nan")))

    orbit = read_csv(os.path.join(folder, "cut_r_a.csv"))
    deg = [(math.degrees(p), v) for p, v in zip(orbit["phi"], orbit["sigma_over_sigma0"])]
    far = sorted(v for d, v in deg if abs(d) > 100.0)
    floor = far[len(far) // 2] if far else float("nan")

    def lagrange(sign):
        return max((v for d, v in deg if 40.0 <= sign * d <= 80.0), default=float("nan")) / floor

    return {"gap": extreme(0.8, 1.2, min), "inner": extreme(0.6, 0.9, max), "outer": extreme(1.2, 1.8, max),
            "floor": floor, "L4": lagrange(1.0), "L5": lagrange(-1.0)}


def cut_table(rows):
    lines = ["| run | opposite: gap's least (r) | inner peak (r) | outer peak (r) | along the orbit: median away "
             "from the planet | L4 / median | L5 / median |", "|---" * 7 + "|"]
    for r in rows:
        c = r["cuts"]
        lines.append(f"| {r['label']} | {c['gap'][0]:.3f} ({c['gap'][1]:.2f}) | {c['inner'][0]:.2f} "
                     f"({c['inner'][1]:.2f}) | {c['outer'][0]:.2f} ({c['outer'][1]:.2f}) | {c['floor']:.3f} | "
                     f"{c['L4']:.2f} | {c['L5']:.2f} |")
    return "\n".join(lines)


def table(rows, fargo):
    regions = " | ".join(f"L1 {lo}-{hi}" for lo, hi in FARGO3D_REGIONS)
    lines = [f"| run | particles / cells | orbits | {regions} | gap depth | user CPU s |",
             "|---" * (6 + len(FARGO3D_REGIONS) - 1) + "|"]
    for name, cells, cpu, l1, gap in fargo:
        lines.append(f"| FARGO3D {name} | {cells} | 100 | " + " | ".join(f"{v:.3f}" for v in l1) +
                     f" | {gap:.3f} | {cpu:.0f} |")
    for r in rows:
        lines.append(f"| {r['label']} | {r['particles']} | {r['orbits']:g} | " +
                     " | ".join(f"{v:.3f}" for v in r["l1"]) + f" | {r['gap']:.3f} | {r['cpu']:.0f} |")
    return "\n".join(lines)


def draw(rows, fargo, png):
    fig, (ax, ax_p) = plt.subplots(1, 2, figsize=(12, 4.5))
    fx = [f for f in fargo if f[3][0] > 0.0]
    ax.plot([f[2] for f in fx], [f[3][0] for f in fx], "ks--", label="FARGO3D (192x64, 384x128)")
    for name, _, cpu, l1, _ in fx:
        ax.annotate(name, (cpu, l1[0]), textcoords="offset points", xytext=(4, 4), fontsize=8)
    by_label = {}
    for r in rows:
        by_label.setdefault(r["label"], []).append(r)
    for label, rs in sorted(by_label.items()):
        rs.sort(key=lambda r: r["cpu"])
        ax.plot([r["cpu"] for r in rs], [r["l1"][0] for r in rs], "o-", label=label)
        ax_p.plot(rs[-1]["profile"]["r"], rs[-1]["profile"]["sigma_over_sigma0"], lw=1,
                  label=f"{label}, {rs[-1]['particles']} particles")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("user CPU seconds, 100 orbits")
    ax.set_ylabel("L1 of Sigma/Sigma_0 against FARGO3D 768x256, 0.6 < r < 2.0")
    ax.legend(fontsize=8)
    if os.path.exists(FARGO3D_PROFILE):
        ref = read_csv(FARGO3D_PROFILE)
        ax_p.plot(ref["r"], ref["sigma_over_sigma0"], "k-", lw=2, label=FARGO3D_LABEL)
    ax_p.set_xlim(0.4, 2.5)
    ax_p.set_xlabel("r")
    ax_p.set_ylabel("azimuthal average Sigma/Sigma_0")
    ax_p.legend(fontsize=7)
    save_figure(fig, png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("folders", nargs="+", help="rsph-planet-disk output folders")
    ap.add_argument("--png", default="disk_vs_fargo3d.png")
    ap.add_argument("--md", default=None, help="also write the table here")
    a = ap.parse_args()
    fargo = fargo3d_runs()
    if not fargo:
        sys.exit("disk_vs_fargo3d: no FARGO3D data in data/reference/fargo3d")
    rows = [run_row(f) for f in a.folders]
    text = table(rows, fargo) + "\n\n" + cut_table(rows)
    print(text)
    if a.md:
        with open(a.md, "w") as f:
            f.write(text + "\n")
    draw(rows, fargo, a.png)


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""The square lattice against the orbit-following rings on the disks: runs the viscous ring and the planet disk on
both lattices with both remaps (one thread per run, --jobs at a time; finished runs are kept), writes
lattices.md (a table per test) and draws error against cost, a point per run and a line per lattice and remap:
the ring's |nu_eff/nu_s - 1| against CPU seconds, and the disk's L1 against FARGO3D's converged profile with
FARGO3D's own resolutions as points on the same chart.

  compare_lattices.py --out out/lattices                          # the ring's quick c_r row, the disk at LOW
  compare_lattices.py --out out/lattices --ring-paper             # the ring at h = 0.02 (hours per run)
  compare_lattices.py --out out/lattices --only disk --disk-resolutions low,med,high
  compare_lattices.py --out out/lattices --only drift             # the disk without a planet (--q 0)
  compare_lattices.py --out out/lattices --only neptune           # Neptune (--q 1e-4), gap depth and profile
"""
import argparse
import concurrent.futures as cf
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import (FARGO3D_REGIONS, fargo3d_l1s, fargo3d_runs, read_csv, read_summary, run_example,  # noqa: E402
                       save_figure)

HERE = os.path.dirname(os.path.abspath(__file__))
BIN = os.path.join(HERE, "..", "build", "bin")
LATTICES = ("square", "rings")
ORDERS = ("first", "second")


def ring_runs(a):
    base = ["--max-bin", 3] if a.ring_paper else ["--preset", "quick"]
    return [("ring", f"hdx{hdx}_c{c}", "rsph-viscous-ring", base + ["--cycle", c, "--h-over-dx", hdx])
            for hdx in (1.4, 1.6) for c in a.cycles.split(",")]


def disk_runs(a):
    return [("disk", r, "rsph-planet-disk", ["--resolution", r, "--snapshot-every", 100])
            for r in a.disk_resolutions.split(",")]


def drift_runs(a):
    return [("drift", r, "rsph-planet-disk", ["--resolution", r, "--q", 0, "--snapshot-every", 100])
            for r in a.disk_resolutions.split(",")]


def neptune_runs(a):
    return [("neptune", r, "rsph-planet-disk", ["--resolution", r, "--q", 1e-4, "--snapshot-every", 100])
            for r in a.disk_resolutions.split(",")]


TESTS = {"ring": ring_runs, "disk": disk_runs, "drift": drift_runs, "neptune": neptune_runs}


def run_all(a):
    todo = []
    for test in a.only.split(","):
        for name, setting, binary, args in TESTS[test](a):
            for lat in a.lattices.split(","):
                for order in ORDERS:
                    out = os.path.join(a.out, name, f"{setting}_{lat}_{order}")
                    todo.append((name, setting, lat, order, out, os.path.join(BIN, binary),
                                 args + ["--lattice", lat, "--remap", order]))
    results = []
    with cf.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        futures = {}
        for name, setting, lat, order, out, binary, args in todo:
            if a.plot_only:
                if os.path.exists(os.path.join(out, "summary.json")):
                    futures[pool.submit(read_summary, out)] = (name, setting, lat, order, out)
                continue
            futures[pool.submit(run_example, binary, out, args, False)] = (name, setting, lat, order, out)
        for f in cf.as_completed(futures):
            name, setting, lat, order, out = futures[f]
            results.append({"test": name, "setting": setting, "lattice": lat, "order": order, "out": out,
                            "s": f.result()})
            print(f"done {out}", flush=True)
    return results


def disk_l1(r):
    prof = read_csv(os.path.join(r["out"], "profile.csv"))
    return fargo3d_l1s(prof["r"], prof["sigma_over_sigma0"])


def drift_error(r):
    """The largest |Sigma/Sigma_0 - 1| of the final azimuthal average over 0.6 < r < 2.3 (away from the zones)."""
    prof = read_csv(os.path.join(r["out"], "profile.csv"))
    return max(abs(v - 1.0) for x, v in zip(prof["r"], prof["sigma_over_sigma0"]) if 0.6 < x < 2.3)


def table(results):
    lines = []
    for test in ("ring", "disk", "drift", "neptune"):
        rows = sorted((r for r in results if r["test"] == test), key=lambda r: (r["setting"], r["lattice"], r["order"]))
        if not rows:
            continue
        if test == "ring":
            lines += ["| setting | lattice | remap | nu_eff/nu_s [min, max] | noise | CPU s |", "|---" * 6 + "|"]
            for r in rows:
                s = r["s"]
                lines.append(f"| {r['setting']} | {r['lattice']} | {r['order']} | {s['nu_eff_over_nu_s']:.3f} "
                             f"[{s['nu_eff_min'] / s['nu_s']:.3f}, {s['nu_eff_max'] / s['nu_s']:.3f}] | "
                             f"{s['noise_error']:.3f} | {s['cpu_seconds']:.0f} |")
        elif test == "disk":
            head = " | ".join(f"L1 {lo}-{hi}" for lo, hi in FARGO3D_REGIONS)
            lines += [f"| resolution | lattice | remap | particles | {head} | gap depth | CPU s |",
                      "|---" * (7 + len(FARGO3D_REGIONS)) + "|"]
            for name, cells, cpu, l1, gap in fargo3d_runs():
                lines.append(f"| FARGO3D {name} | | | {cells} | " + " | ".join(f"{v:.3f}" for v in l1) +
                             f" | {gap:.3f} | {cpu:.0f} |")
            for r in rows:
                s = r["s"]
                lines.append(f"| {r['setting']} | {r['lattice']} | {r['order']} | {s['particles_initial']} | " +
                             " | ".join(f"{v:.3f}" for v in disk_l1(r)) +
                             f" | {s['gap_depth']:.3f} | {s['cpu_seconds']:.0f} |")
        elif test == "neptune":
            lines += ["| resolution | lattice | remap | gap depth | Sigma/Sigma_0 at r = 0.9 / 1.1 | CPU s |",
                      "|---" * 6 + "|"]
            for r in rows:
                prof = read_csv(os.path.join(r["out"], "profile.csv"))
                at = {round(x, 2): v for x, v in zip(prof["r"], prof["sigma_over_sigma0"])}
                lines.append(f"| {r['setting']} | {r['lattice']} | {r['order']} | {r['s']['gap_depth']:.3f} | "
                             f"{at.get(0.91, float('nan')):.3f} / {at.get(1.09, float('nan')):.3f} | "
                             f"{r['s']['cpu_seconds']:.0f} |")
        else:
            lines += ["| resolution | lattice | remap | max abs(Sigma/Sigma_0 - 1), 0.6 < r < 2.3 | CPU s |",
                      "|---" * 5 + "|"]
            for r in rows:
                lines.append(f"| {r['setting']} | {r['lattice']} | {r['order']} | {drift_error(r):.3f} | "
                             f"{r['s']['cpu_seconds']:.0f} |")
        lines.append("")
    return "\n".join(lines)


def draw(results, png):
    tests = [t for t in ("ring", "disk", "drift") if any(r["test"] == t for r in results)]
    if not tests:  # Neptune alone has a table and no error-against-cost chart
        return
    fig, axes = plt.subplots(1, len(tests), figsize=(6 * len(tests), 4.5), squeeze=False)
    for ax, test in zip(axes[0], tests):
        error = {"ring": lambda r: abs(r["s"]["nu_eff_over_nu_s"] - 1.0), "disk": lambda r: disk_l1(r)[0],
                 "drift": drift_error}[test]
        for lat in LATTICES:
            for order in ORDERS:
                rs = sorted((r for r in results if r["test"] == test and r["lattice"] == lat and r["order"] == order
                             and (test != "ring" or r["setting"].startswith("hdx1.4"))),
                            key=lambda r: r["s"]["cpu_seconds"])
                if rs:
                    ax.plot([r["s"]["cpu_seconds"] for r in rs], [max(error(r), 1e-5) for r in rs],
                            "o-" if lat == "rings" else "s--", label=f"{lat}, {order} order")
        if test == "disk":
            fx = [f for f in fargo3d_runs() if f[3][0] > 0.0]
            ax.plot([f[2] for f in fx], [f[3][0] for f in fx], "k^:", label="FARGO3D 192x64, 384x128")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("CPU seconds (one thread)")
        ax.set_ylabel({"ring": "|nu_eff / nu_s - 1|", "disk": "L1 against FARGO3D 768x256, 0.6 < r < 2",
                       "drift": "max |Sigma/Sigma_0 - 1|, q = 0"}[test])
        ax.set_title({"ring": "viscous ring, h/Delta = 1.4, c_r = 1-8", "disk": "planet disk, 100 orbits",
                      "drift": "disk without a planet, 100 orbits"}[test])
        ax.legend(fontsize=7)
    save_figure(fig, png)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--only", default="ring,disk")
    ap.add_argument("--cycles", default="1,2,4,8", help="the ring's c_r row")
    ap.add_argument("--ring-paper", action="store_true", help="the ring at h = 0.02, nu_s = 4.8e-5")
    ap.add_argument("--disk-resolutions", default="low")
    ap.add_argument("--lattices", default="square,rings", help="the lattices to run (all found are drawn)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--plot-only", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    results = run_all(a)
    text = table(results)
    with open(os.path.join(a.out, "lattices.md"), "w") as f:
        f.write(text + "\n")
    print(text)
    draw(results, os.path.join(a.out, "lattices.png"))


if __name__ == "__main__":
    main()

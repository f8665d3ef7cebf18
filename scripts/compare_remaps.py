#!/usr/bin/python3
"""The first- and second-order remaps side by side on the paper's tests: runs each setting with
--remap first and --remap second (one thread per run, --jobs at a time; finished runs are kept), writes
remaps.csv and remaps.md (one line per setting, each remap's error and cost) and draws error against cost,
one point per run and a line per remap, for the ring, Kelvin-Helmholtz and the disk, plus the disk's azimuthal
average over FARGO3D's converged profile (data/reference/fargo3d).

  compare_remaps.py --out out/remaps                       # every test, the settings below
  compare_remaps.py --out out/remaps --only ring,kh        # some of them
  compare_remaps.py --out out/remaps --plot-only

Settings: drifting pulse s = 0.1 and 0.5, 400 regularizations; linear wave lambda = 12, 24, 48 Delta at
r = 0.75, 1.25, 2.25, 4.25 (100 periods); viscous ring --preset quick (nu_s = 4.8e-4, h = 0.04) at
c_r = 1, 2, 4, 8 and h/Delta = 1.4, 1.6 (--ring-paper: h = 0.02, nu_s = 4.8e-5, hours per run); Kelvin-Helmholtz
1/Delta = 128 and 256; the strong shock; the planet disk at --disk-resolutions (default low), 100 orbits.
"""
import argparse
import concurrent.futures as cf
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, NullFormatter  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from rsph_plot import FARGO3D_LABEL, FARGO3D_PROFILE as FARGO, read_csv, read_summary, run_example, save_figure  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))
BIN = os.path.join(HERE, "..", "build", "bin")
ORDERS = ("first", "second")


def pulse_runs(a):
    return [("pulse", {}, "rsph-drifting-pulse", ["--shifts", "0.1,0.5", "--counts", "0,100,200,400"])]


def wave_runs(a):
    return [("wave", {"lambda": lam, "r": r}, "rsph-linear-wave",
             ["--wavelength", lam, "--r", r, "--periods", 100])
            for lam in (12, 24, 48) for r in (0.75, 1.25, 2.25, 4.25)]


def ring_runs(a):
    """The quick preset, or with --ring-paper the paper's h = 0.02 in folders of their own (h0.02_...)."""
    base = ["--max-bin", 3] if a.ring_paper else ["--preset", "quick"]
    h = {"h": 0.02} if a.ring_paper else {}
    return [("ring", {**h, "c_r": c, "h_over_dx": hdx}, "rsph-viscous-ring",
             base + ["--cycle", c, "--h-over-dx", hdx]) for hdx in (1.4, 1.6) for c in (1, 2, 4, 8)]


def kh_runs(a):
    return [("kh", {"cells": n}, "rsph-kelvin-helmholtz", ["--cells", n]) for n in (128, 256)]


def shock_runs(a):
    return [("shock", {}, "rsph-strong-shock", [])]


def disk_runs(a):
    return [("disk", {"resolution": r}, "rsph-planet-disk", ["--resolution", r, "--snapshot-every", 100])
            for r in a.disk_resolutions.split(",") if r]


TESTS = {"pulse": pulse_runs, "wave": wave_runs, "ring": ring_runs, "kh": kh_runs, "shock": shock_runs,
         "disk": disk_runs}


def folder(out, test, setting, order):
    tag = "_".join(f"{k}{v}" for k, v in setting.items())
    return os.path.join(out, test, f"{tag}_{order}" if tag else order)


def measures(test, s):
    """(error name, error, extra) of one run's summary."""
    if test == "pulse":
        c = s["cases"]
        return "width growth after 400 remaps (Delta) s=0.1 / 0.5", [
            c[k]["width_mass"]["400"] - c[k]["width_mass"]["0"] for k in ("0.1", "0.5")]
    if test == "wave":
        return "gamma", [s["gamma"]]
    if test == "ring":
        return "nu_eff/nu_s - 1, noise", [s["nu_eff_over_nu_s"] - 1.0, s["noise_error"]]
    if test == "kh":
        return "amplification by tau_KH", [s["amplification"]]
    if test == "shock":
        return "shock position error, L1(rho)", [s["shock_position"] - s["shock_position_exact"], s["L1_rho"]]
    if test == "disk":
        return "gap depth", [s["gap_depth"]]
    raise ValueError(test)


def run_all(a, jobs):
    todo = []
    for test in a.only.split(","):
        for name, setting, binary, args in TESTS[test](a):
            for order in ORDERS:
                todo.append((name, setting, order, os.path.join(BIN, binary), args + ["--remap", order]))
    results = {}
    with cf.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {}
        for name, setting, order, binary, args in todo:
            out = folder(a.out, name, setting, order)
            if a.plot_only:  # what is there, whatever flags it ran with (a run continued from a checkpoint)
                if os.path.exists(os.path.join(out, "summary.json")):
                    futures[pool.submit(read_summary, out)] = (name, setting, order, out)
                continue
            futures[pool.submit(run_example, binary, out, args, False)] = (name, setting, order, out)
        for f in cf.as_completed(futures):
            name, setting, order, out = futures[f]
            results[(name, tuple(setting.items()), order)] = (f.result(), out)
            print(f"done {out}", flush=True)
    return results


def write_tables(a, results):
    keys = sorted({(n, st) for n, st, _ in results}, key=lambda k: (list(TESTS).index(k[0]), k[1]))
    rows = []
    for name, st in keys:
        row = {"test": name, "setting": " ".join(f"{k}={v}" for k, v in st)}
        for order in ORDERS:
            if (name, st, order) not in results:
                continue
            s, _ = results[(name, st, order)]
            what, values = measures(name, s)
            row["measure"] = what
            row[f"{order}"] = " / ".join(f"{v:.4g}" for v in values)
            row[f"{order}_wall_s"] = f"{s['wall_seconds']:.1f}"
            row[f"{order}_remap_s"] = f"{s.get('regularization_seconds', 0.0):.2f}"
        rows.append(row)
    cols = ["test", "setting", "measure", "first", "second", "first_wall_s", "second_wall_s", "first_remap_s",
            "second_remap_s"]
    with open(os.path.join(a.out, "remaps.csv"), "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=cols)
        w.writeheader()
        w.writerows(rows)
    with open(os.path.join(a.out, "remaps.md"), "w") as f:
        f.write("| test | setting | measure | first | second | wall s (first / second) | remap s (first / second) |\n")
        f.write("|---|---|---|---|---|---|---|\n")
        for r in rows:
            f.write(f"| {r['test']} | {r['setting']} | {r.get('measure', '')} | {r.get('first', '')} | "
                    f"{r.get('second', '')} | {r.get('first_wall_s', '')} / {r.get('second_wall_s', '')} | "
                    f"{r.get('first_remap_s', '')} / {r.get('second_remap_s', '')} |\n")
    print(f"wrote {os.path.join(a.out, 'remaps.md')}")


def error_cost_chart(a, results):
    panels = [("ring", "|nu_eff / nu_s - 1| (labels: c_r, h/Delta)", lambda s: abs(s["nu_eff_over_nu_s"] - 1.0)),
              ("kh", "1 / amplification by tau_KH", lambda s: 1.0 / s["amplification"]),
              ("disk", "gap depth Sigma / Sigma_0 (FARGO3D 768x256: 0.114)", lambda s: s["gap_depth"])]
    panels = [p for p in panels if any(k[0] == p[0] for k in results)]
    if not panels:
        return
    fig, axes = plt.subplots(1, len(panels), figsize=(5.2 * len(panels), 4.2), squeeze=False)
    for ax, (name, ylabel, err) in zip(axes[0], panels):
        for order, style in zip(ORDERS, ("o-", "s-")):
            pts = sorted((s["wall_seconds"], err(s), " ".join(f"{v}" for _, v in st))
                         for (n, st, o), (s, _) in results.items() if n == name and o == order)
            if pts:  # the ring's runs differ in c_r and h/Delta, not in cost alone: points, no line
                ax.plot([p[0] for p in pts], [p[1] for p in pts], style[0] if name == "ring" else style,
                        label=f"{order}-order remap")
                for x, y, tag in pts:
                    ax.annotate(tag, (x, y), textcoords="offset points", xytext=(3, 3), fontsize=7)
        ax.set_xscale("log")
        ax.set_yscale("log")
        xs = [x for line in ax.get_lines() for x in line.get_xdata()]
        ys = [y for line in ax.get_lines() for y in line.get_ydata()]
        if xs:
            ax.set_xlim(min(xs) / 1.5, max(xs) * 1.5)
            ax.set_ylim(min(ys) / 1.5, max(ys) * 1.5)
        for axis in (ax.xaxis, ax.yaxis):
            axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
            axis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("wall seconds (one thread)")
        ax.set_ylabel(ylabel)
        ax.set_title(name)
        ax.legend()
    save_figure(fig, os.path.join(a.out, "error_vs_cost.png"))


def disk_profiles(a, results):
    runs = [(k, v) for k, v in results.items() if k[0] == "disk"]
    if not runs:
        return
    fig, ax = plt.subplots(figsize=(7, 4.2))
    if os.path.exists(FARGO):
        ref = read_csv(FARGO)
        ax.plot(ref["r"], ref["sigma_over_sigma0"], "k-", lw=2, label=FARGO3D_LABEL + ", inviscid")
    for (name, st, order), (s, out) in sorted(runs):
        prof = read_csv(os.path.join(out, "profile.csv"))
        r_key = "r" if "r" in prof else list(prof)[0]
        sig_key = [k for k in prof if k != r_key][0]
        ax.plot(prof[r_key], prof[sig_key], label=f"RSPH {dict(st)['resolution']}, {order} order "
                                                  f"(gap {s['gap_depth']:.2f}, {s['wall_seconds']:.0f} s)")
    ax.set_xlabel("r / a")
    ax.set_ylabel("azimuthal average Sigma / Sigma_0")
    ax.set_xlim(0.4, 2.5)
    ax.legend(fontsize=8)
    save_figure(fig, os.path.join(a.out, "disk_profiles.png"))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", required=True)
    ap.add_argument("--only", default=",".join(TESTS), help="comma-separated: " + ", ".join(TESTS))
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--ring-paper", action="store_true", help="the ring at h = 0.02, nu_s = 4.8e-5 (hours)")
    ap.add_argument("--disk-resolutions", default="low")
    ap.add_argument("--plot-only", action="store_true", help="tables and charts from the runs there; runs nothing")
    a = ap.parse_args()
    for t in a.only.split(","):
        if t not in TESTS:
            ap.error(f"unknown test '{t}' ({', '.join(TESTS)})")
    os.makedirs(a.out, exist_ok=True)
    results = run_all(a, a.jobs)
    write_tables(a, results)
    error_cost_chart(a, results)
    disk_profiles(a, results)


if __name__ == "__main__":
    main()

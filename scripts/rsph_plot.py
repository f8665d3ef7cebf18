"""Helpers shared by the plot scripts (run with Debian's /usr/bin/python3)."""
import argparse
import csv
import json
import os
import subprocess

# The grid code's azimuthally averaged disk after 100 orbits (de Val-Borro's Jupiter, inviscid), kept in the
# repository with its README: the converged 768 x 256 profile is the reference, the coarser ones are points of
# FARGO3D's own error against cost (cost.csv).
FARGO3D_DIR = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "data", "reference", "fargo3d")
FARGO3D_PROFILE = os.path.join(FARGO3D_DIR, "inviscid_768x256_sigma_azavg_orbit100.csv")
FARGO3D_LABEL = "FARGO3D 768x256 (196 608 cells)"
# L1 = mean |Delta Sigma / Sigma_0| over these radii (the first is the headline; 0.6-0.8 differs in set-up: the
# paper's fixed Keplerian zone against FARGO3D's damping zone)
FARGO3D_REGIONS = ((0.6, 2.0), (0.6, 0.8), (0.8, 1.2), (1.2, 1.6), (1.6, 2.0))


def interpolate_linear(xs, ys, x):
    """ys at x, linear between the points xs (ascending), the end values held beyond them."""
    import bisect
    if x <= xs[0]:
        return ys[0]
    if x >= xs[-1]:
        return ys[-1]
    i = bisect.bisect_left(xs, x)
    w = (x - xs[i - 1]) / (xs[i] - xs[i - 1])
    return ys[i - 1] + w * (ys[i] - ys[i - 1])


def profile_l1(r, sigma, ref_r, ref_sigma, lo, hi, n=1400):
    """Mean |sigma - ref| over lo < r < hi on a fine grid, both profiles interpolated linearly."""
    xs = [lo + (k + 0.5) * (hi - lo) / n for k in range(n)]
    return sum(abs(interpolate_linear(r, sigma, x) - interpolate_linear(ref_r, ref_sigma, x)) for x in xs) / n


def fargo3d_l1s(r, sigma):
    """A profile's L1 against FARGO3D's converged one over each of FARGO3D_REGIONS, or None without the data."""
    if not os.path.exists(FARGO3D_PROFILE):
        return None
    ref = read_csv(FARGO3D_PROFILE)
    return [profile_l1(r, sigma, ref["r"], ref["sigma_over_sigma0"], lo, hi) for lo, hi in FARGO3D_REGIONS]


def fargo3d_runs():
    """FARGO3D's own runs: (resolution, cells, user CPU s for 100 orbits, L1 per region, gap depth)."""
    path = os.path.join(FARGO3D_DIR, "cost.csv")
    if not os.path.exists(path):
        return []
    out = []
    with open(path) as f:
        for row in csv.DictReader(f):
            prof = read_csv(os.path.join(FARGO3D_DIR, row["file"]))
            out.append((row["resolution"], int(row["cells"]), float(row["user_cpu_seconds_100_orbits"]),
                        fargo3d_l1s(prof["r"], prof["sigma_over_sigma0"]), float(row["gap_depth_orbit100"])))
    return out


def read_csv(path):
    """Columns of a CSV with a header line, as lists of floats keyed by name."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def load(snapshot):
    """One snap_NNNNN.h5: (fields, attributes), each a dict; fields as numpy arrays (x and v are N x dim)."""
    import h5py  # only the scripts that read snapshots need it

    with h5py.File(snapshot, "r") as f:
        fields = {name: f[name][()] for name in f}
        attributes = {name: f.attrs[name] for name in f.attrs}
    return fields, attributes


def read_summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)


def floats(text):
    """A comma-separated list of numbers."""
    return [float(x) for x in text.split(",") if x]


def kept_summary(out, args):
    """The summary of a finished run in `out` made with these flags (its summary.json records the command),
    or None."""
    if not os.path.exists(os.path.join(out, "summary.json")):
        return None
    summary = read_summary(out)
    return summary if summary.get("command_line", "").endswith(" ".join(str(a) for a in args)) else None


def run_example(binary, out, args, rerun=True):
    """Runs one example on one thread into `out`, without its figure, and returns its summary; with
    rerun=False a run that finished there with the same flags is kept."""
    kept = None if rerun else kept_summary(out, args)
    if kept is not None:
        return kept
    os.makedirs(out, exist_ok=True)
    cmd = [binary, "--out", out, "--overwrite", "--quiet", "--no-plot", "--threads", "1"] + [str(a) for a in args]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    return read_summary(out)


def folders_and_png(description):
    """Command line of the plot scripts: output folders of an example, and the PNG to write."""
    ap = argparse.ArgumentParser(description=description)
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--png", required=True)
    return ap.parse_args()


def save_figure(fig, path, dpi=110):
    """Lays out, writes and announces one figure."""
    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    print(f"wrote {path}")


def method_label(summary):
    """How a run is named in figures and tables: SPH, or RSPH with its remap's order (and its lattice and
    viscosity where they are not the paper's)."""
    if summary.get("method", "rsph") == "sph":
        return "SPH"
    label = f"RSPH {summary.get('remap', 'first')}-order remap"
    if summary.get("lattice") in ("hexagonal", "rings"):
        label += f", {summary['lattice']} lattice"
    if summary.get("rsph_alpha", 0.0) > 0.0:
        label += f", switched viscosity {summary['rsph_alpha']:g}/{summary['rsph_beta']:g}"
    return label

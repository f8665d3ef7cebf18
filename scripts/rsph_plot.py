"""Helpers shared by the plot scripts (run with Debian's /usr/bin/python3)."""
import argparse
import csv
import json
import os
import subprocess

# The grid code's azimuthally averaged disk after 100 orbits (de Val-Borro's Jupiter, inviscid, 49 152 cells).
FARGO3D_PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "shared", "reference",
                               "fargo3d", "inviscid_sigma_azavg_orbit100.csv")


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
    """How a run is named in figures and tables: SPH, or RSPH with its remap's order."""
    if summary.get("method", "rsph") == "sph":
        return "SPH"
    return f"RSPH {summary.get('remap', 'first')}-order remap"

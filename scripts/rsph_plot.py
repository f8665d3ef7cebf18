"""Helpers shared by the plot scripts (run with Debian's /usr/bin/python3)."""
import csv
import json
import os


def read_csv(path):
    """Columns of a CSV with a header line, as lists of floats keyed by name."""
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def read_summary(folder):
    with open(os.path.join(folder, "summary.json")) as f:
        return json.load(f)

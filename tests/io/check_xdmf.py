#!/usr/bin/python3
"""Opens a run's XDMF descriptions with a real reader (meshio, as ParaView and VisIt read them) and checks that
every snapshot's arrays come back equal to the HDF5 datasets, and the series holds every snapshot at its time.

Usage: check_xdmf.py OUT_DIR [OUT_DIR ...]"""
import glob
import os
import sys

import meshio
import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from rsph_plot import load  # noqa: E402


def check(folder):
    snaps = sorted(glob.glob(os.path.join(folder, "snap_*.h5")))
    assert snaps, f"no snapshots in {folder}"
    times = []
    for h5 in snaps:
        fields, attrs = load(h5)
        mesh = meshio.read(h5[:-3] + ".xmf")
        dim = int(attrs["dim"])
        n = len(fields["rho"])
        assert mesh.points.shape[0] == n, f"{h5}: {mesh.points.shape[0]} points for {n} particles"
        assert np.array_equal(mesh.points[:, :dim], fields["x"].reshape(n, dim)), f"{h5}: positions differ"
        for name in ("v", "m", "rho", "h", "P") + (("u",) if "u" in fields else ()):
            got = np.asarray(mesh.point_data[name]).reshape(fields[name].shape)
            assert np.array_equal(got, fields[name]), f"{h5}: {name} differs"
        assert sum(len(c.data) for c in mesh.cells) == n, f"{h5}: not one vertex per particle"
        times.append(float(attrs["time"]))
    with meshio.xdmf.TimeSeriesReader(os.path.join(folder, "snapshots.xmf")) as series:
        series.read_points_cells()
        assert series.num_steps == len(snaps), f"{folder}: {series.num_steps} steps in the series, {len(snaps)} files"
        got = [series.read_data(k)[0] for k in range(series.num_steps)]
        assert np.allclose(got, times, rtol=1e-15, atol=0), f"{folder}: series times {got}, snapshots {times}"
    print(f"check_xdmf: {folder}: {len(snaps)} snapshots read back by meshio, the series at t = {times}")


if __name__ == "__main__":
    for d in sys.argv[1:]:
        check(d)

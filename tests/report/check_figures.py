#!/usr/bin/python3
"""Each program draws its own figure at the end of a run: runs every example at a small size with figures on
(RSPH_NO_PLOT unset) and checks that OUT/<test>.png is a PNG file, then that --no-plot and RSPH_NO_PLOT=1 each
leave it out.

Usage: check_figures.py WORK BIN_DIR
"""
import os
import shutil
import subprocess
import sys

RUNS = [
    ("rsph-sod", "sod", ["--preset", "quick"]),
    ("rsph-drifting-pulse", "drifting_pulse", ["--preset", "quick"]),
    ("rsph-linear-wave", "linear_wave", ["--preset", "quick"]),
    ("rsph-strong-shock", "strong_shock", ["--preset", "quick"]),
    ("rsph-sedov", "sedov", ["--preset", "quick"]),
    ("rsph-kelvin-helmholtz", "kelvin_helmholtz", ["--preset", "quick"]),
    ("rsph-viscous-ring", "viscous_ring", ["--preset", "quick", "--taus", "0.02,0.022"]),
    ("rsph-planet-disk", "planet_disk", ["--preset", "quick", "--orbits", 1, "--snapshot-every", 1]),
]


def run(binary, out, args, env):
    cmd = [binary, "--out", out, "--overwrite", "--threads", "1"] + [str(a) for a in args]
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if proc.returncode != 0:
        sys.exit(f"check_figures: {' '.join(cmd)} failed ({proc.returncode}):\n{proc.stderr}")
    return proc


def is_png(path):
    if not os.path.isfile(path):
        return False
    with open(path, "rb") as f:
        return f.read(8) == b"\x89PNG\r\n\x1a\n"


def main():
    work, bin_dir = sys.argv[1], sys.argv[2]
    shutil.rmtree(work, ignore_errors=True)
    env = {k: v for k, v in os.environ.items() if k != "RSPH_NO_PLOT"}
    for program, test, args in RUNS:
        out = os.path.join(work, test)
        proc = run(os.path.join(bin_dir, program), out, args, env)
        png = os.path.join(out, f"{test}.png")
        if not is_png(png):
            sys.exit(f"check_figures: {program} drew no {png}:\n{proc.stdout}\n{proc.stderr}")
        if f"figure: {png}" not in proc.stdout:
            sys.exit(f"check_figures: {program} did not say where its figure is:\n{proc.stdout}")
    sod = os.path.join(bin_dir, "rsph-sod")
    for name, extra, environment in (("no-plot", ["--no-plot"], env), ("env", [], dict(env, RSPH_NO_PLOT="1"))):
        out = os.path.join(work, f"sod-{name}")
        run(sod, out, ["--preset", "quick"] + extra, environment)
        if os.path.exists(os.path.join(out, "sod.png")):
            sys.exit(f"check_figures: a figure was drawn with {name}")
    print(f"check_figures: {len(RUNS)} programs drew their figures; --no-plot and RSPH_NO_PLOT=1 drew none")


if __name__ == "__main__":
    main()

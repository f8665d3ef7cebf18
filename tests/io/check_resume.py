#!/usr/bin/python3
"""A run stopped and resumed equals the run left alone, to the bit.

    check_resume.py OUT PROGRAM [FLAGS...] --every X [--wall MINUTES] [--ways wall,signal,killed]

Runs PROGRAM FLAGS four ways into OUT/whole, OUT/wall, OUT/signal and OUT/killed: left alone (with
checkpoints every X); stopped by --max-wall MINUTES (0.005 unless given) again and again and resumed each time,
up to 12 times, then let finish; stopped by SIGINT once its first checkpoint is written, then resumed; and killed by SIGKILL
then, which runs no handler and may leave a half-written file, then resumed (--ways names which of the last three to run; all unless given: the signal handlers and the
checkpoint files are the same code in every program, so a long run may check them through its cheaper
siblings). Each stop must exit 5 naming its checkpoint and leave
no .partial file; each finished run must have every snapshot dataset and attribute, every CSV column but
wall times and every summary.json figure but wall times equal to the run left alone."""
import glob
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "scripts"))
from rsph_plot import load  # noqa: E402

STOPS = 12  # stops by --max-wall before the run is let finish
WALL = ("seconds", "per_second", "command_line", "checkpoint-every", "max-wall", "stop-at")


def fail(message):
    sys.exit("check_resume: " + message)


def run(cmd, expect):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in expect:
        fail(f"{' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()}")
    return p


def no_partial(folder):
    left = glob.glob(os.path.join(folder, ".*.partial"))
    if left:
        fail(f"partial files left in {folder}: {left}")


def stopped_message(p, folder):
    if p.returncode == 5 and f"--resume {folder}" not in p.stderr:
        fail(f"a stop did not say how to resume: {p.stderr.strip()}")


def figures(value, path=""):
    """summary.json flattened, wall-clock figures left out."""
    if isinstance(value, dict):
        out = {}
        for k, v in value.items():
            if not any(w in k for w in WALL):
                out.update(figures(v, f"{path}/{k}"))
        return out
    if isinstance(value, list):
        out = {}
        for i, v in enumerate(value):
            out.update(figures(v, f"{path}/{i}"))
        return out
    return {path: value}


def csv_columns(path):
    with open(path) as f:
        header = f.readline().strip().split(",")
        rows = [line.strip().split(",") for line in f]
    return {h: [r[i] for r in rows] for i, h in enumerate(header) if not any(w in h for w in WALL)}


def compare(a, b):
    names = lambda d, pattern: sorted(os.path.relpath(p, d) for p in glob.glob(os.path.join(d, "**", pattern), recursive=True))
    for pattern in ("snap_*.h5", "*.csv", "summary.json"):
        if names(a, pattern) != names(b, pattern):
            fail(f"{b} holds other {pattern} files than {a}: {names(b, pattern)} against {names(a, pattern)}")
    for rel in names(a, "snap_*.h5"):
        fa, aa = load(os.path.join(a, rel))
        fb, ab = load(os.path.join(b, rel))
        for k in set(fa) | set(fb):
            if k not in fa or k not in fb or not np.array_equal(fa[k], fb[k]):
                fail(f"{rel}: dataset {k} differs between {a} and {b}")
        for k in set(aa) | set(ab):
            if not np.array_equal(np.asarray(aa.get(k)), np.asarray(ab.get(k))):
                fail(f"{rel}: attribute {k} differs between {a} and {b}")
    for rel in names(a, "*.csv"):
        if csv_columns(os.path.join(a, rel)) != csv_columns(os.path.join(b, rel)):
            fail(f"{rel} differs between {a} and {b}")
    for rel in names(a, "summary.json"):
        with open(os.path.join(a, rel)) as f:
            sa = figures(json.load(f))
        with open(os.path.join(b, rel)) as f:
            sb = figures(json.load(f))
        if sa != sb:
            diff = [k for k in set(sa) | set(sb) if sa.get(k) != sb.get(k)]
            fail(f"{rel}: figures differ between {a} and {b}: {sorted(diff)[:8]}")


def main():
    out, program, *flags = sys.argv[1:]
    def take(name, default):
        if name not in flags:
            return default
        i = flags.index(name)
        value = flags[i + 1]
        del flags[i : i + 2]
        return value

    every = take("--every", None)
    wall_limit = take("--wall", "0.005")
    ways = take("--ways", "wall,signal,killed").split(",")
    unknown = set(ways) - {"wall", "signal", "killed"}
    if unknown:
        fail(f"unknown ways {sorted(unknown)}")
    base = [program, *flags, "--quiet", "--checkpoint-every", every]
    whole, wall, sig = (os.path.join(out, d) for d in ("whole", "wall", "signal"))
    shutil.rmtree(out, ignore_errors=True)  # an earlier checkpoint would be taken for this run's
    run([*base, "--overwrite", "--out", whole], [0])

    stops = resume_after_wall(base, program, whole, wall, wall_limit) if "wall" in ways else 0
    if "signal" in ways:
        resume_after_signal(base, program, whole, sig)
    if "killed" in ways:
        resume_after_kill(base, program, whole, os.path.join(out, "killed"))
    done = " and ".join(name for way, name in (("signal", "SIGINT"), ("killed", "SIGKILL")) if way in ways)
    print(f"check_resume: {os.path.basename(program)} resumed {stops} time{'' if stops == 1 else 's'} after --max-wall"
          f"{' and once after ' + done if done else ''}; every snapshot, curve and figure equals the run left alone")


def resume_after_wall(base, program, whole, wall, wall_limit):
    """Stopped by --max-wall again and again, resumed each time; returns how many times it stopped."""
    # A faster machine may finish before the limit: take a tenth of it, and so on, until the run is stopped.
    for limit in (float(wall_limit) / 10**k for k in range(4)):
        p = run([*base, "--overwrite", "--out", wall, "--max-wall", f"{limit:g}"], [0, 5])
        if p.returncode == 5:
            break
    stops = 0
    while p.returncode == 5:
        stopped_message(p, wall)
        no_partial(wall)
        stops += 1
        # after STOPS stops the last resume lifts the limit: more stops would cost process starts, not checks
        p = run([program, "--resume", wall, "--quiet", *(["--max-wall", "0"] if stops == STOPS else [])], [0, 5])
        if stops > STOPS:
            fail(f"the run stopped again after its limit was lifted at the {STOPS}th resume")
    if stops == 0:
        fail(f"--max-wall down to {limit:g} never stopped the run: nothing was resumed")
    compare(whole, wall)
    return stops


def resume_after_signal(base, program, whole, sig):
    """Stopped by SIGINT once its first checkpoint is written, then resumed."""
    proc = subprocess.Popen([*base, "--overwrite", "--out", sig], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)
    while proc.poll() is None and not os.path.exists(os.path.join(sig, "checkpoint.h5")):
        time.sleep(0.01)
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    _, err = proc.communicate()
    if proc.returncode == 5:
        stopped_message(subprocess.CompletedProcess([], 5, "", err), sig)
        no_partial(sig)
        run([program, "--resume", sig, "--quiet", "--max-wall", "0"], [0])
    elif proc.returncode != 0:
        fail(f"the run sent SIGINT exited {proc.returncode}: {err.strip()}")
    compare(whole, sig)


def resume_after_kill(base, program, whole, killed):
    """SIGKILL: no handler runs; the last whole checkpoint resumes."""
    proc = subprocess.Popen([*base, "--overwrite", "--out", killed], stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)
    while proc.poll() is None and not os.path.exists(os.path.join(killed, "checkpoint.h5")):
        time.sleep(0.01)
    proc.kill()
    proc.wait()
    if os.path.exists(os.path.join(killed, "checkpoint.h5")) and not os.path.exists(os.path.join(killed, "summary.json")):
        run([program, "--resume", killed, "--quiet", "--max-wall", "0"], [0])
        no_partial(killed)
        compare(whole, killed)


if __name__ == "__main__":
    main()

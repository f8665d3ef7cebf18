#!/usr/bin/python3
"""The paper in one report: runs every test of Børve, Speith & Trulsen (2009) with RSPH (first- and
second-order remap) and plain SPH where the paper compares them, and writes OUT/index.html: a summary table
(each test's headline error and cost per method, and whether the paper's claim holds), and per test its
figure over the exact or reference solution, the figures measured, and error against cost.

  report.py                       # the reduced suite, about 20 minutes on 2 cores
  report.py --quick               # every test at a size that takes about three minutes in all
  report.py --full                # the paper's resolutions (hours)
  report.py --only kelvin_helmholtz,sod

Runs already in OUT/runs with the same flags are reused. Each run is one thread; --jobs run at a time.
"""
import argparse
import concurrent.futures as cf
import html
import os
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter  # noqa: E402

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from report_tests import TESTS, finite  # noqa: E402
from rsph_plot import kept_summary, run_example, save_figure  # noqa: E402

HERE = os.path.dirname(os.path.abspath(__file__))


class Progress:
    """A line with runs done, elapsed time and an ETA (on a terminal; one line per run otherwise). The ETA
    scales the time taken so far by the guessed cost (core-seconds) still to come over that done."""

    def __init__(self, total_guess, count):
        self.total, self.done_guess, self.count, self.done = total_guess, 0.0, count, 0
        self.t0 = time.monotonic()
        self.tty = sys.stderr.isatty()

    def finished(self, label, guess, reused):
        self.done += 1
        self.done_guess += guess
        elapsed = time.monotonic() - self.t0
        left = elapsed / self.done_guess * (self.total - self.done_guess) if self.done_guess > 0 and elapsed > 1 else 0
        eta = f"ETA {fmt_time(left)}" if self.done < self.count else "done"
        kept = " (kept)" if reused else ""
        line = f"report: {self.done}/{self.count} runs, {fmt_time(elapsed)}, {eta}: {label}{kept}"
        if self.tty:
            sys.stderr.write("\r\033[K" + line[:150] + ("\n" if self.done == self.count else ""))
        else:
            sys.stderr.write(line + "\n")
        sys.stderr.flush()


def fmt_time(s):
    return f"{int(s // 60)} min {int(s % 60):02d} s" if s >= 60 else f"{s:.0f} s"


def run_suite(a, tests):
    """Runs (or reuses) every run of `tests`; returns {test key: [(Run, summary, measures, folder)]}."""
    todo = [(t, r) for t in tests for r in t.runs(a.suite)]
    progress = Progress(sum(r.guess for _, r in todo), len(todo))
    done = {}

    def one(t, r):
        folder = os.path.join(a.out, "runs", r.folder(t.key))
        kept = kept_summary(folder, r.args)
        if kept is not None:
            return folder, kept, True
        return folder, run_example(os.path.join(a.bin, r.program), folder, r.args), False

    with cf.ThreadPoolExecutor(max_workers=a.jobs) as pool:
        # the longest first, so that the short runs fill in beside them at the end
        futures = {pool.submit(one, t, r): (t, r) for t, r in sorted(todo, key=lambda tr: -tr[1].guess)}
        failed = []
        for f in cf.as_completed(futures):
            t, r = futures[f]
            try:
                folder, s, reused = f.result()
                done[id(r)] = (r, s, t.measures(s, folder), folder)
            except RuntimeError as e:
                failed.append(str(e))
                reused = False
            progress.finished(f"{t.key}, {r.method}, {r.size}", r.guess, reused)
    if failed:
        sys.exit("report: runs failed, no report written:\n" + "\n".join(failed))
    results = {}
    for t, r in todo:
        results.setdefault(t.key, []).append(done[id(r)])
    return results


def figure(t, rows, png):
    """The test's own figure (its plot script) over the largest run of each method."""
    largest = {}
    for r, s, m, folder in rows:
        largest[r.method] = folder
    script = os.path.join(HERE, f"plot_{t.figure}.py")
    folders = list(dict.fromkeys(largest.values()))
    proc = subprocess.run([sys.executable, script] + folders + ["--png", png], capture_output=True, text=True)
    if proc.returncode != 0:
        raise RuntimeError(f"{script} failed:\n{proc.stderr.strip()}")


def error_cost_chart(t, rows, png):
    """Headline error against wall seconds: one point per run, a line per method."""
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    methods = list(dict.fromkeys(r.method for r, _, _, _ in rows))
    for method, marker in zip(methods, "os^vDx<>"):
        pts = [(s["wall_seconds"], abs(m[t.headline])) for r, s, m, _ in rows if r.method == method]
        pts = [p for p in pts if p[1] > 0]
        if pts:
            ax.plot([p[0] for p in pts], [p[1] for p in pts], marker + "-", label=method)
    ax.set_xscale("log")
    ax.set_yscale("log")
    for axis in (ax.xaxis, ax.yaxis):  # ticks at 1, 2 and 5 of each decade: narrow ranges keep their labels
        axis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        axis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("wall seconds (one thread)")
    ax.set_ylabel(f"|{t.headline}|")
    ax.set_title(f"{t.title}: error against cost", fontsize=9)
    ax.legend(fontsize=7)
    save_figure(fig, png, dpi=90)


def number(v):
    if isinstance(v, bool) or not finite(v):
        raise ValueError(f"not a finite number: {v!r}")
    if v == 0:
        return "0"
    return f"{v:.3g}" if 1e-3 <= abs(v) < 1e5 else f"{v:.2e}"


def cell(v):
    return f"<td>{number(v)}</td>"


def claims_of(t, rows):
    c = t.claim([(r, s, m) for r, s, m, _ in rows])
    return [] if c is None else (c if isinstance(c, list) else [c])


def test_section(t, rows, out):
    key = t.key
    figure(t, rows, os.path.join(out, f"{key}.png"))
    error_cost_chart(t, rows, os.path.join(out, f"{key}_cost.png"))
    names = list(dict.fromkeys(n for _, _, m, _ in rows for n in m))
    h = [f'<section id="{key}"><h2>{html.escape(t.title)}</h2>',
         f"<p>Reference: {html.escape(t.reference)}. Program: <code>{t.program}</code>; each run's command is in "
         f"its <code>summary.json</code> under <code>runs/{key}/</code>.</p>",
         f'<p><a href="{key}.png"><img src="{key}.png" alt="{html.escape(t.title)}: figure"></a> '
         f'<a href="{key}_cost.png"><img src="{key}_cost.png" alt="{html.escape(t.title)}: error against cost">'
         "</a> (click an image for its full size)</p>",
         "<table><tr><th>method</th><th>size</th>" + "".join(f"<th>{html.escape(n)}</th>" for n in names) +
         "<th>particles</th><th>wall s</th><th>particle updates / s</th></tr>"]
    for r, s, m, _ in rows:
        particles = s.get("mean_particles", s.get("particles", s.get("cells", 0)))
        h.append(f"<tr><th>{html.escape(r.method)}</th><th>{html.escape(r.size)}</th>" +
                 "".join(cell(m[n]) for n in names) + cell(particles) +
                 cell(s["wall_seconds"]) + cell(s["particle_updates_per_second"]) + "</tr>")
    h.append("</table>")
    claims = claims_of(t, rows)
    if claims:
        h.append("<table><tr><th>the paper's claim</th><th>measured</th><th>verdict</th></tr>")
        for text, value, holds in claims:
            h.append(f"<tr><th>{html.escape(text)}</th>{cell(value)}{verdict(holds)}</tr>")
        h.append("</table>")
    h.append("</section>")
    return "\n".join(h)


def verdict(holds, rows=1):
    word = "holds" if holds else "fails"
    return f'<td class="verdict {word}" rowspan="{rows}">{word}</td>'


def summary_table(tests, results):
    h = ["<table><tr><th>test</th><th>method</th><th>headline error</th><th>error, largest size</th>"
         "<th>wall s, largest size</th><th>wall s, all sizes</th><th>claims holding</th><th>claims checked</th>"
         "<th>verdict</th></tr>"]
    for t in tests:
        rows = results[t.key]
        claims = claims_of(t, rows)
        held = sum(1 for c in claims if c[2])
        methods = list(dict.fromkeys(r.method for r, _, _, _ in rows))
        for i, method in enumerate(methods):
            mine = [(r, s, m) for r, s, m, _ in rows if r.method == method]
            r, s, m = mine[-1]
            lead = (f'<th rowspan="{len(methods)}"><a href="#{t.key}">{html.escape(t.title)}</a></th>' if i == 0
                    else "")
            n = len(methods)
            tail = (f'<td rowspan="{n}">{held}</td><td rowspan="{n}">{len(claims)}</td>'
                    f"{verdict(held == len(claims), n)}" if i == 0 else "")
            h.append(f"<tr>{lead}<th>{html.escape(method)}</th><th>{html.escape(t.headline)}</th>"
                     f"{cell(m[t.headline])}{cell(s['wall_seconds'])}{cell(sum(x[1]['wall_seconds'] for x in mine))}"
                     f"{tail}</tr>")
    h.append("</table>")
    return "\n".join(h)


STYLE = """body{font-family:sans-serif;max-width:1400px;margin:1em auto;padding:0 1em;color:#222}
table{border-collapse:collapse;margin:0.8em 0;font-size:13px}th,td{border:1px solid #bbb;padding:3px 7px}
td{text-align:right;font-variant-numeric:tabular-nums}th{background:#f2f2f2;text-align:left;font-weight:normal}
tr:first-child th{font-weight:bold}td.holds{color:#060;text-align:center}td.fails{color:#a00;text-align:center}
img{max-width:49%;vertical-align:top}section{border-top:2px solid #ddd;margin-top:1.5em}"""


def write_page(a, tests, results):
    sections = [test_section(t, results[t.key], a.out) for t in tests]
    page = ["<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
            "<title>rsph: the paper's tests, accuracy against cost</title>", f"<style>{STYLE}</style></head><body>",
            "<h1>rsph: the paper's tests, accuracy against cost</h1>",
            f"<p>Suite <b>{a.suite}</b> ({html.escape(' '.join(sys.argv[1:]) or 'defaults')}); every run on one "
            f"thread, {a.jobs} at a time, on {html.escape(os.uname().nodename)} ({os.cpu_count()} cores), "
            f"{time.strftime('%Y-%m-%d %H:%M')}. Headline errors: lower is better; the claims are the paper's "
            "(and, for the second-order remap, this project's targets).</p>",
            summary_table(tests, results)] + sections + ["</body></html>"]
    path = os.path.join(a.out, "index.html")
    with open(path + ".partial", "w") as f:
        f.write("\n".join(page) + "\n")
    os.replace(path + ".partial", path)
    return path


def summary_markdown(a, tests, results):
    """The summary as a Markdown table (for the README and docs), and each claim with its verdict."""
    lines = ["| test | method | headline error | error | wall s |", "|---|---|---|---|---|"]
    claims = []
    for t in tests:
        rows = results[t.key]
        for method in dict.fromkeys(r.method for r, _, _, _ in rows):
            r, s, m, _ = [x for x in rows if x[0].method == method][-1]
            lines.append(f"| {t.title} | {method} ({r.size}) | {t.headline} | {number(m[t.headline])} | "
                         f"{number(s['wall_seconds'])} |")
        claims += [f"- {t.title}: {text}: {number(value)}, **{'holds' if holds else 'fails'}**"
                   for text, value, holds in claims_of(t, rows)]
    path = os.path.join(a.out, "summary.md")
    with open(path, "w") as f:
        f.write("\n".join(lines + [""] + claims) + "\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    size = ap.add_mutually_exclusive_group()
    size.add_argument("--quick", dest="suite", action="store_const", const="quick", help="about three minutes")
    size.add_argument("--full", dest="suite", action="store_const", const="full", help="the paper's sizes (hours)")
    ap.set_defaults(suite="reduced")
    ap.add_argument("--only", default="", help="comma-separated tests: " + ", ".join(t.key for t in TESTS))
    ap.add_argument("--out", default=os.path.join(HERE, "..", "out", "report"))
    ap.add_argument("--bin", default=os.path.join(HERE, "..", "build", "bin"), help="folder of the programs")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 2, help="runs at a time")
    a = ap.parse_args()
    known = {t.key: t for t in TESTS}
    wanted = [w for w in a.only.split(",") if w]
    for w in wanted:
        if w not in known:
            ap.error(f"unknown test '{w}' (known: {', '.join(known)})")
    if a.jobs < 1:
        ap.error("--jobs must be at least 1")
    tests = [t for t in TESTS if not wanted or t.key in wanted]
    missing = [t.program for t in tests if not os.path.exists(os.path.join(a.bin, t.program))]
    if missing:
        sys.exit(f"report: {', '.join(missing)} not in {a.bin}; build first (scripts/build.sh)")
    os.makedirs(a.out, exist_ok=True)
    results = run_suite(a, tests)
    summary_markdown(a, tests, results)
    print(f"wrote {write_page(a, tests, results)}")


if __name__ == "__main__":
    main()

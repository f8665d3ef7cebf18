#!/usr/bin/python3
"""The report's page holds what it promises: runs scripts/report.py (the quick suite, or the tests named)
into WORK and checks that index.html names only images that exist and are PNG files, that every data cell of
every table is a finite number (a verdict cell says holds or fails), that the summary has a line for every
test, and that each test's section has its figure and its error-cost chart. Then it runs the report again and
checks that every run was kept, not recomputed.

Usage: check_report.py WORK BIN_DIR [report.py flags]
"""
import html.parser
import math
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPORT = os.path.join(HERE, "..", "..", "scripts", "report.py")


class Page(html.parser.HTMLParser):
    """The images, the tables (rows of (tag, class, text) cells) and the section ids of a page."""

    def __init__(self):
        super().__init__()
        self.images, self.tables, self.sections, self.links = [], [], [], []
        self.cell = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "img":
            self.images.append(a.get("src", ""))
        elif tag == "a":
            self.links.append(a.get("href", ""))
        elif tag == "section":
            self.sections.append(a.get("id", ""))
        elif tag == "table":
            self.tables.append([])
        elif tag == "tr":
            self.tables[-1].append([])
        elif tag in ("td", "th"):
            self.cell = [tag, a.get("class", ""), ""]

    def handle_data(self, data):
        if self.cell is not None:
            self.cell[2] += data

    def handle_endtag(self, tag):
        if tag in ("td", "th") and self.cell is not None:
            self.tables[-1][-1].append(tuple(self.cell))
            self.cell = None


def fail(message):
    sys.exit(f"check_report: {message}")


def check_page(out):
    page = Page()
    with open(os.path.join(out, "index.html")) as f:
        page.feed(f.read())
    if not page.images or not page.tables:
        fail("the page has no images or no tables")
    for src in page.images:
        path = os.path.join(out, src)
        if not os.path.isfile(path):
            fail(f"the page names {src}, which does not exist")
        with open(path, "rb") as f:
            if f.read(8) != b"\x89PNG\r\n\x1a\n":
                fail(f"{src} is not a PNG file")
    cells = 0
    for table in page.tables:
        for row in table:
            for tag, cls, text in row:
                if tag != "td":
                    continue
                cells += 1
                if "verdict" in cls:
                    if text not in ("holds", "fails"):
                        fail(f"a verdict cell says '{text}'")
                    continue
                try:
                    value = float(text)
                except ValueError:
                    fail(f"a table cell holds '{text}', not a number")
                if not math.isfinite(value):
                    fail(f"a table cell holds '{text}'")
    for key in page.sections:
        for name in (f"{key}.png", f"{key}_cost.png"):
            if name not in page.images:
                fail(f"the section {key} lacks {name}")
        if f"#{key}" not in page.links:
            fail(f"the summary has no line for {key}")
    return page, cells


def main():
    if len(sys.argv) < 3:
        fail(__doc__)
    work, bin_dir, flags = sys.argv[1], sys.argv[2], sys.argv[3:]
    shutil.rmtree(work, ignore_errors=True)
    cmd = [sys.executable, REPORT, "--out", work, "--bin", bin_dir] + flags
    first = subprocess.run(cmd, capture_output=True, text=True)
    if first.returncode != 0:
        fail(f"{' '.join(cmd)} failed:\n{first.stderr}")
    page, cells = check_page(work)
    if len(page.sections) < 1 or cells < 10:
        fail(f"{len(page.sections)} sections and {cells} cells: too few")
    again = subprocess.run(cmd, capture_output=True, text=True)
    if again.returncode != 0:
        fail(f"the second report failed:\n{again.stderr}")
    runs = [line for line in again.stderr.splitlines() if line.startswith("report: ")]
    if not runs or not all(line.endswith("(kept)") for line in runs):
        fail("the second report recomputed runs it had:\n" + "\n".join(runs))
    print(f"check_report: {len(page.sections)} tests, {len(page.images)} images, {cells} cells; every run kept")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Sums the output of `cg_annotate --show=Ir,Bcm` (a difference of two remaps) by function, the code inlined
into a function counted with it, and prints the eight heaviest per old particle. Argument: the particle count.
Used by scripts/remap-cost.sh."""
import re
import signal
import sys

ROW = re.compile(r"^\s*([\d,]+) \([ \d.]+%\)\s+(?:([\d,]+) \([ \d.]+%\)|\.)\s+(\S.*)$")


def short(name):
    """The last three parts of a function's name, without its file, return type, template arguments and
    parameters: 'for_each_old_cell::Visitor::add_cell'."""
    if ":" in name and not name.startswith("rsph::"):
        head, rest = name.split(":", 1)
        if "/" in head or "." in head or head == "???":
            name = rest
    for pattern in (r"<[^<>]*>", r"\([^()]*\)"):  # innermost first, until none is left
        while True:
            stripped = re.sub(pattern, "", name)
            if stripped == name:
                break
            name = stripped
    name = re.sub(r" \[clone [^\]]*\]$| const$", "", name)  # OpenMP outlined bodies, const members
    name = name.split(" ")[-1]  # a return type
    name = name.replace("::operator", "").replace("{lambda#", "{lambda ")
    return "::".join(name.split("::")[-3:])


def main():
    signal.signal(signal.SIGPIPE, signal.SIG_DFL)  # quiet when piped into head
    particles = float(sys.argv[1])
    totals = {}
    for line in sys.stdin:
        m = ROW.match(line)
        if not m or "PROGRAM TOTALS" in line:
            continue
        cost = totals.setdefault(short(m.group(3)), [0, 0])
        cost[0] += int(m.group(1).replace(",", ""))
        cost[1] += int((m.group(2) or "0").replace(",", ""))
    print("where it goes, per old particle (instructions, mispredicted):")
    for name, (ir, bcm) in sorted(totals.items(), key=lambda kv: -kv[1][0])[:8]:
        print(f"  {ir / particles / 2:7.0f} {bcm / particles / 2:6.1f}  {name}")


if __name__ == "__main__":
    main()

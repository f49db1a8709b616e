#!/usr/bin/env python3
"""Generated tables for docs/*.md, made from the benchmark results in bench/results.

A page asks for a table with two marker lines:

    <!-- table: NAME -->
    <!-- end table -->

and this script writes, between them, the markdown table that the function registered under NAME makes from
bench/results/*.csv and *.json. Figures on a page then come from the same files as the plots.

    python3 docs/tables.py            # rewrite every block in place
    python3 docs/tables.py --check    # exit 1 and name each block that is out of date (for a test)
    python3 docs/tables.py --list     # the table names and the files each one reads

Standard library only (csv, json, argparse, pathlib, math, statistics, re, sys). The tables themselves are in
docs/tablegen/, one module per area of benchmarks.
"""
import argparse
import re
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from tablegen import DOCS, ROOT, TABLES  # noqa: E402  (the tables, one module per area of benchmarks)

BEGIN = re.compile(r"^<!-- table: ([A-Za-z0-9_.-]+) -->\s*$")
END = "<!-- end table -->"


def render(name):
    """The block's lines: the table with a blank line before and after, so that markdown sees it as a block."""
    function, _ = TABLES[name]
    return "\n" + function().strip("\n") + "\n"


def rewrite(text, path):
    """The page with every block regenerated, and the names of the blocks that changed. Raises on a bad block."""
    lines = text.split("\n")
    out, changed, i = [], [], 0
    while i < len(lines):
        match = BEGIN.match(lines[i])
        out.append(lines[i])
        i += 1
        if not match:
            continue
        name = match.group(1)
        start = i
        while i < len(lines) and lines[i].strip() != END:
            if BEGIN.match(lines[i]):
                raise SystemExit(f"{path}:{i + 1}: table '{name}' has no '{END}' before the next table")
            i += 1
        if i == len(lines):
            raise SystemExit(f"{path}:{start}: table '{name}' has no '{END}'")
        if name not in TABLES:
            raise SystemExit(f"{path}:{start}: no table named '{name}' (python3 docs/tables.py --list)")
        new = render(name).split("\n")
        if lines[start:i] != new:
            changed.append((name, start))
        out.extend(new)
        out.append(lines[i])
        i += 1
    return "\n".join(out), changed


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if a block is out of date")
    parser.add_argument("--list", action="store_true", help="print each table name and the files it reads")
    parser.add_argument("pages", nargs="*", type=Path, help="pages to process (default: docs/*.md)")
    args = parser.parse_args()
    if args.list:
        for name, (_, sources) in TABLES.items():
            print(f"{name:28s} " + ", ".join(f"bench/results/{s}" for s in sources))
        return 0
    stale = []
    for path in args.pages or sorted(DOCS.glob("*.md")):
        text = path.read_text()
        new, changed = rewrite(text, path)
        shown = path.resolve().relative_to(ROOT) if path.resolve().is_relative_to(ROOT) else path
        for name, line in changed:
            stale.append(f"{shown}:{line}: table '{name}' is out of date")
        if changed and not args.check:
            path.write_text(new)
            print(f"{shown}: rewrote " + ", ".join(name for name, _ in changed))
    if args.check:
        for line in stale:
            print(line, file=sys.stderr)
        if stale:
            print("run python3 docs/tables.py to regenerate them", file=sys.stderr)
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())

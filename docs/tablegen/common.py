"""What every table module shares: where the results are, the registry of tables, reading and number formatting
(docs/tables.py's library)."""
import csv
import json
import math
import statistics
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
RESULTS = ROOT / "bench" / "results"
DOCS = ROOT / "docs"

TABLES = {}  # name -> (function, [files it reads, relative to bench/results])


def table(name, *sources):
    """Registers the decorated function as the table NAME, made from `sources` (bench/results/...)."""
    def register(function):
        TABLES[name] = (function, list(sources))
        return function
    return register


# --- reading -------------------------------------------------------------------------------------------------------

def rows_of(name):
    with open(RESULTS / name, newline="") as f:
        return list(csv.DictReader(f))


def json_of(name):
    with open(RESULTS / name) as f:
        return json.load(f)


def num(text):
    """A CSV cell as a float; None when empty, 'nan' or not a number (skipped, timeout, ...)."""
    if text is None:
        return None
    try:
        x = float(text)
    except (TypeError, ValueError):
        return None
    return None if math.isnan(x) else x


# --- formatting ----------------------------------------------------------------------------------------------------

def sig(x, digits=3):
    """x to `digits` significant figures: plain with thousands separators from 1e-3 to 1e6, else 1.23e-8."""
    if x is None:
        return "-"
    if x == 0:
        return "0"
    magnitude = math.floor(math.log10(abs(x)))
    if -3 <= magnitude < 6:
        decimals = max(0, digits - 1 - magnitude)
        return f"{round(x, decimals):,.{decimals}f}"
    return sci(x, digits)


def sci(x, digits=3):
    if x is None:
        return "-"
    mantissa, exponent = f"{x:.{digits - 1}e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def pct(x, digits=None, sign=True):
    """A ratio as a percentage: 0.0123 -> +1.2 %, 0.125 -> +12.5 % (default: two significant figures below 10 %,
    three above)."""
    if x is None:
        return "-"
    value = 100 * x
    if value == 0:
        return "0 %"
    text = sig(abs(value), digits or (2 if abs(value) < 10 else 3))
    return ("+" if value > 0 and sign else "-" if value < 0 else "") + text + " %"


def integer(x):
    return "-" if x is None else f"{int(round(x)):,}"


def fixed(x, decimals):
    return "-" if x is None else f"{x:,.{decimals}f}"


def gib(mib):
    """MiB as GiB, three significant figures."""
    return "-" if mib is None else sig(mib / 1024)


def plain(text):
    """A number as typed in the results (3.5, 0.86, 0.0125), without trailing zeros."""
    return f"{float(text):g}"


def markdown(header, rows, align=None):
    """A markdown table. align: a string of 'l' and 'r', one per column (default: first left, the rest right)."""
    align = align or "l" + "r" * (len(header) - 1)
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---" if a == "l" else "---:" for a in align) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(lines)


def slope(points):
    """Least-squares slope of log y against log x."""
    xs = [math.log(x) for x, _ in points]
    ys = [math.log(y) for _, y in points]
    mx, my = statistics.fmean(xs), statistics.fmean(ys)
    return sum((x - mx) * (y - my) for x, y in zip(xs, ys)) / sum((x - mx) ** 2 for x in xs)

#!/usr/bin/python3
"""Plots bench/results/sparse_solver_bench.csv (sparse_solver_bench): the factorization that a Newton matrix rebuild
costs (KLU's refactorization; SparseLU and the quasi-definite LDLT have none, so their full factorization) and a
solve, in µs against the reduced matrix's rows, log-log, rigid and GCMS chains side by side.

    /usr/bin/python3 bench/sparse_solver_plot.py [bench/results/sparse_solver_bench.csv]
writes the PNG beside the CSV.
"""
import csv
import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

path = Path(sys.argv[1] if len(sys.argv) > 1 else Path(__file__).resolve().parent / "results" / "sparse_solver_bench.csv")
rows = list(csv.DictReader(path.open()))
kinds = sorted({r["kind"] for r in rows}, reverse=True)
solvers = list(dict.fromkeys(r["solver"] for r in rows))
fig, axes = plt.subplots(2, len(kinds), figsize=(5.5 * len(kinds), 8), squeeze=False)
for col, kind in enumerate(kinds):
    for row, (key, label) in enumerate([("refactor_us", "factorization per Newton matrix [µs]"), ("solve_us", "solve [µs]")]):
        ax = axes[row][col]
        for solver in solvers:
            points = sorted((int(r["size"]), float(r[key])) for r in rows if r["kind"] == kind and r["solver"] == solver)
            if points:
                ax.loglog(*zip(*points), marker="o", label=solver)
        ax.set_xlabel("reduced matrix rows")
        ax.set_ylabel(label)
        ax.set_title(f"{kind} chains")
        ax.grid(True, which="both", alpha=0.3)
axes[0][0].legend(fontsize=8)
fig.tight_layout()
out = path.with_suffix(".png")
fig.savefig(out, dpi=110)
print(f"wrote {out}")

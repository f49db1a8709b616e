#!/usr/bin/env python3
"""Plot bench/results/reduction_bench.csv (written by build/bin/reduction_bench): the error of reduced bodies
against the full-order reference versus their cost per step.

    python3 bench/reduction_plot.py bench/results/reduction_bench.csv bench/results/reduction_bench.png
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(source, target):
    rows = list(csv.DictReader(open(source)))
    reduced = [r for r in rows if r["body"] == "craig_bampton"]
    full = [r for r in rows if r["body"] == "full_order"][0]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    cost = [float(r["us_per_step"]) for r in reduced]
    error = [float(r["max_tip_error_relative"]) for r in reduced]
    ax.loglog(cost, error, "o-", label="improved GCMS, Craig-Bampton basis")
    for r, c, e in zip(reduced, cost, error):
        ax.annotate(f'{r["modes"]} mode' + ("" if r["modes"] == "1" else "s"), (c, e), textcoords="offset points", xytext=(6, 4), fontsize=8)
    ax.axvline(float(full["us_per_step"]), color="C3", ls="--",
               label=f'full-order reference ({full["coordinates"]} coordinates)')
    ax.set_xlabel("µs per generalized-α step")
    ax.set_ylabel("largest tip error / largest tip deflection")
    ax.set_title("Clamped steel beam under gravity, 8 ms, h = 20 µs")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    print("wrote", target)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2])

#!/usr/bin/env python3
"""Plot bench/results/runtime_bench.csv (written by build/bin/runtime_bench): cost per time step against the
number of modes, constant-core Newton against the dense Newton matrix, with n^2 and n^3 guides.

    python3 bench/runtime_plot.py bench/results/runtime_bench.csv bench/results/runtime_bench.png \
        [bench/results/runtime_bench_native.csv]

The optional third file is the same benchmark built with -DFLEXBODY_NATIVE=ON; its default variant is drawn too.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(source, target, native=None):
    rows = [r for r in csv.DictReader(open(source)) if r["scene"] == "free"]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    labels = {"core_kept": "constant core, matrix kept (default)", "core_every_iteration": "constant core, rebuilt",
              "dense_every_iteration": "dense matrix, rebuilt"}
    for newton, style in (("core_kept", "o-"), ("core_every_iteration", "^-"), ("dense_every_iteration", "s--")):
        pts = sorted((int(r["modes"]), float(r["us_per_step"])) for r in rows if r["newton"] == newton)
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], style, label=labels[newton])
    if native:
        native_rows = [r for r in csv.DictReader(open(native)) if r["scene"] == "free" and r["newton"] == "core_kept"]
        pts = sorted((int(r["modes"]), float(r["us_per_step"])) for r in native_rows)
        ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o-", mfc="none", label="constant core, kept, -march=native")
    core = sorted((int(r["modes"]), float(r["us_per_step"])) for r in rows if r["newton"] == "core_kept")
    dense = sorted((int(r["modes"]), float(r["us_per_step"])) for r in rows if r["newton"] == "dense_every_iteration")
    n0, c0 = core[1]
    ns = [p[0] for p in core]
    ax.loglog(ns, [c0 * (n / n0) ** 2 for n in ns], ":", color="grey", label="∝ n_m²")
    n0, d0 = dense[1]
    ax.loglog(ns, [d0 * (n / n0) ** 3 for n in ns], "-.", color="grey", label="∝ n_m³")
    ax.axhline(20.0, color="C3", lw=0.8, label="target 20 µs (20 modes)")
    ax.set_xlabel("modes n_m (9 n_m GCMS coordinates at most)")
    ax.set_ylabel("µs per generalized-α step")
    ax.set_title("One free flexible bar, ρ∞ = 0.9, h = T₁/50")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    print("wrote", target)


if __name__ == "__main__":
    main(sys.argv[1], sys.argv[2], sys.argv[3] if len(sys.argv) > 3 else None)

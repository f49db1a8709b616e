#!/usr/bin/python3
"""Plot bench/results/convergence_bench.csv (written by build/bin/convergence_bench): each scene's error against the
step size at the integrator's default settings, with a slope-2 guide, and optionally the same scenes run by an
earlier version (dashed).

    python3 bench/convergence_plot.py bench/results/convergence_bench.csv bench/results/convergence_bench.png \
        [OTHER.csv "LABEL" ["TITLE"]]

OTHER.csv is drawn dashed with LABEL after each scene's name (the index-3 form, an earlier commit, ...).
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    return [r for r in csv.DictReader(open(path)) if r["error_m"] != "nan"]


def main(source, target, before=None, before_label="", title="Generalized-α at default settings (ρ∞ = 0.9)"):
    rows = read(source)
    old = read(before) if before else []
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for k, scene in enumerate(scenes):
        mine = [r for r in rows if r["scene"] == scene]
        h = [float(r["step_s"]) for r in mine]
        e = [float(r["error_m"]) for r in mine]
        ax.loglog(h, e, "o-", color=f"C{k}", label=scene)
        # slope 2 through the largest step
        ax.loglog([h[0], h[-1]], [e[0], e[0] * (h[-1] / h[0]) ** 2], ":", color=f"C{k}", lw=1)
        earlier = [r for r in old if r["scene"] == scene]
        if earlier:
            ax.loglog([float(r["step_s"]) for r in earlier], [float(r["error_m"]) for r in earlier], "x--",
                      color=f"C{k}", alpha=0.5, label=f"{scene}, {before_label}")
    ax.set_xlabel("step h [s]")
    ax.set_ylabel("error [m]")
    ax.set_title(f"{title}; dotted: h²")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(target, dpi=120)
    print("wrote", target)


if __name__ == "__main__":
    main(*sys.argv[1:])

#!/usr/bin/env python3
"""Plot bench/results/order_bench.csv (written by build/bin/order_bench): the frequency error of linear and quadratic
tetrahedra against DOFs and against the time of meshing, assembly and the eigen solve, and write its markdown table.

    python3 bench/order_plot.py bench/results/order_bench.csv bench/results/order_bench.png bench/results/order_bench.md
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

TIMOSHENKO = (263.46, 714.57)  # Hz, the steel beam's first two free-free bending pairs (validation/README.md)


def errors(rows):
    """Per row, the relative errors of its reference quantities: the beam's two bending pairs against Timoshenko, the
    bracket's first six frequencies against the finest quadratic mesh (largest of them)."""
    bracket_reference = max((r for r in rows if r["part"] == "bracket" and r["order"] == "2"), key=lambda r: int(r["dofs"]))
    out = []
    for r in rows:
        f = [float(r[f"f{k}_hz"]) for k in range(1, 7) if r[f"f{k}_hz"]]
        if r["part"] == "beam":
            pairs = [(f[0] + f[1]) / 2, (f[2] + f[3]) / 2]
            out.append([p / t - 1 for p, t in zip(pairs, TIMOSHENKO)])
        else:
            ref = [float(bracket_reference[f"f{k}_hz"]) for k in range(1, 7)]
            out.append([a / b - 1 for a, b in zip(f, ref)] if r is not bracket_reference else [float("nan")] * 6)
    return out


def main(source, picture, table):
    rows = list(csv.DictReader(open(source)))
    err = errors(rows)
    fig, axes = plt.subplots(2, 2, figsize=(10, 7.5))
    for col, part in enumerate(("beam", "bracket")):
        for order, marker in (("1", "o-"), ("2", "s-")):
            chosen = [(r, e) for r, e in zip(rows, err) if r["part"] == part and r["order"] == order and e[0] == e[0]]
            dofs = [int(r["dofs"]) for r, _ in chosen]
            time = [float(r["mesh_s"]) + float(r["assembly_s"]) + float(r["eigen_s"]) for r, _ in chosen]
            first = [abs(e[0]) for _, e in chosen]
            label = ("linear" if order == "1" else "quadratic") + " tetrahedra"
            axes[0][col].loglog(dofs, first, marker, label=label)
            axes[1][col].loglog(time, first, marker, label=label)
        what = "first bending pair against Timoshenko" if part == "beam" else "first frequency against the finest quadratic mesh"
        axes[0][col].set_title(f"{part}: {what}", fontsize=9)
        axes[0][col].set_xlabel("DOFs")
        axes[1][col].set_xlabel("mesh + assembly + eigen solve [s]")
        for row in (0, 1):
            axes[row][col].set_ylabel("|relative frequency error|")
            axes[row][col].grid(True, which="both", alpha=0.3)
            axes[row][col].axhline(0.01, color="grey", lw=0.8, ls=":")
            axes[row][col].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(picture, dpi=110)
    with open(table, "w") as md:
        md.write("| part | order | mesh | DOFs | mesh [s] | assembly [s] | eigen [s] | error 1 | error 2 |\n")
        md.write("|---|---:|---|---:|---:|---:|---:|---:|---:|\n")
        for r, e in zip(rows, err):
            errs = "reference | reference" if e[0] != e[0] else f"{e[0]:+.2e} | {e[1]:+.2e}"
            md.write(f'| {r["part"]} | {r["order"]} | {r["mesh"]} | {int(r["dofs"]):,} | {float(r["mesh_s"]):.2f} | '
                     f'{float(r["assembly_s"]):.2f} | {float(r["eigen_s"]):.2f} | {errs} |\n')
    print("wrote", picture, "and", table)


if __name__ == "__main__":
    main(*sys.argv[1:4])

#!/usr/bin/python3
"""fbprep end to end with linear against quadratic tetrahedra (issue 15): frequency error against DOFs and against
fbprep's wall time, with CalculiX (C3D4, C3D10) on the same meshes beside it.

For each part, element order and mesh size it runs `fbprep --order N --json` (the whole pipeline: gmsh, assembly,
free-free modes, GCMS constants, stress recovery, the written body file), measures its wall time and peak RSS, and
up to --ccx-max-dofs writes the same mesh as a CalculiX *FREQUENCY job (bench/prep_bench.py's writer: C3D10 for
quadratic meshes) and times ccx on one thread. Errors: of the beam's first bending pair (the mean of modes 1 and 2)
against Timoshenko (validation/README.md, 263.46 Hz); of the bracket's first frequency against its finest quadratic
run here.
Writes results/order_prep_bench.{csv,md,png}. See bench/README.md.
"""
import argparse, csv, json, os, shutil, sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import prep_bench  # noqa: E402  (run_measured, write_inp, parse_ccx_frequencies, machine_info)

REPO = Path(__file__).resolve().parent.parent
TIMOSHENKO_PAIR = 263.46  # Hz, the 1 x 0.05 x 0.05 m steel beam's first free-free bending pair
PARTS = {
    # name: (input, unit, {order: sizes in the input's unit}), the bracket's last quadratic size is its reference
    "beam": (REPO / "tests/data/gmsh-beam/beam_1m.geo", "m",
             {1: [0.05, 0.025, 0.0125, 0.00625, 0.004, 0.003], 2: [0.05, 0.025, 0.0125, 0.0083]}),
    "bracket": (REPO / "meshes/bracket.step", None,
                {1: [6, 4, 3, 2, 1.5, 1.2], 2: [8, 6, 4, 3, 2.5, 1.6]}),
}
COLUMNS = ["part", "order", "size", "dofs", "fbprep_s", "mesh_s", "assembly_s", "modes_s", "gcms_s", "recovery_s",
           "write_s", "peak_mb", "f1_hz", "compared_hz", "error", "ccx_s", "ccx_error", "ccx_vs_fbprep"]


def run_fbprep(fbprep, part, unit, order, size, modes, work):
    cmd = [str(fbprep), str(part), "-o", str(work / "body.fbh5"), "--order", str(order), "--mesh-size", str(size),
           "--modes", str(modes), "--json", "--quiet",
           "--volume-tolerance", "0.5"] + (["--unit", unit] if unit else [])  # the sweep measures the coarse meshes too
    rc, wall, rss, out = prep_bench.run_measured(cmd, work)
    if rc != 0:
        raise RuntimeError(f"fbprep failed ({rc}): {(work / 'stderr.txt').read_text().strip()}")
    return dict(json.loads(out), wall_s=wall, rss_mb=rss)


def run_ccx(work, modes, timeout):
    prep_bench.write_inp(work / "body.fbh5", work / "job.inp", modes)
    env = dict(os.environ, CCX_NPROC_EQUATION_SOLVER="1", OMP_NUM_THREADS="1")
    rc, wall, _, out = prep_bench.run_measured(["ccx", "-i", "job"], work, timeout, env)
    if rc == "timeout":
        return {"status": "timeout", "wall_s": wall}
    freqs = prep_bench.parse_ccx_frequencies(work / "job.dat") if (work / "job.dat").exists() else []
    if rc != 0 or len(freqs) < modes + 6 or "*ERROR" in out:
        return {"status": f"error (rc {rc}, {len(freqs)} eigenvalues)", "wall_s": wall}
    return {"status": "ok", "wall_s": wall, "frequencies_hz": sorted(freqs)[6:]}


def compared(part, frequencies):
    """The frequency the error is of: the beam's first bending pair (mean of modes 1, 2), the bracket's mode 1."""
    return 0.5 * (frequencies[0] + frequencies[1]) if part == "beam" else frequencies[0]


def sweep(args):
    runs = []
    for name, (part, unit, sizes) in PARTS.items():
        if args.parts and name not in args.parts:
            continue
        for order, order_sizes in sizes.items():
            for size in (order_sizes[:2] if args.quick else order_sizes):
                work = args.out / "work" / f"{name}-{order}-{size:g}"
                work.mkdir(parents=True, exist_ok=True)
                try:
                    fb = run_fbprep(args.fbprep, part, unit, order, size, args.modes, work)
                except RuntimeError as e:  # e.g. out of memory at the largest size: keep the other runs
                    print(f"{name} order {order} h {size:g}: {e}", flush=True)
                    shutil.rmtree(work)
                    continue
                ccx = {"status": "skipped"}
                if fb["dofs"] <= args.ccx_max_dofs and shutil.which("ccx"):
                    ccx = run_ccx(work, args.modes, args.ccx_timeout)
                runs.append({"part": name, "order": order, "size": size, "fbprep": fb, "ccx": ccx})
                print(f"{name} order {order} h {size:g}: {fb['dofs']} DOFs, fbprep {fb['wall_s']:.2f} s, ccx "
                      f"{ccx['status']}" + (f" {ccx['wall_s']:.1f} s" if "wall_s" in ccx else ""), flush=True)
                shutil.rmtree(work)
    return runs


def rows_of(runs):
    rows = []
    for name in PARTS:
        part_runs = [r for r in runs if r["part"] == name]
        if not part_runs:
            continue
        finest = None  # the run that is its part's reference, if one is
        if name == "beam":
            reference = TIMOSHENKO_PAIR
        else:  # the finest quadratic run
            quadratic = [r for r in part_runs if r["order"] == 2]
            if not quadratic:
                continue
            finest = max(quadratic, key=lambda r: r["fbprep"]["dofs"])
            reference = compared(name, finest["fbprep"]["frequencies_hz"])
        for r in part_runs:
            fb, t, ccx = r["fbprep"], r["fbprep"]["timings_s"], r["ccx"]
            f = fb["frequencies_hz"]
            row = {"part": name, "order": r["order"], "size": r["size"], "dofs": fb["dofs"], "fbprep_s": fb["wall_s"],
                   "mesh_s": t["mesh"], "assembly_s": t["assembly"], "modes_s": t["modes"], "gcms_s": t["gcms"],
                   "recovery_s": t["recovery"], "write_s": t["write"], "peak_mb": fb["rss_mb"], "f1_hz": f[0],
                   "compared_hz": compared(name, f), "error": compared(name, f) / reference - 1.0, "ccx_s": None, "ccx_error": None,
                   "ccx_vs_fbprep": None}
            if r is finest:
                row["error"] = None  # the reference itself
            if ccx["status"] == "ok":
                g = ccx["frequencies_hz"]
                row["ccx_s"] = ccx["wall_s"]
                row["ccx_error"] = compared(name, g) / reference - 1.0
                row["ccx_vs_fbprep"] = float(np.max(np.abs(np.array(g[:len(f)]) / np.array(f) - 1.0)))
            elif ccx["status"] != "skipped":
                row["ccx_s"] = ccx["status"]
            rows.append(row)
    return rows


def cell(value, kind):
    if value is None:
        return "reference" if kind == "error" else "-"
    if isinstance(value, str):
        return value
    if kind == "error":
        return f"{value:+.2e}"
    if kind == "int":
        return f"{value:,}"
    return f"{value:.2f}"


def table(rows):
    head = ("| part | order | h | DOFs | fbprep [s] | mesh | assembly | modes | gcms | peak [MB] | f [Hz] | error | "
            "ccx [s] | ccx error | ccx vs fbprep |")
    lines = [head, "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        unit = " m" if r["part"] == "beam" else " mm"
        ccx_error = "-" if r["ccx_error"] is None else cell(r["ccx_error"], "error")
        ccx_vs = "-" if r["ccx_vs_fbprep"] is None else f"{r['ccx_vs_fbprep']:.1e}"
        lines.append(f"| {r['part']} | {r['order']} | {r['size']:g}{unit} | {cell(r['dofs'], 'int')} | "
                     f"{cell(r['fbprep_s'], 's')} | {cell(r['mesh_s'], 's')} | {cell(r['assembly_s'], 's')} | "
                     f"{cell(r['modes_s'], 's')} | {cell(r['gcms_s'], 's')} | {r['peak_mb']:.0f} | {r['compared_hz']:.2f} | "
                     f"{cell(r['error'], 'error')} | {cell(r['ccx_s'], 's')} | {ccx_error} | {ccx_vs} |")
    return "\n".join(lines) + "\n"


def plot(rows, png):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    parts = [p for p in PARTS if any(r["part"] == p for r in rows)]
    fig, axes = plt.subplots(len(parts), 2, figsize=(11, 4.2 * len(parts)), squeeze=False)
    for row_axes, name in zip(axes, parts):
        for order, colour in ((1, "tab:red"), (2, "tab:blue")):
            rs = [r for r in rows if r["part"] == name and r["order"] == order and r["error"] is not None]
            label = "linear (tet4)" if order == 1 else "quadratic (tet10)"
            err = [abs(r["error"]) for r in rs]
            row_axes[0].loglog([r["dofs"] for r in rs], err, "o-", color=colour, label=f"fbprep {label}")
            row_axes[1].loglog([r["fbprep_s"] for r in rs], err, "o-", color=colour, label=f"fbprep {label}")
            cc = [r for r in rs if isinstance(r["ccx_s"], float)]
            row_axes[1].loglog([r["ccx_s"] for r in cc], [abs(r["ccx_error"]) for r in cc], "^--", color=colour,
                               alpha=0.6, label=f"ccx {'C3D4' if order == 1 else 'C3D10'} (one thread)")
        for ax, xlabel in zip(row_axes, ("DOFs", "wall time [s]")):
            ax.axhline(1e-2, color="0.6", lw=0.8, ls=":")
            ax.set_xlabel(xlabel)
            ax.set_ylabel("|error| of the first bending pair" if name == "beam" else "|error| of the first frequency")
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
        reference = "Timoshenko" if name == "beam" else "the finest quadratic mesh"
        row_axes[0].set_title(f"{name}: error against {reference}, by DOFs")
        row_axes[1].set_title(f"{name}: by fbprep's (and ccx's) wall time")
    fig.tight_layout()
    fig.savefig(png, dpi=110)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fbprep", type=Path, default=REPO / "build/bin/fbprep")
    p.add_argument("--modes", type=int, default=10, help="elastic modes (fbprep --modes; ccx gets 6 more)")
    p.add_argument("--parts", nargs="*", choices=list(PARTS), help="default: all")
    p.add_argument("--ccx-max-dofs", type=int, default=60000, help="skip ccx above this many DOFs")
    p.add_argument("--ccx-timeout", type=float, default=600, help="ccx time limit [s]")
    p.add_argument("--out", type=Path, default=REPO / "bench/results")
    p.add_argument("--quick", action="store_true", help="the two coarsest sizes of each order (smoke run)")
    p.add_argument("--replot", type=Path, metavar="JSON", help="no runs: table, CSV and plot of a saved JSON")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        raw = json.loads(args.replot.read_text())
    else:
        args.fbprep = args.fbprep.resolve()
        if not args.fbprep.is_file():
            p.error(f"{args.fbprep} not found: build it first or pass --fbprep")
        raw = {"machine": prep_bench.machine_info(), "modes": args.modes, "runs": sweep(args)}
        raw["machine"]["load_avg_end"] = os.getloadavg()
        work = args.out / "work"
        if work.exists() and not any(work.iterdir()):
            work.rmdir()
    rows = rows_of(raw["runs"])
    text = table(rows)
    print(text)
    stem = args.out / "order_prep_bench"
    Path(f"{stem}.md").write_text(text)
    Path(f"{stem}.json").write_text(json.dumps(raw, indent=1))
    with open(f"{stem}.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    plot(rows, f"{stem}.png")


if __name__ == "__main__":
    main()

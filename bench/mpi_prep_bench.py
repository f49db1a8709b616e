#!/usr/bin/python3
"""The eigen stage on one and on two MPI ranks: fbprep with ARPACK (CHOLMOD) against the slepc backend.

For each mesh of the bracket it runs, on the same .msh (meshed once by gmsh with HXT, so every
configuration gets the same matrices):

  arpack        fbprep --eigensolver arpack                 one process, two OpenMP threads
  slepc-1       fbprep --eigensolver slepc                  one MPI rank, MUMPS, two threads
  slepc-2       mpirun -np 2 fbprep --eigensolver slepc     two ranks, one thread each
  slepc-2-ooc   as slepc-2 with MUMPS's out-of-core factor (-st_mat_mumps_icntl_22 1; largest mesh only)
  slepc-1-ooc   one rank, out of core (not in the default list: --configs slepc-1-ooc)

and records the stage times, MUMPS's factor size and flops, rank 0's peak memory and the other
ranks'. Writes results/mpi_prep_bench.{csv,json,md,png} and prints the table. Needs a build with
-DFLEXBODY_WITH_SLEPC=ON. See bench/README.md ("Distributed eigen stage").
"""
import argparse, csv, json, os, shutil, subprocess
from pathlib import Path

from prep_bench import machine_info, run_measured

REPO = Path(__file__).resolve().parent.parent
COLUMNS = ["size_mm", "config", "ranks", "dofs", "modes_s", "factorize_s", "solve_s", "gcms_s", "total_s", "wall_s",
           "solves", "factor_entries", "factor_gflop", "factor_mb", "rank0_peak_mb", "other_ranks_peak_mb",
           "max_f_rel_diff"]
MPI_ENV = {"OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_btl_vader_single_copy_mechanism": "none"}


def mesh(part, size, work):
    """The part meshed once by gmsh's HXT at `size` mm (cached in work)."""
    msh = work / f"bracket_{size:g}.msh"
    if not msh.exists():
        subprocess.run(["gmsh", str(part), "-3", "-clmax", str(size), "-algo", "hxt", "-format", "msh41", "-o",
                        str(msh)], check=True, capture_output=True)
    return msh


def run(args, msh, config, work):
    """One fbprep run of a configuration; its JSON plus wall time."""
    env = dict(os.environ, **MPI_ENV)
    cmd = [str(args.fbprep), str(msh), "--unit", "mm", "--modes", str(args.modes), "--json", "--quiet",
           "-o", str(work / f"{config}.fbh5")]
    if config == "arpack":
        cmd += ["--eigensolver", "arpack"]
        env["OMP_NUM_THREADS"] = "2"
    else:
        cmd += ["--eigensolver", "slepc"]
        if config.startswith("slepc-2"):
            cmd = [shutil.which("mpirun"), "--oversubscribe", "-np", "2"] + cmd
            env["OMP_NUM_THREADS"] = env["OPENBLAS_NUM_THREADS"] = "1"
        else:
            env["OMP_NUM_THREADS"] = "2"
        if config.endswith("ooc"):
            ooc = work / "ooc"
            ooc.mkdir(exist_ok=True)
            env["PETSC_OPTIONS"] = "-st_mat_mumps_icntl_22 1"
            env["MUMPS_OOC_TMPDIR"] = str(ooc)
    rc, wall, _, out = run_measured(cmd, work, env=env)
    if rc != 0:
        raise RuntimeError(f"{config} failed ({rc}): {(work / 'stderr.txt').read_text().strip()[-400:]}")
    return dict(json.loads(out), wall_s=wall)


def row_of(size, config, fb, reference):
    t = fb["timings_s"]
    f, f_ref = fb["frequencies_hz"], reference["frequencies_hz"]
    return {"size_mm": size, "config": config, "ranks": fb.get("mpi_ranks", 1), "dofs": fb["dofs"],
            "modes_s": t["modes"], "factorize_s": t["factorize"], "solve_s": t["solve"], "gcms_s": t["gcms"],
            "total_s": t["total"], "wall_s": fb["wall_s"], "solves": fb["solves"],
            "factor_entries": fb["factor_nonzeros"], "factor_gflop": fb["factor_flops"] * 1e-9, "factor_mb": fb["factor_mb"],
            "rank0_peak_mb": fb["peak_memory_mb"], "other_ranks_peak_mb": fb.get("peak_memory_other_ranks_mb"),
            "max_f_rel_diff": max(abs(a / b - 1.0) for a, b in zip(f, f_ref))}


def fmt(v):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1e-2 or abs(v) >= 1e5 else f"{v:.2f}"
    return str(v)


def write_results(raw, out):
    rows = raw["rows"]
    header = "| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS) + "\n"
    table = header + "".join("| " + " | ".join(fmt(r[c]) for c in COLUMNS) + " |\n" for r in rows)
    print(table)
    (out / "mpi_prep_bench.md").write_text(table)
    with open(out / "mpi_prep_bench.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(rows)
    (out / "mpi_prep_bench.json").write_text(json.dumps(raw, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(11, 4.2))
    for config in dict.fromkeys(r["config"] for r in rows):
        sel = [r for r in rows if r["config"] == config]
        dofs = [r["dofs"] for r in sel]
        ax_t.plot(dofs, [r["modes_s"] for r in sel], "o-", label=config)
        line, = ax_m.plot(dofs, [max(r["rank0_peak_mb"], r["other_ranks_peak_mb"] or 0) / 1024 for r in sel], "o-",
                          label=config)
        if sel[0]["ranks"] > 1:  # the whole run's memory: rank 0 plus the others
            ax_m.plot(dofs, [(r["rank0_peak_mb"] + (r["ranks"] - 1) * r["other_ranks_peak_mb"]) / 1024 for r in sel],
                      "x:", color=line.get_color(), label=f"{config}, all ranks")
    ax_t.set(xscale="log", yscale="log", xlabel="DOFs", ylabel="eigen stage [s] (factor + solves)",
             title=f"{raw['options']['modes']} modes, bracket, {raw['machine']['nproc']} cores")
    ax_m.set(xscale="log", xlabel="DOFs", ylabel="peak memory [GiB]: largest process, and all ranks")
    ax_m.axhline(8, color="grey", lw=0.8, ls="--")
    for ax in (ax_t, ax_m):
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(out / "mpi_prep_bench.png", dpi=120)


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fbprep", type=Path, default=REPO / "build/bin/fbprep")
    p.add_argument("--part", type=Path, default=REPO / "meshes/bracket.step")
    p.add_argument("--sizes", default="1.5,0.82,0.45", help="mesh sizes [mm], comma list")
    p.add_argument("--modes", type=int, default=26)
    p.add_argument("--configs", default="arpack,slepc-1,slepc-2")
    p.add_argument("--ooc", action="store_true", help="also slepc-2-ooc at the largest size")
    p.add_argument("--out", type=Path, default=REPO / "bench/results")
    p.add_argument("--work", type=Path, default=Path("/tmp/flexbody_mpi_bench"), help="meshes and body files")
    p.add_argument("--replot", type=Path, metavar="JSON", help="no runs: table, CSV and plot of a saved JSON")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        return write_results(json.loads(args.replot.read_text()), args.out)
    args.work.mkdir(parents=True, exist_ok=True)
    args.fbprep = args.fbprep.resolve()
    if not args.fbprep.is_file():
        p.error(f"{args.fbprep} not found: build with -DFLEXBODY_WITH_SLEPC=ON or pass --fbprep")
    sizes = [float(s) for s in args.sizes.split(",")]
    raw = {"machine": machine_info(), "options": {k: str(v) for k, v in vars(args).items()}, "rows": []}
    for size in sizes:
        msh = mesh(args.part.resolve(), size, args.work)
        configs = args.configs.split(",") + (["slepc-2-ooc"] if args.ooc and size == min(sizes) else [])
        runs = {}
        for config in configs:
            runs[config] = run(args, msh, config, args.work)
            print(f"h = {size} mm, {config}: {runs[config]['dofs']} DOFs, eigen stage "
                  f"{runs[config]['timings_s']['modes']:.1f} s, whole {runs[config]['wall_s']:.1f} s", flush=True)
        reference = runs[configs[0]]
        raw["rows"] += [row_of(size, c, runs[c], reference) for c in configs]
    raw["machine"]["load_avg_end"] = os.getloadavg()
    write_results(raw, args.out)


if __name__ == "__main__":
    main()

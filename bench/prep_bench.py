#!/usr/bin/python3
"""Preprocessing benchmark: fbprep (mesh, assembly, modes) against CalculiX over mesh sizes.

For each mesh size and eigensolver it runs `fbprep --json`, measures wall time and the child's peak
RSS, then (once per size) writes the same mesh as a CalculiX .inp, runs `ccx` *FREQUENCY on it and
compares the frequencies. Writes results/prep_bench.{csv,json,png}. See bench/README.md.
"""
import argparse, csv, json, os, platform, shutil, subprocess, threading, time
from datetime import datetime, timezone
from pathlib import Path

import h5py
import numpy as np

REPO = Path(__file__).resolve().parent.parent
COLUMNS = ["size_mm", "solver", "mesher", "dofs", "mesh_s", "assembly_s", "analyze_s", "factorize_s", "solve_s", "modes_s",
           "gcms_s", "total_s", "fbprep_peak_mb", "solves", "max_residual", "ccx_s", "ccx_peak_mb",
           "f1_rel_diff", "max_rel_diff"]


def run_measured(cmd, cwd, timeout=None, env=None):
    """Run cmd, wait for it with os.wait4 and return (rc or "timeout", wall s, peak RSS MB, stdout).

    ru_maxrss from wait4 is the child's own peak resident set (KiB on Linux). stdout and stderr go
    to files in cwd so no pipe can fill up. On timeout the child's process group is killed."""
    with open(Path(cwd) / "stdout.txt", "w") as out, open(Path(cwd) / "stderr.txt", "w") as err:
        t0 = time.perf_counter()
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=out, stderr=err, start_new_session=True)
        res = {}

        def waiter():
            _, status, usage = os.wait4(proc.pid, 0)
            res.update(wall=time.perf_counter() - t0, status=status, rss=usage.ru_maxrss)

        thread = threading.Thread(target=waiter)
        thread.start()
        thread.join(timeout)
        timed_out = thread.is_alive()
        if timed_out:
            os.killpg(proc.pid, 9)
            thread.join()
        proc.returncode = os.waitstatus_to_exitcode(res["status"])  # keep Popen from re-waiting
    rc = "timeout" if timed_out else proc.returncode
    return rc, res["wall"], res["rss"] / 1024.0, (Path(cwd) / "stdout.txt").read_text()


def run_fbprep(args, size, solver, work):
    """Run fbprep on the part at one mesh size with one eigensolver; return its JSON plus our timings."""
    cmd = [str(args.fbprep), str(args.part), "-o", str(work / f"{solver}.fbh5"), "--mesh-size",
           str(size), "--modes", str(args.modes), "--eigensolver", solver, "--mesher", args.mesher, "--json", "--quiet",
           "--volume-tolerance", "0.5",  # timing every size of the sweep, the coarse ones too
           "--order", "1"]  # the linear meshes its recorded results are for (the default is quadratic from 0.13)
    rc, wall, rss, out = run_measured(cmd, work)
    if rc != 0:
        raise RuntimeError(f"fbprep failed ({rc}): {(work / 'stderr.txt').read_text().strip()}")
    return dict(json.loads(out), wall_s=wall, rss_mb=rss)


def ccx_num(v):
    """Shortest round-trip text of v, cut to at most 20 characters.

    ccx reads each number of a data line as `(textpart(1:20), '(f20.0)')`: a longer field is silently
    truncated, which can chop the exponent ("1.234567890123456e-10" would read as 0.1234...)."""
    s, digits = repr(v), 17
    while len(s) > 20:
        digits -= 1
        s = f"{v:.{digits}g}"
    return s


def write_inp(fbh5, inp, n_modes):
    """Write the mesh and material of a body file as a CalculiX *FREQUENCY job (N + 6 rigid modes).

    Linear tetrahedra as C3D4, quadratic ones (element_order 2) as C3D10: the body file's node order is Abaqus'."""
    with h5py.File(fbh5, "r") as f:
        nodes, tets = f["/mesh/nodes"][...], f["/mesh/tets"][...]
        mat = {k: float(f["/material"].attrs[k]) for k in ("youngs_modulus", "poisson_ratio", "density")}
    with open(inp, "w") as out:
        out.write("*NODE, NSET=NALL\n")
        out.writelines(f"{i}, {ccx_num(x)}, {ccx_num(y)}, {ccx_num(z)}\n"
                       for i, (x, y, z) in enumerate(nodes.tolist(), 1))
        out.write(f"*ELEMENT, TYPE={'C3D10' if tets.shape[1] == 10 else 'C3D4'}, ELSET=EALL\n")
        eids = np.arange(1, len(tets) + 1)
        np.savetxt(out, np.column_stack([eids, tets.astype(np.int64) + 1]), fmt="%d", delimiter=", ")
        out.write(f"*MATERIAL, NAME=M\n*ELASTIC\n{ccx_num(mat['youngs_modulus'])}, "
                  f"{ccx_num(mat['poisson_ratio'])}\n*DENSITY\n{ccx_num(mat['density'])}\n"
                  f"*SOLID SECTION, ELSET=EALL, MATERIAL=M\n"
                  f"*STEP\n*FREQUENCY\n{n_modes + 6}\n*END STEP\n")


def parse_ccx_frequencies(dat):
    """Return the frequencies [Hz] (cycles/time column) of the first eigenvalue table in a .dat file."""
    freqs, started = [], False
    for line in Path(dat).read_text().splitlines():
        if "E I G E N V A L U E   O U T P U T" in line:
            started = True
            continue
        parts = line.split()
        if started and len(parts) == 5 and parts[0].isdigit():
            freqs.append(float(parts[3]))
        elif started and freqs and not parts:
            break
    return freqs


def run_ccx(args, fbh5, work):
    """Run CalculiX on the mesh of fbh5; return wall time, peak RSS and elastic frequencies or a status."""
    write_inp(fbh5, work / "job.inp", args.modes)
    env = dict(os.environ, CCX_NPROC_EQUATION_SOLVER="1", OMP_NUM_THREADS="1")
    rc, wall, rss, out = run_measured(["ccx", "-i", "job"], work, args.ccx_timeout, env)
    if rc == "timeout":
        return {"status": "timeout", "wall_s": wall, "rss_mb": rss}
    freqs = parse_ccx_frequencies(work / "job.dat") if (work / "job.dat").exists() else []
    if rc != 0 or len(freqs) < args.modes + 6 or "*ERROR" in out:
        return {"status": f"error (rc {rc}, {len(freqs)} eigenvalues)", "wall_s": wall, "rss_mb": rss}
    return {"status": "ok", "wall_s": wall, "rss_mb": rss, "frequencies_hz": sorted(freqs)[6:]}


def machine_info():
    """CPU, core count, memory, BLAS alternative and time of the run."""
    cpu = next((l.split(":", 1)[1].strip() for l in open("/proc/cpuinfo") if l.startswith("model name")), "?")
    mem_kb = next(int(l.split()[1]) for l in open("/proc/meminfo") if l.startswith("MemTotal"))
    q = subprocess.run(["update-alternatives", "--query", "libblas.so.3-x86_64-linux-gnu"],
                       capture_output=True, text=True).stdout
    blas = next((l.split(":", 1)[1].strip() for l in q.splitlines() if l.startswith("Value:")), "?")
    return {"date_utc": datetime.now(timezone.utc).isoformat(timespec="seconds"), "nproc": os.cpu_count(),
            "cpu": cpu, "mem_total_gib": round(mem_kb / 2**20, 1), "blas": blas,
            "kernel": platform.release(), "load_avg_start": os.getloadavg()}


def row_of(size, solver, fb, ccx):
    """Flatten one fbprep run and the ccx run of its size into a table row."""
    t = fb["timings_s"]
    row = {"size_mm": size, "solver": solver, "mesher": fb.get("mesher"), "dofs": fb["dofs"], "mesh_s": t.get("mesh"),
           "assembly_s": t.get("assembly"), "analyze_s": t.get("analyze"), "factorize_s": t.get("factorize"), "solve_s": t.get("solve"),
           "modes_s": t.get("modes"), "gcms_s": t.get("gcms"), "total_s": t.get("total"), "fbprep_peak_mb": fb["rss_mb"],
           "solves": fb.get("solves"), "max_residual": fb["max_relative_residual"],
           "ccx_s": ccx["status"], "ccx_peak_mb": None, "f1_rel_diff": None, "max_rel_diff": None}
    if ccx["status"] in ("ok", "timeout"):
        row["ccx_s"], row["ccx_peak_mb"] = ccx["wall_s"], ccx["rss_mb"]
    if ccx["status"] == "ok":
        f, g = np.array(fb["frequencies_hz"]), np.array(ccx["frequencies_hz"][:len(fb["frequencies_hz"])])
        row["f1_rel_diff"] = float(f[0] / g[0] - 1)
        row["max_rel_diff"] = float(np.max(np.abs(f / g - 1)))
    if ccx["status"] == "timeout":
        row["ccx_s"] = f"timeout>{ccx['wall_s']:.0f}"
    return row


def fmt(v):
    """Format a table cell."""
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.2e}" if abs(v) < 1e-3 and v != 0 else f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"
    return str(v)


def print_table(rows):
    """Print rows as an aligned text table."""
    cells = [COLUMNS] + [[fmt(r.get(c)) for c in COLUMNS] for r in rows]
    widths = [max(len(c[i]) for c in cells) for i in range(len(COLUMNS))]
    for c in cells:
        print("  ".join(s.rjust(w) for s, w in zip(c, widths)), flush=True)


def plot(rows, png):
    """Log-log time per stage and peak memory against DOFs, fbprep (per solver) and ccx, with targets."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(13, 8))
    styles = ["-", "--", ":", "-."]
    for i, solver in enumerate(dict.fromkeys(r["solver"] for r in rows)):
        rs = [r for r in rows if r["solver"] == solver]
        x = [r["dofs"] for r in rs]
        for key, color in [("assembly_s", "C0"), ("factorize_s", "C1"), ("solve_s", "C2"), ("total_s", "C3")]:
            ax_t.plot(x, [r[key] for r in rs], styles[i % 4], color=color, marker="o",
                      label=f"fbprep {solver}: {key[:-2]}")
        ax_t.plot(x, [r["assembly_s"] + r["modes_s"] for r in rs], styles[i % 4], color="C4", marker="s",
                  label=f"fbprep {solver}: assembly + modes")
        ax_m.plot(x, [r["fbprep_peak_mb"] for r in rs], styles[i % 4], color="C3", marker="o",
                  label=f"fbprep {solver}")
    cc = [r for r in rows if r["solver"] == rows[0]["solver"] and r["ccx_peak_mb"] is not None]
    ok = [r for r in cc if isinstance(r["ccx_s"], float)]
    ax_t.plot([r["dofs"] for r in ok], [r["ccx_s"] for r in ok], "-", color="k", marker="^", label="ccx total")
    ax_m.plot([r["dofs"] for r in cc], [r["ccx_peak_mb"] for r in cc], "-", color="k", marker="^", label="ccx")
    ax_t.plot([2e5], [15], "r*", ms=16, label="target: assembly + modes <= 15 s at 200k DOFs")
    ax_m.axhline(24 * 1024, color="r", lw=1, label="24 GiB")
    ax_m.plot([1e6], [24 * 1024], "r*", ms=16, label="target: 1M DOFs within 24 GiB")
    for ax, ylabel in [(ax_t, "wall time [s]"), (ax_m, "peak RSS [MB]")]:
        ax.set(xscale="log", yscale="log", xlabel="DOFs", ylabel=ylabel)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2)
    ax_t.set_title("time per stage")
    ax_m.set_title("peak memory")
    fig.tight_layout()
    fig.savefig(png, dpi=120)


def main():
    """Parse options, run the sweep, write the table, CSV, JSON and plot."""
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--fbprep", type=Path, default=REPO / "build/bin/fbprep")
    p.add_argument("--part", type=Path, default=REPO / "meshes/bracket.step")
    p.add_argument("--sizes", default="3.5,2.2,1.5,1.0,0.75,0.6,0.48", help="mesh sizes [mm], comma list")
    p.add_argument("--modes", type=int, default=26, help="elastic modes")
    p.add_argument("--eigensolvers", default="arpack", help="comma list of --eigensolver values")
    p.add_argument("--mesher", default="delaunay", choices=["delaunay", "hxt"], help="fbprep --mesher")
    p.add_argument("--ccx-max-dofs", type=int, default=300000, help="skip ccx above this many DOFs")
    p.add_argument("--ccx-timeout", type=float, default=900, help="ccx time limit [s]")
    p.add_argument("--out", type=Path, default=REPO / "bench/results")
    p.add_argument("--quick", action="store_true", help="sizes 3.5,2.2 only (smoke run, ~1 min)")
    p.add_argument("--keep", action="store_true", help="keep .fbh5 and ccx files in OUT/work")
    p.add_argument("--replot", type=Path, metavar="JSON", help="no runs: table, CSV and plot of a saved JSON")
    args = p.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        return write_results(json.loads(args.replot.read_text()), args.out)
    sizes = [3.5, 2.2] if args.quick else [float(s) for s in args.sizes.split(",")]
    solvers = args.eigensolvers.split(",")
    # Absolute: fbprep runs in OUT/work/h<size>, where a relative output path would name another directory.
    args.fbprep, args.part, args.out = args.fbprep.resolve(), args.part.resolve(), args.out.resolve()
    if not args.fbprep.is_file():
        p.error(f"{args.fbprep} not found: build it (bash scripts/build.sh) or pass --fbprep")
    raw = {"machine": machine_info(), "options": {k: str(v) for k, v in vars(args).items()}, "runs": []}
    rows = []
    for size in sizes:
        work = args.out / "work" / f"h{size:g}"
        work.mkdir(parents=True, exist_ok=True)
        try:
            fbs = {s: run_fbprep(args, size, s, work) for s in solvers}
        except RuntimeError as e:  # e.g. out of memory at the largest size: keep what we have
            print(f"h = {size} mm: {e}; stopping the sweep", flush=True)
            raw["error"] = f"h = {size} mm: {e}"
            break
        dofs = fbs[solvers[0]]["dofs"]
        if dofs > args.ccx_max_dofs:
            ccx = {"status": "skipped"}
        else:
            ccx = run_ccx(args, work / f"{solvers[0]}.fbh5", work)
        raw["runs"].append({"size_mm": size, "fbprep": fbs, "ccx": ccx})
        rows += [row_of(size, s, fbs[s], ccx) for s in solvers]
        times = ", ".join(f"{s} {fbs[s]['wall_s']:.1f} s" for s in solvers)
        ccx_time = f" {ccx['wall_s']:.1f} s" if "wall_s" in ccx else ""
        print(f"h = {size} mm: {dofs} DOFs, fbprep {times}, ccx {ccx['status']}{ccx_time}", flush=True)
        if not args.keep:
            shutil.rmtree(work)
    if not args.keep and "error" in raw:
        shutil.rmtree(args.out / "work" / f"h{size:g}", ignore_errors=True)
    if not args.keep and (args.out / "work").exists() and not any((args.out / "work").iterdir()):
        (args.out / "work").rmdir()
    raw["rows"], raw["machine"]["load_avg_end"] = rows, os.getloadavg()
    write_results(raw, args.out)


def write_results(raw, out):
    """Print the table of raw["rows"] and write prep_bench.csv, .json and .png into out."""
    print_table(raw["rows"])
    with open(out / "prep_bench.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=COLUMNS)
        w.writeheader()
        w.writerows(raw["rows"])
    (out / "prep_bench.json").write_text(json.dumps(raw, indent=1))
    if raw["rows"]:
        plot(raw["rows"], out / "prep_bench.png")
    print(f"wrote {out}/prep_bench.csv, .json" + (", .png" if raw["rows"] else ""))


if __name__ == "__main__":
    main()

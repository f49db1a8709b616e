"""The tables of the preprocessing benchmarks: fbprep against CalculiX, the eigen stage, linear against quadratic
tetrahedra, the CAD corpus (docs/tables.py's library)."""
import statistics

from .common import fixed, gib, integer, json_of, markdown, num, pct, plain, rows_of, sci, sig, table

# --- preprocessing: fbprep against CalculiX, stage timings ----------------------------------------------------------

PREP_COLUMNS = [("size_mm", "h [mm]", plain), ("solver", "solver", str),
                ("mesher", "mesher", str), ("dofs", "DOFs", lambda v: integer(num(v))),
                ("mesh_s", "mesh", lambda v: sig(num(v))), ("assembly_s", "assembly", lambda v: sig(num(v))),
                ("analyze_s", "analysis", lambda v: sig(num(v))), ("factorize_s", "factorize", lambda v: sig(num(v))),
                ("solve_s", "solves", lambda v: sig(num(v))), ("modes_s", "eigen stage", lambda v: sig(num(v))),
                ("gcms_s", "GCMS", lambda v: sig(num(v))), ("total_s", "total", lambda v: sig(num(v))),
                ("fbprep_peak_mb", "peak [MiB]", lambda v: sig(num(v))), ("solves", "solves [n]", str),
                ("max_residual", "max residual", lambda v: sci(num(v))),
                ("ccx_s", "ccx [s]", lambda v: sig(num(v)) if num(v) is not None else (v or "-")),
                ("ccx_peak_mb", "ccx [MiB]", lambda v: sig(num(v))),
                ("f1_rel_diff", "f1 vs ccx", lambda v: pct(num(v))),
                ("max_rel_diff", "max vs ccx", lambda v: pct(num(v), sign=False))]


def prep_table(name, with_ccx):
    rows = rows_of(name)
    columns = [c for c in PREP_COLUMNS if c[0] in rows[0]
               and (with_ccx or not c[0].startswith(("ccx", "f1_", "max_rel")))]
    return markdown([c[1] for c in columns], [[c[2](r[c[0]]) for c in columns] for r in rows],
                    "".join("l" if c[0] in ("solver", "mesher") else "r" for c in columns))


@table("prep_bench", "prep_bench.csv")
def prep_bench():
    """fbprep 0.2 on the bracket, ARPACK and Spectra, against CalculiX (times in s)."""
    return prep_table("prep_bench.csv", True)


@table("prep_bench_f5d4f45", "prep_bench_f5d4f45.csv")
def prep_bench_f5d4f45():
    """The node ordering of f5d4f45 (times in s)."""
    return prep_table("prep_bench_f5d4f45.csv", False)


@table("block_lanczos_sweep", "block_lanczos/prep_bench.csv")
def block_lanczos_sweep():
    """ARPACK against block Lanczos, HXT meshes (times in s)."""
    return prep_table("block_lanczos/prep_bench.csv", False)


@table("block_solve_bench", "block_solve_bench.csv")
def block_solve_bench():
    rows = rows_of("block_solve_bench.csv")
    header = ["b"] + [r["block"] for r in rows]
    return markdown(header, [["one pass [s]"] + [sig(num(r["pass_s"])) for r in rows],
                             ["per vector, relative to b = 1"] + [sig(num(r["relative_per_vector"]), 2) for r in rows]])


@table("mpi_prep_bench", "mpi_prep_bench.csv")
def mpi_prep_bench():
    rows = rows_of("mpi_prep_bench.csv")
    out = []
    for r in rows:
        dofs = num(r["dofs"])
        size = f"{dofs / 1e6:.2f}M" if dofs >= 1e6 else f"{dofs / 1e3:.0f}k"
        diff = num(r["max_f_rel_diff"])
        out.append([size, r["config"], sig(num(r["modes_s"])), sig(num(r["factorize_s"])),
                    f'{sig(num(r["solve_s"]))} ({r["solves"]})', sig(num(r["gcms_s"])), sig(num(r["wall_s"])),
                    gib(num(r["rank0_peak_mb"])), gib(num(r["other_ranks_peak_mb"])),
                    integer(num(r["factor_mb"])), sci(num(r["factor_entries"])),
                    "-" if not diff else sci(diff, 2)])
    return markdown(["DOFs", "config", "eigen stage [s]", "factorize [s]", "solves [s] (n)", "GCMS [s]", "whole [s]",
                     "rank 0 [GiB]", "rank 1 [GiB]", "MUMPS factor [MB]", "factor entries", "max Δf/f vs ARPACK"],
                    out, "rlrrrrrrrrrr")


def stages(t, solves_label):
    rest = t["modes"] - t["analyze"] - t["factorize"] - t["solve"]
    return (f'mesh {t["mesh"]:.1f}, assembly {t["assembly"]:.1f}, eigen {t["modes"]:.1f} (analysis {t["analyze"]:.1f}, '
            f'factorization {t["factorize"]:.1f}, {solves_label} {t["solve"]:.1f}, rest {rest:.1f}), '
            f'GCMS {t["gcms"]:.1f}, write {t["write"]:.1f}')


@table("issue16_targets", "issue16_targets.json")
def issue16_targets():
    """The saved runs of 2026-11-26 (ARPACK on CHOLMOD, HXT, 26 modes); stages in s."""
    data = json_of("issue16_targets.json")
    out = []
    for r in data["runs"]:
        t = r["timings_s"]
        out.append([r["case"], r["note"], f'{r["dofs"]:,}', f'{t["total"]:.1f}', gib(r["peak_memory_mb"]),
                    stages(t, "69 solves")])
    return markdown(["case", "time", "DOFs", "whole run [s]", "peak [GiB]", "stages [s]"], out, "llrrrl")


@table("issue16_targets_0_10", "issue16_targets_0.10.json")
def issue16_targets_0_10():
    """0.10.0, block Lanczos (auto) against ARPACK at 1M DOFs; stages in s."""
    data = json_of("issue16_targets_0.10.json")
    out = []
    for r in data["runs"]:
        j = r["json"]
        t = j["timings_s"]
        passes = j.get("solve_passes")
        label = f'{j["solves"]} solves' + (f' in {passes} passes' if passes and passes != j["solves"] else "")
        out.append([r["run"], f'{j["dofs"]:,}', f'{t["total"]:.1f}', gib(j["peak_memory_mb"]), stages(t, label)])
    return markdown(["run", "DOFs", "whole run [s]", "peak [GiB]", "stages [s]"], out, "lrrrl")


# --- linear against quadratic tetrahedra ---------------------------------------------------------------------------

TIMOSHENKO = (263.46, 714.57)  # Hz, the steel beam's first two free-free bending pairs (as bench/order_plot.py)


@table("order_bench", "order_bench.csv")
def order_bench():
    """Library stages, one run each; errors: beam against Timoshenko, bracket against its finest quadratic mesh."""
    rows = rows_of("order_bench.csv")
    reference = max((r for r in rows if r["part"] == "bracket" and r["order"] == "2"), key=lambda r: int(r["dofs"]))
    out = []
    for r in rows:
        f = [num(r[f"f{k}_hz"]) for k in range(1, 7)]
        if r["part"] == "beam":
            errors = [((f[0] + f[1]) / 2) / TIMOSHENKO[0] - 1, ((f[2] + f[3]) / 2) / TIMOSHENKO[1] - 1]
        elif r is reference:
            errors = None
        else:
            errors = [f[0] / num(reference["f1_hz"]) - 1, f[1] / num(reference["f2_hz"]) - 1]
        seconds = num(r["mesh_s"]) + num(r["assembly_s"]) + num(r["eigen_s"])
        out.append([r["part"], r["order"], r["mesh"], integer(num(r["dofs"])), sig(num(r["assembly_s"]), 2),
                    sig(num(r["eigen_s"]), 2), sig(seconds, 2),
                    "reference" if errors is None else pct(errors[0]),
                    "reference" if errors is None else pct(errors[1])])
    return markdown(["part", "order", "mesh", "DOFs", "assembly [s]", "eigen [s]", "all stages [s]",
                     "error, first", "error, second"], out, "lrlrrrrrr")


@table("order_prep_bench", "order_prep_bench.csv")
def order_prep_bench():
    """fbprep end to end; errors: beam against Timoshenko, bracket against its finest quadratic mesh."""
    out = []
    for r in rows_of("order_prep_bench.csv"):
        unit = "m" if r["part"] == "beam" else "mm"
        ccx, fbprep = num(r["ccx_s"]), num(r["fbprep_s"])
        out.append([r["part"], r["order"], f'{plain(r["size"])} {unit}', integer(num(r["dofs"])), sig(fbprep, 2),
                    sig(num(r["modes_s"]), 2), integer(num(r["peak_mb"])), fixed(num(r["compared_hz"]), 2),
                    "reference" if num(r["error"]) is None else pct(num(r["error"])),
                    "-" if ccx is None else sig(ccx, 2), "-" if ccx is None else sig(ccx / fbprep, 2),
                    "-" if num(r["ccx_vs_fbprep"]) is None else sci(num(r["ccx_vs_fbprep"]), 2)])
    return markdown(["part", "order", "h", "DOFs", "fbprep [s]", "eigen [s]", "peak [MiB]", "f [Hz]", "error",
                     "ccx [s]", "ccx / fbprep time", "max ccx vs fbprep"], out, "lrrrrrrrrrrr")


# --- the CAD corpus ------------------------------------------------------------------------------------------------

def corpus():
    rows = rows_of("cad_corpus_bench.csv")
    by = {(r["part"], r["order"]): r for r in rows}
    parts = list(dict.fromkeys(r["part"] for r in rows))
    both = [p for p in parts if by[(p, "1")]["outcome"] == "body file" and by[(p, "2")]["outcome"] == "body file"]
    return rows, by, parts, both


def change(by, part):
    return num(by[(part, "1")]["first_hz"]) / num(by[(part, "2")]["first_hz"]) - 1


@table("cad_corpus_summary", "cad_corpus_bench.csv")
def cad_corpus_summary():
    rows, by, parts, both = corpus()
    refused = [p for p in parts if p not in both]
    folded = [p for p in both if (num(by[(p, "2")]["folded"]) or 0) > 0]
    cured = [p for p in folded if (num(by[(p, "2")]["folded_after_gmsh"]) or 0) == 0]
    moves = [(num(by[(p, "2")]["largest_move_m"]) or 0, p) for p in folded]
    relative = [((num(by[(p, "2")]["largest_move_m"]) or 0) / num(by[(p, "2")]["mesh_size_m"]), p) for p in folded]
    changes = [(change(by, p), p) for p in both]
    estimates = {o: [(num(by[(p, o)]["first_error_estimate"]), p) for p in both] for o in "12"}
    flagged = [p for e, p in estimates["1"] if e > 0.05]
    high = [p for c, p in changes if c > 0.05]
    missed = [p for p in high if p not in flagged]
    volume = {o: max((abs(num(by[(p, o)]["volume_error"])), p) for p in both) for o in "12"}
    refined = [(p, o) for p in both for o in "12" if by[(p, o)]["refined_from_m"]]
    sewn = [p for p in both if (num(by[(p, "1")]["sewn_faces"]) or 0) > 0]
    seconds = {o: [(num(by[(p, o)]["seconds"]), p) for p in both] for o in "12"}
    second_quad = sorted(estimates["2"], reverse=True)
    out = [
        ["parts (files; as1-tu-203 counts each solid)", f"{len(parts)} ({len(rows)} runs)"],
        ["body files with both orders", str(len(both))],
        ["refused with both orders", f"{len(refused)}: " + ", ".join(refused)],
        ["faces sewn into a solid", ", ".join(f'{p} ({by[(p, "1")]["sewn_faces"]})' for p in sewn) or "none"],
        ["quadratic: parts with folded elements after gmsh raised the order",
         f'{len(folded)} (1 to {max(int(num(by[(p, "2")]["folded"])) for p in folded)} elements)'],
        ["cured by gmsh's smoothing alone / straightening needed", f"{len(cured)} / {len(folded) - len(cured)}"],
        ["largest mid-edge move", f"{sig(max(moves)[0] * 1e6, 2)} µm ({max(moves)[1]}); "
         f"{pct(max(relative)[0], sign=False)} of the element size ({max(relative)[1]})"],
        ["worst volume error, linear / quadratic",
         f'{pct(volume["1"][0], sign=False)} ({volume["1"][1]}) / {pct(volume["2"][0], sign=False)} ({volume["2"][1]})'],
        ["default size refined (runs)", f"{len(refined)}: {sum(o == '1' for _, o in refined)} linear, "
         f"{sum(o == '2' for _, o in refined)} quadratic"],
        ["first frequency, linear over quadratic", f"{pct(min(changes)[0])} to {pct(max(changes)[0], 3)} "
         f"({max(changes)[1]})"],
        ["... above 5 % / above 20 %", f"{len(high)} / {sum(c > 0.2 for c, _ in changes)} of {len(both)}"],
        ["linear estimate above 5 % (flagged)", f"{len(flagged)}, all among those above 5 %" if
         all(p in high for p in flagged) else str(len(flagged))],
        ["above 5 % but not flagged", ", ".join(f"{p} ({pct(change(by, p))}, estimated "
                                                f"{pct(num(by[(p, '1')]['first_error_estimate']), 2, sign=False)})"
                                                for p in missed) or "none"],
        ["quadratic estimate, largest two", "; ".join(f"{p}: {pct(e, 3, sign=False)}" for e, p in second_quad[:2])],
        ["fbprep time, linear: median (range)", f'{statistics.median(s for s, _ in seconds["1"]):.1f} s '
         f'({min(seconds["1"])[0]:.2f} to {max(seconds["1"])[0]:.1f} s, {max(seconds["1"])[1]})'],
        ["fbprep time, quadratic: median (range)", f'{statistics.median(s for s, _ in seconds["2"]):.1f} s '
         f'({min(seconds["2"])[0]:.2f} to {max(seconds["2"])[0]:.1f} s, {max(seconds["2"])[1]})'],
    ]
    return markdown(["", "2026-11-27, fbprep defaults"], out, "ll")


@table("cad_corpus_changes", "cad_corpus_bench.csv")
def cad_corpus_changes():
    """Parts whose first frequency with linear elements is more than 5 % above the quadratic one."""
    rows, by, parts, both = corpus()
    chosen = sorted(((change(by, p), p) for p in both if change(by, p) > 0.05), reverse=True)
    out = []
    for c, p in chosen:
        lin, quad = by[(p, "1")], by[(p, "2")]
        out.append([p, integer(num(lin["dofs"])), integer(num(quad["dofs"])), sig(num(lin["first_hz"]) / 1e3),
                    sig(num(quad["first_hz"]) / 1e3), pct(c), pct(num(lin["first_error_estimate"]), sign=False),
                    pct(num(quad["first_error_estimate"]), sign=False)])
    return markdown(["part", "DOFs, linear", "DOFs, quadratic", "f1 linear [kHz]", "f1 quadratic [kHz]", "change",
                     "estimate, linear", "estimate, quadratic"], out)

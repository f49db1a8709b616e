"""The tables of the runtime benchmarks: cost per step, accuracy against step size and references, the improved GCMS
against the FFRF, scenes of many bodies (docs/tables.py's library)."""
import math
import statistics

from .common import integer, markdown, num, pct, rows_of, sci, sig, slope, table

# --- the runtime: cost per step ------------------------------------------------------------------------------------

@table("runtime_bench", "runtime_bench.csv", "runtime_bench_native.csv")
def runtime_bench():
    """µs per step (Newton iterations per step)."""
    rows = rows_of("runtime_bench.csv")
    native = {(r["scene"], r["modes"], r["newton"]): r for r in rows_of("runtime_bench_native.csv")}
    cases = list(dict.fromkeys((r["scene"], r["modes"], r["coordinates"]) for r in rows))
    by = {(r["scene"], r["modes"], r["newton"]): r for r in rows}

    def cell(r, iterations=True):
        if r is None:
            return "-"
        text = sig(num(r["us_per_step"]))
        return text + (f' ({num(r["iterations_per_step"]):.2f})' if iterations else "")

    out = []
    for scene, modes, coordinates in cases:
        name = "free bar" if scene == "free" else "chain of 4 bars" if scene == "chain4" else scene
        out.append([name, modes + (" each" if scene.startswith("chain") else ""), coordinates,
                    cell(by.get((scene, modes, "core_kept"))), cell(native.get((scene, modes, "core_kept")), False),
                    cell(by.get((scene, modes, "core_every_iteration"))),
                    cell(by.get((scene, modes, "dense_every_iteration"))),
                    cell(by.get((scene, modes, "core_kept_index3")))])
    return markdown(["scene", "n_m", "coordinates", "core, matrix kept", "same, -march=native (0.6.1)",
                     "core, rebuilt", "dense, rebuilt", "kept, index-3"], out, "lrrrrrrr")


@table("fbsim_bench", "fbsim_bench.csv")
def fbsim_bench():
    out = []
    for r in rows_of("fbsim_bench.csv"):
        out.append([r["scene"], r["modes"], f'{num(r["iterations_per_step"]):.2f}', sig(num(r["integrator_us_per_step"])),
                    sig(num(r["fbsim_us_per_step"])), pct(num(r["overhead"]), sign=False)])
    return markdown(["scene", "modes", "Newton iterations per step", "integrator [µs/step]", "fbsim [µs/step]",
                     "bookkeeping"], out, "lrrrrr")


@table("stiffening_cost", "stiffening_bench.csv")
def stiffening_cost():
    out = []
    for r in rows_of("stiffening_bench.csv"):
        out.append([r["formulation"].upper(), "on" if r["stiffening"] == "True" else "off", sig(num(r["us_per_step"])),
                    f'{num(r["iterations_per_step"]):.2f}', r["newton_matrices"], f'{num(r["ratio"]):.2f}'])
    return markdown(["formulation", "stiffening", "µs/step", "Newton iterations/step", "Newton matrices", "ratio"],
                    out, "llrrrr")


@table("stiffening_frequencies", "stiffening_frequencies.csv")
def stiffening_frequencies():
    """Flapwise frequency [rad/s] against the spin; each error against that run's rotating beam."""
    rows = rows_of("stiffening_frequencies.csv")
    by = {(r["formulation"], r["stiffening"], r["spin_over_omega1"]): r for r in rows}
    spins = sorted({r["spin_over_omega1"] for r in rows if num(r["spin_over_omega1"])}, key=float)

    def cell(r):
        f = num(r["frequency_rad_s"])
        return "diverges" if f is None else f'{f:.2f} ({pct(num(r["error"]))})'

    out = []
    for s in spins:
        ref = by[("gcms", "True", s)]
        out.append([f"{float(s):.1f}", cell(ref), cell(by[("ffrf", "True", s)]),
                    f'{num(ref["rotating_beam_rad_s"]):.2f}', f'{num(ref["southwell_rad_s"]):.2f}',
                    cell(by[("gcms", "False", s)]), cell(by[("ffrf", "False", s)])])
    return markdown(["Ω/ω₁", "GCMS stiffened", "FFRF (root frame) stiffened", "rotating beam", "Southwell",
                     "GCMS linear", "FFRF (root) linear"], out)


# --- the runtime: accuracy -----------------------------------------------------------------------------------------

@table("reduction_bench", "reduction_bench.csv")
def reduction_bench():
    rows = rows_of("reduction_bench.csv")
    full = next(r for r in rows if r["body"] == "full_order")
    out = []
    for r in rows:
        is_full = r is full
        ratio = num(full["us_per_step"]) / num(r["us_per_step"])
        out.append(["full order (reference)" if is_full else r["body"].replace("_", "-").replace("craig", "Craig")
                    .replace("bampton", "Bampton"), r["modes"] or "-", integer(num(r["coordinates"])),
                    sig(num(r["us_per_step"])), "1" if is_full else f"1/{ratio:,.0f}",
                    f'{num(r["iterations_per_step"]):.2f}',
                    "-" if is_full else sig(num(r["max_tip_error_relative"]), 2)])
    return markdown(["body", "modes", "coordinates", "µs per step", "cost / full order",
                     "Newton iterations per step", "tip error / deflection"], out, "lrrrrrr")


def convergence(main, index3):
    rows = rows_of(main)
    other = {(r["scene"], r["step_s"]): r for r in rows_of(index3)}
    out, last = [], None
    for r in rows:
        o = other.get((r["scene"], r["step_s"]))

        def err(row):
            e = None if row is None else num(row["error_m"])
            return "failed" if e is None else sci(e)

        def it(row):
            i = None if row is None else num(row["newton_iterations_per_step"])
            return "-" if i is None else f"{i:.2f}"

        order = num(r["order"])
        out.append(["" if r["scene"] == last else r["scene"], sci(num(r["step_s"]), 2), err(r),
                    "" if order is None else f"{order:.2f}", it(r), err(o), it(o)])
        last = r["scene"]
    return markdown(["scene", "h [s]", "error [m]", "order", "Newton iterations per step", "index 3: error [m]",
                     "iterations"], out)


@table("convergence_bench", "convergence_bench.csv", "convergence_bench_index3.csv")
def convergence_bench():
    return convergence("convergence_bench.csv", "convergence_bench_index3.csv")


@table("convergence_bench_rho1", "convergence_bench_rho1.csv", "convergence_bench_rho1_index3.csv")
def convergence_bench_rho1():
    return convergence("convergence_bench_rho1.csv", "convergence_bench_rho1_index3.csv")


# --- the improved GCMS against the FFRF ----------------------------------------------------------------------------

WORK_SCENES = ["pendulum", "slider-crank", "plate", "rotor"]
FORMULATIONS = {"gcms": "GCMS", "ffrf": "FFRF, mean axis", "ffrf_root": "FFRF, root frame"}


def work_rows(scene):
    return rows_of(f"work_precision_{scene}.csv")


def is_auto(row):
    """A run under error control (step: auto); its step_s is the mean step."""
    return (num(row.get("error_tolerance_m") or "0") or 0.0) > 0.0


def fixed_rows(scene):
    """The runs with fixed steps (and the full-order reference)."""
    return [r for r in work_rows(scene) if not is_auto(r)]


def work_precision(scene):
    """Tip error / travel and CPU s per simulated s, for each formulation, number of modes and step."""
    rows = fixed_rows(scene)
    runs = [r for r in rows if r["formulation"] != "full_order"]
    steps = sorted({r["step_s"] for r in runs}, key=float, reverse=True)
    by = {(r["formulation"], r["modes"], r["step_s"]): r for r in runs}
    out = []
    for formulation in [f for f in FORMULATIONS if any(r["formulation"] == f for r in runs)]:
        for modes in sorted({r["modes"] for r in runs if r["formulation"] == formulation}, key=int):
            cells = []
            for h in steps:
                r = by.get((formulation, modes, h))
                if r is None:
                    cells.append("-")
                elif r["failed"] != "0" or num(r["tip_error_relative"]) is None:
                    cells.append("failed")
                else:
                    cells.append(f'{sci(num(r["tip_error_relative"]), 2)} / {sig(num(r["cpu_s_per_simulated_s"]), 2)}')
            out.append([FORMULATIONS[formulation], modes] + cells)
    full = next(r for r in rows if r["formulation"] == "full_order")
    out.append([f'reference: full order, {full["coordinates"]} coordinates, h = {sci(num(full["step_s"]), 2)} s', "",
                f'own error {sci(num(full["tip_error_relative"]), 2)} / {sig(num(full["cpu_s_per_simulated_s"]), 3)}']
               + [""] * (len(steps) - 1))
    return markdown(["formulation", "modes"] + [f"h = {float(h) * 1e3:g} ms" for h in steps], out)


for _scene in WORK_SCENES:
    table(f"work_precision_{_scene.replace('-', '_')}", f"work_precision_{_scene}.csv")(
        lambda scene=_scene: work_precision(scene))


@table("work_precision_cost_ratio", *[f"work_precision_{s}.csv" for s in WORK_SCENES])
def work_precision_cost_ratio():
    """CPU time of the GCMS over the mean-axis FFRF's, at equal modes and step (runs that did not fail)."""
    out = []
    for scene in WORK_SCENES:
        by = {(r["formulation"], r["modes"], r["step_s"]): r for r in fixed_rows(scene)}
        ratios = []
        for (formulation, modes, h), r in by.items():
            other = by.get(("ffrf", modes, h))
            if formulation == "gcms" and other and r["failed"] == "0" and other["failed"] == "0":
                ratios.append((num(r["cpu_s_per_simulated_s"]) / num(other["cpu_s_per_simulated_s"]), modes, h))
        low, high = min(ratios), max(ratios)
        out.append([scene, len(ratios), f"{low[0]:.2f} ({low[1]} modes, h = {float(low[2]) * 1e3:g} ms)",
                    f"{statistics.median(r for r, _, _ in ratios):.2f}",
                    f"{high[0]:.1f} ({high[1]} modes, h = {float(high[2]) * 1e3:g} ms)"])
    return markdown(["scene", "pairs", "least", "median", "most"], out, "lrrrr")


def fixed_cost_at(rows, formulation, modes, error):
    """The CPU time per simulated second fixed steps need for a tip error (relative) of `error`, the steps it lies
    between [s], and whether it is only an upper bound: interpolated log-log between the two swept steps whose errors
    bracket it (or a swept step that reaches the error for less); the cheapest swept step that reaches it when the
    largest step already does (an upper bound: a larger step might too). None when no swept step is as accurate."""
    series = sorted(((float(r["step_s"]), num(r["tip_error_relative"]), num(r["cpu_s_per_simulated_s"]))
                     for r in rows if not is_auto(r) and r["formulation"] == formulation and r["modes"] == modes
                     and r["failed"] == "0"), reverse=True)
    reaching = [(c, h) for h, e, c in series if e <= error]
    if not reaching:
        return None
    cheapest = min(reaching)
    if series[0][1] <= error:
        return cheapest[0], (cheapest[1],), True
    for (h0, e0, c0), (h1, e1, c1) in zip(series, series[1:]):
        if e0 >= error >= e1 and e0 > e1:
            w = math.log(e0 / error) / math.log(e0 / e1)
            cost = math.exp((1 - w) * math.log(c0) + w * math.log(c1))
            return (cost, (h0, h1), False) if cost <= cheapest[0] else (cheapest[0], (cheapest[1],), False)
    return cheapest[0], (cheapest[1],), False


@table("work_precision_auto", *[f"work_precision_{s}.csv" for s in WORK_SCENES])
def work_precision_auto():
    """Each run under error control against fixed steps of the same formulation and modes at its tip error: the CPU
    time per simulated second they need (fixed_cost_at; ≤: at most, the sweep's largest step being more accurate)."""
    out = []
    for scene in WORK_SCENES:
        rows = work_rows(scene)
        for r in (r for r in rows if is_auto(r)):
            label = [scene, FORMULATIONS[r["formulation"]], r["modes"], sci(num(r["error_tolerance_m"]), 1)]
            if r["failed"] != "0":
                out.append(label + ["failed", "", "", ""])
                continue
            error, cpu = num(r["tip_error_relative"]), num(r["cpu_s_per_simulated_s"])
            fixed = fixed_cost_at(rows, r["formulation"], r["modes"], error)
            if fixed is None:
                where, ratio = "none as accurate", "-"
            else:
                cost, steps, bound = fixed
                between = " to ".join(f"{h * 1e3:g}" for h in steps)
                where = f"{'≤ ' if bound else ''}{sig(cost, 2)} (h = {between} ms)"
                ratio = f"{'≥ ' if bound else ''}{cpu / cost:.2f}"
            out.append(label + [f'{sig(num(r["step_s"]) * 1e3, 2)} ms, {r["steps"]} ({r["rejected_steps"]})',
                                f"{sci(error, 2)} / {sig(cpu, 2)}", where, ratio])
    return markdown(["scene", "formulation", "modes", "E [m]", "mean step, steps (again)", "error / CPU",
                     "fixed steps' CPU at that error", "ratio"], out, "lllrrrrr")


# --- many bodies ---------------------------------------------------------------------------------------------------

KINDS = ["rigid", "gcms", "ffrf"]


def scale_table(name, ladders=True):
    rows = [r for r in rows_of(name) if r["status"].startswith("ok")]
    chain = {(r["kind"], int(r["bodies"])): r for r in rows if r["scene"].startswith("chain")
             and not r["scene"].endswith("_probe")}
    sizes = sorted({n for _, n in chain})

    def cell(r):
        return "-" if r is None else f'{sig(num(r["us_per_step"]))} ({num(r["newton_per_step"]):.2f})'

    out = [[str(n)] + [cell(chain.get((k, n))) for k in KINDS] for n in sizes]
    fits = []
    for k in KINDS:
        points = [(n, num(chain[(k, n)]["us_per_step"])) for n in sizes if n >= 16 and (k, n) in chain]
        fits.append(f"N^{slope(points):.2f}" if len(points) >= 2 else "-")
    if any(f != "-" for f in fits):
        out.append(["fitted from 16"] + fits)
    out.append(["64 / (64 x 1)"] + [f'{num(chain[(k, 64)]["us_per_step"]) / (64 * num(chain[(k, 1)]["us_per_step"])):.2f}'
                                    if (k, 64) in chain and (k, 1) in chain else "-" for k in KINDS])
    if ladders:
        for scene, label in (("revolute", "ladder, revolute loops"), ("spherical", "ladder, spherical rungs")):
            found = {r["kind"]: r for r in rows if r["scene"].startswith("ladder") and r["scene"].endswith(scene)}
            if found:
                any_row = next(iter(found.values()))
                out.append([f'{label} ({any_row["bodies"]} bodies, {any_row["joints"]} joints)']
                           + [cell(found.get(k)) for k in KINDS])
    out.append([f"peak RSS [MB], N = {sizes[0]} / {sizes[-1]}"]
               + [f'{sig(num(chain[(k, sizes[0])]["peak_rss_mb"]))} / {sig(num(chain[(k, sizes[-1])]["peak_rss_mb"]))}'
                  if (k, sizes[0]) in chain and (k, sizes[-1]) in chain else "-" for k in KINDS])
    return markdown(["N", "rigid", "GCMS", "FFRF"], out)


@table("scale_bench", "scale_bench.csv")
def scale_bench():
    """fbsim µs per step (Newton iterations per step), chains of N brackets and the ladders."""
    return scale_table("scale_bench.csv")


@table("scale_bench_threads2", "scale_bench_threads2.csv")
def scale_bench_threads2():
    return scale_table("scale_bench_threads2.csv", ladders=False)


@table("scale_bench_steps200", "scale_bench_steps200.csv")
def scale_bench_steps200():
    """The same at equal simulated time: 200 steps (0.2 s) for every N, as issue 27 measured."""
    return scale_table("scale_bench_steps200.csv")


SOLVERS = [("klu", "KLU (COLAMD, no BTF)"), ("klu_amd_btf", "KLU default (BTF + AMD)"), ("klu_amd", "KLU, AMD alone"),
           ("sparselu", "Eigen SparseLU"), ("ldlt_quasidefinite", "SimplicialLDLT, quasi-definite"),
           ("klu_block_pattern_amd_btf", "KLU default on the blocks' dense pattern")]


@table("sparse_solver_bench", "sparse_solver_bench.csv")
def sparse_solver_bench():
    """The largest chains (ms); a rebuild of the Newton matrix is a refactorization for KLU."""
    rows = rows_of("sparse_solver_bench.csv")
    largest = max(int(r["bodies"]) for r in rows)
    by = {(r["kind"], int(r["bodies"]), r["solver"]): r for r in rows}
    out = []
    for kind in ("rigid", "gcms"):
        size = by[(kind, largest, "klu")]["size"]
        label = "rigid" if kind == "rigid" else "GCMS"
        lines = [("analyse", "analyse_us", 1e-3, lambda x: sig(x) + " ms"),
                 ("per Newton matrix", "refactor_us", 1e-3, lambda x: sig(x) + " ms"),
                 ("solve", "solve_us", 1e-3, lambda x: sig(x) + " ms"),
                 ("relative residual", "relative_residual", 1, lambda x: sci(x, 2)),
                 ("entries of the factors", "factor_nonzeros", 1, lambda x: sig(x, 3))]
        for i, (what, column, scale, show) in enumerate(lines):
            out.append([f"{label}: {what}", f"{int(size):,}" if i == 0 else ""]
                       + [show(num(by[(kind, largest, s)][column]) * scale) for s, _ in SOLVERS])
    for n in sorted({int(r["bodies"]) for r in rows}):
        if n != largest:
            out.append([f"rigid, {n} links: analyse", f'{int(by[("rigid", n, "klu")]["size"]):,}']
                       + [sig(num(by[("rigid", n, s)]["analyse_us"]) * 1e-3) + " ms" for s, _ in SOLVERS])
    return markdown([f"{largest} links", "rows"] + [label for _, label in SOLVERS], out)

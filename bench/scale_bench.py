#!/usr/bin/python3
"""fbsim's cost per step against the number of bodies N (issue 27, "Scenes of many bodies").

Makes the sample bracket's body file once (fbprep meshes/bracket.yaml --modes 6), then runs fbsim --json on chains
of N copies of it: body k's bore_1 is pinned to body k-1's bore_2 by a revolute joint about z, body 0's bore_1 to
ground; gravity -y, generalized-alpha (rho_inf 0.9, h = 1 ms); no outputs, monitors or ParaView series, so what is
timed is the solver. Three body kinds: `modes: rigid`, the improved GCMS with 6 modes (the default formulation) and
the FFRF with the same 6 modes (`formulation: ffrf`). Every scene starts exactly assembled: body k sits where its
bore_1 marker (the interface's y_row X̄_c, body frame, plus the centre of mass: what fbsim's interface marker uses)
coincides with body k-1's bore_2 marker. Plus one closed-loop scene per kind, a ladder of parallelogram four-bars
(99 bodies by default; see ladder_scene).

Per run: us_per_step and integrator_us_per_step from fbsim --json, and the peak RSS of that fbsim process alone
(os.wait4's rusage of the child). The cost is capped: each run's step count is chosen so that it takes about
--budget seconds (at least 20 steps, at most --max-steps; with --steps S exactly S, the same simulated time for every
N), predicted from the previous size's measured cost and the
growth seen so far (local exponent, never below --min-exponent: the dense solver grows like N^3); a size whose
predicted 20-step run exceeds --max-run seconds is skipped and recorded with that prediction. With --repeat R each
chain runs R times and the fastest run is kept: this virtual machine's neighbours only ever add time, and a short
one-body run varied by up to 60 % between runs.

Writes bench/results/scale_bench.csv and scale_bench.png (µs per step and peak memory against N, log-log, the growth
exponent fitted from N = 16 to the largest measured N in the legend) and prints a table. See bench/README.md.

    /usr/bin/python3 bench/scale_bench.py [--build build] [--work bench/results/work/scale] [--sizes 1 4 16 64 256 1024]
    /usr/bin/python3 bench/scale_bench.py --fbsim /path/to/older/fbsim --tag old     # time another build's fbsim
    /usr/bin/python3 bench/scale_bench.py --threads 2 --tag threads2                 # fbsim --threads 2
    /usr/bin/python3 bench/scale_bench.py --replot                                   # table and plot from the CSV
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from scale_scenes import KINDS, Bracket, chain_scene, ladder_scene, vec  # the scenes, beside this script

REPO = Path(__file__).resolve().parent.parent
MIN_STEPS = 20
MAX_REPEATS = 40  # runs of one chain at most with --steps (fastest_run)
STYLE = {"rigid": ("tab:gray", "o"), "gcms": ("tab:blue", "s"), "ffrf": ("tab:red", "^")}
FIELDS = ["kind", "scene", "bodies", "joints", "steps", "us_per_step", "integrator_us_per_step", "peak_rss_mb",
          "status",
          "newton_per_step", "run_wall_s", "setup_s", "predicted_s", "others_cores", "warnings",
          "fbsim", "threads"]


# ------------------------------------------------------------------------------------------------------- running --

def cpu_busy_seconds():
    """CPU time the whole machine has spent busy (all cores: user, nice, system, irq, softirq, steal) [s]."""
    with open("/proc/stat") as f:
        ticks = [int(x) for x in f.readline().split()[1:]]
    return sum(ticks[i] for i in (0, 1, 2, 5, 6, 7) if i < len(ticks)) / os.sysconf("SC_CLK_TCK")


def wait_idle(longest, threshold=0.3):
    """Waits (up to `longest` s) until the other processes use less than `threshold` cores over a second: fbsim's
    OpenMP threads slow down many times when they share the cores. Returns the seconds waited."""
    start = time.monotonic()
    while True:
        b0, t0 = cpu_busy_seconds(), time.monotonic()
        time.sleep(1.0)
        if (cpu_busy_seconds() - b0) / (time.monotonic() - t0) < threshold or time.monotonic() - start > longest:
            return time.monotonic() - start


def run_fbsim(fbsim, scene, out, timeout, threads=1):
    """Runs fbsim --json on `scene`; returns (summary or None, exit code, stderr, wall s, the child's own peak RSS MB,
    the cores other processes kept busy meanwhile on average).

    os.wait4 reports the rusage of that one child (ru_maxrss in KiB on Linux), unlike RUSAGE_CHILDREN, which is
    the largest over every child this script has waited for. The others' share is the machine's busy CPU time less
    the child's own (utime + stime), over the run's wall time."""
    stdout_path, stderr_path = scene.with_suffix(".stdout"), scene.with_suffix(".stderr")
    busy = cpu_busy_seconds()
    start = time.monotonic()
    with open(stdout_path, "w") as so, open(stderr_path, "w") as se:
        p = subprocess.Popen([str(fbsim), str(scene), "-o", str(out), "--json", "--threads", str(threads)],
                             stdout=so, stderr=se)
        killed = False
        while True:
            pid, status, usage = os.wait4(p.pid, os.WNOHANG)
            if pid == p.pid:
                break
            if not killed and time.monotonic() - start > timeout:
                p.kill()  # not reaped yet: the pid is still ours
                killed = True
            time.sleep(0.05)
        p.returncode = os.waitstatus_to_exitcode(status)  # reaped here; keep Popen from waiting again
    wall = time.monotonic() - start
    others = max(0.0, cpu_busy_seconds() - busy - usage.ru_utime - usage.ru_stime) / max(wall, 1e-9)
    text = stdout_path.read_text().strip()
    err = stderr_path.read_text().strip()
    summary = None
    if p.returncode == 0 and text:
        summary = json.loads(text.splitlines()[-1])
    if killed:  # the reason first; the last line of stderr may be a warning
        err = f"killed after {timeout:.0f} s (its time limit)" + \
              "".join(f"; {line}" for line in err.splitlines() if "warning" in line)[:300]
    return summary, p.returncode, err, wall, usage.ru_maxrss / 1024.0, others


def local_exponent(history, column=1):
    """d log(value) / d log(N) between the last two measured sizes (None with fewer)."""
    if len(history) < 2:
        return None
    (n0, c0), (n1, c1) = (history[-2][0], history[-2][column]), (history[-1][0], history[-1][column])
    return math.log(c1 / c0) / math.log(n1 / n0) if n1 != n0 and c0 > 0 and c1 > 0 else None


def predict(history, n, min_exponent):
    """(µs per step, setup s) at N = n from the measured (N, µs per step, setup s) so far: the last measured size's
    cost grown by the larger of the last local exponent and min_exponent; its setup (reading N body files, assembling,
    the initial solve: about linear in N at these sizes) by the larger of its last local exponent and 1."""
    n0, c0, s0 = history[-1]
    ratio = max(1.0, n / n0)
    e = local_exponent(history)
    e_setup = local_exponent(history, 2)
    e = min_exponent if e is None else max(e, min_exponent)
    e_setup = 1.0 if e_setup is None else max(e_setup, 1.0)
    return c0 * ratio ** e, max(s0, 0.05) * ratio ** e_setup


def steps_for(cost_us, setup_s, budget, max_steps):
    steps = int((budget - setup_s) / (cost_us * 1e-6)) if budget > setup_s else 0
    return max(MIN_STEPS, min(max_steps, steps))


def fit_exponent(points, smallest=16):
    """Least-squares slope of log(µs per step) against log(N) over the measured N >= smallest (None below 2 points)."""
    pts = [(n, c) for n, c in points if n >= smallest and c > 0]
    if len(pts) < 2:
        return None, None
    x = np.log([n for n, _ in pts])
    y = np.log([c for _, c in pts])
    return float(np.polyfit(x, y, 1)[0]), (pts[0][0], pts[-1][0])


def one_run(args, kind, name, text_of, n_bodies, steps, timeout):
    """Writes the scene with `steps` steps and runs it; returns the CSV row."""
    scenes = Path(args.work) / "scenes"
    scenes.mkdir(parents=True, exist_ok=True)
    text, bodies, joints = text_of(steps)
    scene = scenes / f"{kind}_{name}.yaml"
    scene.write_text(text)
    wait_idle(args.wait_idle)  # other work on the machine disturbs the timings: `others` records how much
    out = Path(args.work) / "out" / f"{kind}_{name}"
    summary, code, err, wall, rss, others = run_fbsim(args.fbsim, scene, out, timeout, args.threads)
    row = dict(kind=kind, scene=name, bodies=bodies, joints=joints, steps=steps, us_per_step="",
               integrator_us_per_step="", peak_rss_mb=f"{rss:.1f}", status="ok", newton_per_step="",
               run_wall_s=f"{wall:.2f}", setup_s="", predicted_s="", others_cores=f"{others:.2f}", warnings="",
               fbsim=args.label, threads=args.threads)
    if summary is None:
        errors = [line for line in err.splitlines() if not line.startswith("fbsim: warning:")]
        last = errors[-1] if errors else err.splitlines()[-1] if err else f"exit code {code}"
        row["status"] = ("refused: " if code == 2 else "failed: ") + last.replace("fbsim: error: ", "")
        return row, None
    if summary["steps"] != steps:
        row["status"] = f"ok ({summary['steps']} steps run, {steps} asked)"
    row["steps"] = summary["steps"]
    row["us_per_step"] = f"{summary['us_per_step']:.1f}"
    if "integrator_us_per_step" in summary:
        row["integrator_us_per_step"] = f"{summary['integrator_us_per_step']:.1f}"
    row["newton_per_step"] = f"{summary['newton_iterations'] / max(1, summary['steps']):.2f}"
    row["setup_s"] = f"{max(0.0, wall - summary['wall_s']):.2f}"
    row["warnings"] = " | ".join(summary.get("warnings", []))  # e.g. Newton falling back to a costlier step
    return row, summary


def print_row(row):
    print(f"{row['kind']:6s} {row['scene']:22s} {row['bodies']:>5} {row['joints']:>5} {row['steps']:>6} "
          f"{row['us_per_step']:>12} {row['integrator_us_per_step']:>12} {row['peak_rss_mb']:>8} "
          f"{row['newton_per_step']:>6} {row['run_wall_s']:>8} {row['predicted_s']:>8} "
          f"{row.get('others_cores', ''):>6}  {row['status']}"
          + (f"; warning: {row['warnings'][:110]}" if row.get("warnings") else ""), flush=True)


def header():
    print(f"{'kind':6s} {'scene':22s} {'N':>5s} {'joint':>5s} {'steps':>6s} {'us/step':>12s} {'integr. us':>12s} "
          f"{'RSS MB':>8s} {'newton':>6s} {'wall s':>8s} {'pred. s':>8s} {'others':>6s}  status", flush=True)


def skipped_row(args, kind, name, bodies, joints, shortest):
    return dict(kind=kind, scene=name, bodies=bodies, joints=joints, steps="", us_per_step="",
                integrator_us_per_step="", peak_rss_mb="",
                status=f"skipped: {MIN_STEPS} steps predicted {shortest:.0f} s > --max-run {args.max_run:g}",
                newton_per_step="", run_wall_s="", setup_s="", predicted_s=f"{shortest:.0f}", others_cores="",
                warnings="", fbsim=args.label, threads=args.threads)


def ladder_runs(args, kind, body_file, bracket, history):
    """The ladder with revolute loops (which fbsim may refuse as redundant), then with spherical rungs. Its cost per
    step does not follow from the chains' (the loops' Newton matrices differ), so each is probed with 20 steps first
    (when the chains' growth, times 4/3 for the joints, predicts that to fit in --max-run) and then, if the budget
    allows more steps, run with as many as fit."""
    rows = []
    links = args.ladder_links
    n = 3 * links
    for closing in ("revolute", "spherical"):
        name = f"ladder{n}_{closing}"
        text_of = lambda steps, closing=closing: ladder_scene(body_file, bracket, kind, links, steps, closing)
        _, bodies, joints = text_of(MIN_STEPS)
        if history:
            below = [h for h in history if h[0] <= n]
            cost, setup = predict(below or history[:1], n, args.min_exponent)
            cost *= 4.0 / 3.0  # 4/3 joints per body, against the chain's one
            shortest = setup + MIN_STEPS * cost * 1e-6
            if shortest > args.max_run:
                row = skipped_row(args, kind, name, bodies, joints, shortest)
                rows.append(row)
                print_row(row)
                continue
        probe, summary = one_run(args, kind, name, text_of, n, MIN_STEPS, 4 * args.max_run)
        done = [probe]
        if summary is not None:
            steps = args.steps or steps_for(summary["us_per_step"], float(probe["setup_s"]), args.budget, args.max_steps)
            if steps > MIN_STEPS:
                predicted = float(probe["setup_s"]) + steps * summary["us_per_step"] * 1e-6
                # Killed at 4 times its prediction (at least 2 budgets): Newton may fall back to a much costlier
                # step later in the run; the probe's figures stay then.
                row, full = one_run(args, kind, name, text_of, n, steps, max(2 * args.budget, 4 * predicted))
                row["predicted_s"] = f"{predicted:.1f}"
                if full is None:
                    probe["status"] = f"ok ({MIN_STEPS}-step probe; the {steps}-step run failed, next row)"
                    done.append(row)
                else:
                    done = [row]
        for row in done:
            rows.append(row)
            print_row(row)
    return rows


def fastest_run(args, kind, name, text_of, n_bodies, steps, timeout):
    """one_run --repeat times; the row of the fastest (the first failure ends the repeats)."""
    def cost(summary):
        return summary.get("integrator_us_per_step", summary["us_per_step"])

    best = None
    runs, timed = 0, 0.0
    # With --steps a one-body run is a few milliseconds of stepping: it repeats until a second of it is timed (at most
    # MAX_REPEATS runs), so that the fastest run is not one the machine's neighbours happened to spare.
    while runs < max(1, args.repeat) or (args.steps and timed < 1.0 and runs < MAX_REPEATS):
        row, summary = one_run(args, kind, name, text_of, n_bodies, steps, timeout)
        runs += 1
        if summary is None:
            return row, summary
        timed += steps * cost(summary) * 1e-6
        if best is None or cost(summary) < cost(best[1]):
            best = (row, summary)
    return best


def measure(args):
    work = Path(args.work).resolve()
    work.mkdir(parents=True, exist_ok=True)
    args.work = str(work)
    body_file = work / "bracket.fbh5"
    if args.body:
        body_file = Path(args.body).resolve()
    else:
        subprocess.run([str(args.fbprep), str(REPO / "meshes/bracket.yaml"), "-o", str(body_file), "--modes", "6",
                        "--order", "1", "--quiet"], check=True)  # as its recorded results (quadratic from 0.13)
    bracket = Bracket(body_file)
    d = bracket.point("bore_2") - bracket.point("bore_1")
    print(f"body file {body_file}: bore_1 -> bore_2 = {vec(d)} m (input frame)")
    rows = []
    header()
    for kind in args.kinds:
        history = []  # (N, µs per step, setup s) of the measured chains
        for n in sorted(args.sizes):
            name = f"chain{n}"
            text_of = lambda steps, n=n, kind=kind: chain_scene(body_file, bracket, kind, n, steps)
            if history:
                cost, setup = predict(history, n, args.min_exponent)
                shortest = setup + MIN_STEPS * cost * 1e-6
                if shortest > args.max_run:
                    row = skipped_row(args, kind, name, n, n, shortest)
                    rows.append(row)
                    print_row(row)
                    continue
                steps = args.steps or steps_for(cost, setup, args.budget, args.max_steps)
                predicted = setup + steps * cost * 1e-6
            else:  # the smallest size: a 20-step probe for its cost, then the budgeted run
                probe, summary = one_run(args, kind, name + "_probe", text_of, n, MIN_STEPS, args.max_run * 4)
                if summary is None:
                    rows.append(probe)
                    print_row(probe)
                    continue
                cost = summary["us_per_step"]
                setup = float(probe["setup_s"])
                steps = args.steps or steps_for(cost, setup, args.budget, args.max_steps)
                predicted = setup + steps * cost * 1e-6
            row, summary = fastest_run(args, kind, name, text_of, n, steps, max(4 * args.max_run, 4 * predicted))
            row["predicted_s"] = f"{predicted:.1f}"
            rows.append(row)
            print_row(row)
            if summary is not None:
                history.append((n, summary["us_per_step"], float(row["setup_s"])))
        if args.ladder_links > 0:
            rows += ladder_runs(args, kind, body_file, bracket, history)
    return rows


# ------------------------------------------------------------------------------------------------ table and plot --

def as_float(text):
    try:
        return float(text)
    except (TypeError, ValueError):
        return None


def chain_points(rows, kind, key="us_per_step"):
    pts = []
    for r in rows:
        if r["kind"] == kind and r["scene"].startswith("chain") and not r["scene"].endswith("_probe"):
            v = as_float(r[key])
            if v is not None and r["status"].startswith("ok"):
                pts.append((int(r["bodies"]), v))
    return sorted(pts)


def exponents(rows, kinds):
    out = {}
    for kind in kinds:
        e, span = fit_exponent(chain_points(rows, kind))
        m, _ = fit_exponent(chain_points(rows, kind, "peak_rss_mb"))
        out[kind] = (e, span, m)
    return out


def report(rows, csv_path, png_path, title):
    kinds = [k for k in KINDS if any(r["kind"] == k for r in rows)]
    fits = exponents(rows, kinds)
    print("\ngrowth of the cost per step, fitted from N = 16 to the largest measured N:")
    for kind in kinds:
        e, span, m = fits[kind]
        if e is None:
            print(f"  {kind:6s} n/a (fewer than two measured sizes >= 16)")
        else:
            print(f"  {kind:6s} us/step ~ N^{e:.2f} (N = {span[0]}..{span[1]}); peak RSS ~ N^{m:.2f}")
    # The targets: 64 bodies at most 1.5 x 64 x one body's step; 1024 rigid links at most 10 ms per step.
    print("64 bodies against 64 single bodies (target 1.5), and the cost at 1024:")
    for kind in kinds:
        pts = dict(chain_points(rows, kind))
        ratio = f"{pts[64] / (64 * pts[1]):.2f}" if 1 in pts and 64 in pts else "n/a"
        largest = f"{pts[1024] / 1000:.1f} ms" if 1024 in pts else "n/a"
        print(f"  {kind:6s} 64 / (64 x 1): {ratio}; N = 1024: {largest} per step")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(12, 4.8))
    for kind in kinds:
        color, marker = STYLE[kind]
        e, span, _ = fits[kind]
        pts = chain_points(rows, kind)
        label = f"{kind} chain" + (f": N^{e:.2f} ({span[0]}..{span[1]})" if e is not None else "")
        if pts:
            ax_t.loglog(*zip(*pts), marker=marker, color=color, label=label)
        skipped = [(int(r["bodies"]), 1e6 * float(r["predicted_s"]) / MIN_STEPS) for r in rows
                   if r["kind"] == kind and r["status"].startswith("skipped") and r["scene"].startswith("chain")]
        if pts and skipped:
            ax_t.loglog([pts[-1][0]] + [n for n, _ in skipped], [pts[-1][1]] + [c for _, c in skipped], ls=":",
                        marker=marker, mfc="none", color=color)
        for closing, star in (("revolute", "*"), ("spherical", "P")):
            ladder = [(int(r["bodies"]), float(r["us_per_step"]), float(r["peak_rss_mb"])) for r in rows
                      if r["kind"] == kind and r["scene"].startswith("ladder") and r["scene"].endswith(closing)
                      and r["status"].startswith("ok")]
            if ladder:
                n, cost, mem = zip(*ladder)
                label = f"{kind} ladder, {'revolute loops' if closing == 'revolute' else 'spherical rungs'}"
                ax_t.loglog(n, cost, ls="none", marker=star, ms=11, color=color, label=label)
                ax_m.loglog(n, mem, ls="none", marker=star, ms=11, color=color)
        mem = chain_points(rows, kind, "peak_rss_mb")
        if mem:
            ax_m.loglog(*zip(*mem), marker=marker, color=color, label=f"{kind} chain")
    ax_t.set_xlabel("bodies N")
    ax_t.set_ylabel("fbsim wall time per step [µs]")
    ax_t.set_title("cost per step (open markers: predicted, skipped)", fontsize=10)
    ax_t.grid(True, which="both", alpha=0.3)
    ax_t.legend(fontsize=8)
    ax_m.set_xlabel("bodies N")
    ax_m.set_ylabel("peak RSS of fbsim [MB]")
    ax_m.set_title("peak memory (* and +: the ladders)", fontsize=10)
    ax_m.grid(True, which="both", alpha=0.3)
    ax_m.legend(fontsize=8)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(png_path, dpi=120)
    print("wrote", csv_path, "and", png_path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--fbsim", help="the fbsim to time (default: <build>/bin/fbsim)")
    parser.add_argument("--fbprep", help="the fbprep that makes the body file (default: <build>/bin/fbprep)")
    parser.add_argument("--body", help="an existing bracket body file to use instead of making one")
    parser.add_argument("--work", default=str(REPO / "bench/results/work/scale"))
    parser.add_argument("--sizes", type=int, nargs="+", default=[1, 4, 16, 64, 256, 1024])
    parser.add_argument("--kinds", nargs="+", choices=list(KINDS), default=list(KINDS))
    parser.add_argument("--budget", type=float, default=60.0, help="wall seconds a run should take at most (about)")
    parser.add_argument("--repeat", type=int, default=1, help="runs per chain; the fastest is kept")
    parser.add_argument("--max-run", type=float, default=600.0,
                        help="skip a size whose predicted 20-step run takes longer [s]")
    parser.add_argument("--max-steps", type=int, default=10000, help="the most steps a run takes (small N)")
    parser.add_argument("--steps", type=int, default=0,
                        help="every run takes exactly this many steps (the same simulated time, steps x 1 ms, for "
                             "every N; issue 27 measured 200) instead of as many as --budget allows")
    parser.add_argument("--min-exponent", type=float, default=3.0,
                        help="the least growth exponent the prediction assumes (the dense solver's N^3)")
    parser.add_argument("--ladder-links", type=int, default=33,
                        help="rail links of the ladder scene (3 links bodies; 0: no ladder)")
    parser.add_argument("--wait-idle", type=float, default=120.0,
                        help="before each run, wait up to this long [s] for other processes to leave the cores idle")
    parser.add_argument("--threads", type=int, default=1, help="fbsim --threads (1: fbsim's default)")
    parser.add_argument("--tag", default="", help="suffix of the output names: scale_bench_<tag>.csv/.png")
    parser.add_argument("--replot", action="store_true", help="table and plot from the CSV, no runs")
    args = parser.parse_args()
    args.fbsim = Path(args.fbsim or Path(args.build) / "bin/fbsim").resolve()
    if not args.replot:  # the CSV names the binary and its build time: the same bench times older and newer builds
        built = time.strftime("%Y-%m-%d %H:%M", time.localtime(args.fbsim.stat().st_mtime))
        args.label = f"{args.fbsim} (built {built})"
    args.fbprep = Path(args.fbprep or Path(args.build) / "bin/fbprep").resolve()
    stem = "scale_bench" + (f"_{args.tag}" if args.tag else "")
    csv_path = REPO / "bench/results" / f"{stem}.csv"
    png_path = REPO / "bench/results" / f"{stem}.png"
    if args.replot:
        with open(csv_path, newline="") as f:
            rows = list(csv.DictReader(f))
        header()
        for row in rows:
            print_row(row)
    else:
        started = time.monotonic()
        rows = measure(args)
        with open(csv_path, "w", newline="") as f:
            writer = csv.DictWriter(f, fieldnames=FIELDS)
            writer.writeheader()
            writer.writerows(rows)
        print(f"measured in {time.monotonic() - started:.0f} s")
    fbsim = rows[0]["fbsim"] if rows else ""
    report(rows, csv_path, png_path, f"fbsim cost per step against bodies: chains of brackets (h = 1 ms), {fbsim}")


if __name__ == "__main__":
    sys.exit(main())

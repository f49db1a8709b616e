#!/usr/bin/python3
"""Work-precision diagrams of the improved GCMS and the FFRF on scenes with large rotations, with fixed steps and
under error control (step: auto).

Runs build/bin/work_precision_bench for each scene (or re-reads its CSV with --replot), then writes
bench/results/work_precision_<scene>.csv, work_precision_<scene>.png (error against CPU time per simulated second,
log-log, both formulations; error control's runs dashed), work_precision.png (the headline: every scene's tip error)
and work_precision.md (the tables, stamped with the machine and the commit).

    /usr/bin/python3 bench/work_precision.py                # every scene, ~12 min on 2 cores
    /usr/bin/python3 bench/work_precision.py --quick        # 2 modes x 2 steps per formulation, a smoke run
    /usr/bin/python3 bench/work_precision.py --scenes plate --replot
"""
import argparse
import csv
import datetime
import os
import platform
import subprocess
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

SCENES = ["pendulum", "slider-crank", "plate", "rotor"]
TITLES = {
    "pendulum": "flexible pendulum (Craig-Bampton, rbe2 root pinned), 0.5 s",
    "slider-crank": "slider-crank, flexible rod (Craig-Bampton, both ends), crank spun up, 1 s",
    "plate": "free plate flipping about its intermediate axis, 1 s",
    "rotor": "blade spun up to 94 rad/s by a driven hub, 0.75 s",
}
STYLE = {
    "gcms": ("improved GCMS", "tab:blue", "o"),
    "ffrf": ("FFRF, mean-axis frame", "tab:red", "s"),
    "ffrf_root": ("FFRF, root frame", "tab:orange", "^"),
}
QUANTITIES = [("tip_error_relative", "tip path error / travel"),
              ("reaction_error_relative", "joint reaction error / largest")]


def machine():
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    return f"{model}, {os.cpu_count()} cores, {platform.system()} {platform.release()}"


def commit(root):
    try:
        head = subprocess.run(["git", "-C", root, "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
        # The results this script is writing do not make the code dirty.
        dirty = subprocess.run(["git", "-C", root, "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":(exclude)bench/results"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + ("+changes" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def read(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def is_auto(row):
    """A run under error control (its step_s is the mean step)."""
    return float(row.get("error_tolerance_m") or 0) > 0


def pareto(points):
    """The points no other point beats in both cost and error, by increasing cost."""
    front, best = [], float("inf")
    for cost, error in sorted(points):
        if error < best:
            front.append((cost, error))
            best = error
    return front


def plot_scene(ax, rows, column, label, floor=None):
    if floor:
        ax.axhline(floor, color="0.4", linestyle="--", linewidth=1, label="the reference's own error")
    for formulation, (name, colour, marker) in STYLE.items():
        mine = [r for r in rows if r["formulation"] == formulation and r["failed"] == "0" and float(r[column]) > 0]
        fixed = [r for r in mine if not is_auto(r)]
        if not fixed:
            continue
        for modes in sorted({int(r["modes"]) for r in fixed}):
            series = sorted((float(r["cpu_s_per_simulated_s"]), float(r[column])) for r in fixed if int(r["modes"]) == modes)
            ax.plot(*zip(*series), color=colour, marker=marker, markersize=2 + modes ** 0.5, linewidth=0.6, alpha=0.45)
        front = pareto([(float(r["cpu_s_per_simulated_s"]), float(r[column])) for r in fixed])
        ax.plot(*zip(*front), color=colour, linewidth=2.2, label=name + " (best of the sweep)")
        controlled = sorted((float(r["cpu_s_per_simulated_s"]), float(r[column]), int(r["modes"])) for r in mine if is_auto(r))
        if controlled:
            ax.plot([c for c, _, _ in controlled], [e for _, e, _ in controlled], color=colour, linestyle="--",
                    marker="D", markerfacecolor="white", markersize=5, linewidth=1.4,
                    label=f"{name}, step: auto ({controlled[0][2]} modes)")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("CPU time per simulated second [s]")
    ax.set_ylabel(label)
    ax.grid(True, which="both", alpha=0.3)


def table(rows):
    out = ["| formulation | modes | coordinates | step [s] | error tolerance [m] | steps (again) | CPU s / sim. s | "
           "iterations / step | tip error [m] | tip error / travel | joint reaction error |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        failed = r["failed"] == "1"
        auto = is_auto(r)
        out.append("| {} | {} | {} | {} | {} | {} | {:.4g} | {:.2f} | {} | {} | {} |".format(
            r["formulation"], r["modes"] or "-", r["coordinates"],
            "{:.4g}{}".format(float(r["step_s"]), " (mean)" if auto else ""),
            "{:g}".format(float(r["error_tolerance_m"])) if auto else "-",
            "{} ({})".format(r["steps"], r["rejected_steps"]) if auto else r.get("steps", "-"),
            float(r["cpu_s_per_simulated_s"]), float(r["iterations_per_step"]),
            "failed" if failed else "{:.3g}".format(float(r["tip_error_m"])),
            "failed" if failed else "{:.3g}".format(float(r["tip_error_relative"])),
            "failed" if failed else "{:.3g}".format(float(r["reaction_error_relative"]))))
    return "\n".join(out)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--bench", default=os.path.join(root, "build", "bin", "work_precision_bench"))
    parser.add_argument("--out", default=os.path.join(root, "bench", "results"))
    parser.add_argument("--scenes", default=",".join(SCENES))
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--replot", action="store_true", help="no runs: tables and plots from the CSV files")
    args = parser.parse_args()
    scenes = [s for s in args.scenes.split(",") if s]
    os.makedirs(args.out, exist_ok=True)
    seconds = {}
    for scene in scenes:
        path = os.path.join(args.out, f"work_precision_{scene}.csv")
        if not args.replot:
            start = time.time()
            command = [args.bench, scene, path] + (["--quick"] if args.quick else [])
            print("running", " ".join(command), flush=True)
            if subprocess.run(command).returncode != 0:
                sys.exit(f"work_precision.py: {scene} failed")
            seconds[scene] = time.time() - start
    results = {scene: read(os.path.join(args.out, f"work_precision_{scene}.csv")) for scene in scenes}

    for scene, rows in results.items():
        reduced = [r for r in rows if r["formulation"] != "full_order"]
        reference = next(r for r in rows if r["formulation"] == "full_order")
        has_reaction = any(float(r["reaction_error_relative"]) > 0 for r in reduced)
        panels = QUANTITIES if has_reaction else QUANTITIES[:1]
        fig, axes = plt.subplots(1, len(panels), figsize=(6.2 * len(panels), 4.6), squeeze=False)
        for ax, (column, label) in zip(axes[0], panels):
            plot_scene(ax, reduced, column, label, float(reference[column]))
        axes[0][0].legend(fontsize=8)
        fig.suptitle(f"{scene}: {TITLES.get(scene, scene)}\n(thin lines: one number of modes, steps halved along "
                     "the line; marker size grows with the modes)", fontsize=9)
        fig.tight_layout()
        fig.savefig(os.path.join(args.out, f"work_precision_{scene}.png"), dpi=130)
        plt.close(fig)

    fig, axes = plt.subplots(1, len(results), figsize=(6.0 * len(results), 4.6), squeeze=False)
    for ax, (scene, rows) in zip(axes[0], results.items()):
        reference = next(r for r in rows if r["formulation"] == "full_order")
        plot_scene(ax, [r for r in rows if r["formulation"] != "full_order"], "tip_error_relative",
                   "tip path error / travel", float(reference["tip_error_relative"]))
        ax.set_title(TITLES.get(scene, scene), fontsize=9)
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(args.out, "work_precision.png"), dpi=130)
    plt.close(fig)

    # The stamp of the runs: written when they run, read back by --replot (a replot measures nothing).
    stamp_file = os.path.join(args.out, "work_precision_stamp.txt")
    if args.replot and os.path.exists(stamp_file):
        with open(stamp_file) as f:
            stamp = f.read().strip()
    else:
        stamp = "{} on {}, commit {}".format(datetime.datetime.now().strftime("%Y-%m-%d %H:%M"), machine(), commit(root))
        if not args.replot:
            with open(stamp_file, "w") as f:
                f.write(stamp + "\n")
    lines = ["# Work-precision of the improved GCMS and the FFRF (bench/work_precision.py)", "", f"Measured {stamp}.", ""]
    for scene, rows in results.items():
        reference = next(r for r in rows if r["formulation"] == "full_order")
        lines += [f"## {scene}: {TITLES.get(scene, scene)}", "",
                  "Reference: the unreduced improved ACF of the same mesh, {} coordinates, h = {:.4g} s ({:.4g} s CPU per "
                  "simulated second); its own error, |x(2h) − x(h)|/3: {:.3g} m at the tip ({:.3g} of the travel), {:.3g} "
                  "of the largest joint reaction.{}".format(
                      reference["coordinates"], float(reference["step_s"]), float(reference["cpu_s_per_simulated_s"]),
                      float(reference["tip_error_m"]), float(reference["tip_error_relative"]),
                      float(reference["reaction_error_relative"]),
                      f" This scene took {seconds[scene]:.0f} s." if scene in seconds else ""),
                  "", table([r for r in rows if r["formulation"] != "full_order"]), ""]
    with open(os.path.join(args.out, "work_precision.md"), "w") as f:
        f.write("\n".join(lines))
    print("wrote", os.path.join(args.out, "work_precision.md"))


if __name__ == "__main__":
    main()

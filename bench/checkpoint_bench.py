#!/usr/bin/python3
"""What a checkpoint costs (issue 32): fbsim on chains of N sample brackets (bench/scale_scenes.py), once without
checkpoints and once with `checkpoint: {interval: 1.0e-9}` (a checkpoint after every step, and one at the end), S
steps each; the difference of the two runs' wall times over the S + 1 checkpoints is one checkpoint's cost, and the
checkpoint file's size is its size. Each pair runs R times and the fastest of each is kept (this machine's neighbours
only ever add time).

Writes bench/results/checkpoint_bench.csv and checkpoint_bench.png (ms and MB per checkpoint against N) and prints
the table. See bench/README.md.

    /usr/bin/python3 bench/checkpoint_bench.py [--build build] [--body build/bracket.fbh5] [--steps 40] [--repeat 3]
    /usr/bin/python3 bench/checkpoint_bench.py --replot
"""
import argparse
import csv
import subprocess
import sys
import time
from pathlib import Path

from scale_scenes import Bracket, chain_scene  # the scenes, beside this script

REPO = Path(__file__).resolve().parent.parent
CASES = [("rigid", 1), ("rigid", 64), ("rigid", 1024), ("gcms", 1), ("gcms", 64), ("ffrf", 64)]


def timed_run(fbsim, scene, out):
    """fbsim -q on `scene` into `out`: its wall time [s]; exits on a failed run."""
    start = time.monotonic()
    run = subprocess.run([str(fbsim), str(scene), "-o", str(out), "-q"], capture_output=True, text=True)
    wall = time.monotonic() - start
    if run.returncode != 0:
        sys.exit(f"{scene}: fbsim failed ({run.returncode}): {run.stderr.strip()}")
    return wall


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--body", default=None, help="the bracket body file (default: BUILD/bracket.fbh5, made if missing)")
    parser.add_argument("--work", default=str(REPO / "bench" / "results" / "work" / "checkpoint"))
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--replot", action="store_true", help="the plot from the CSV, without running")
    args = parser.parse_args()
    results = REPO / "bench" / "results"
    if args.replot:
        with open(results / "checkpoint_bench.csv") as f:
            plot([{k: (v if k == "kind" else float(v)) for k, v in row.items()} for row in csv.DictReader(f)], results)
        return
    build, work = Path(args.build), Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    body = Path(args.body) if args.body else build / "bracket.fbh5"
    if not body.exists():
        subprocess.run([str(build / "bin" / "fbprep"), str(REPO / "meshes" / "bracket.yaml"), "-o", str(body), "-q"],
                       check=True)
    bracket = Bracket(body)
    rows = []
    for kind, n in CASES:
        text, _, _ = chain_scene(str(body.resolve()), bracket, kind, n, args.steps)
        plain, with_checkpoints = work / f"{kind}{n}.yaml", work / f"{kind}{n}_checkpoints.yaml"
        plain.write_text(text)
        with_checkpoints.write_text(text + "checkpoint: {interval: 1.0e-9}\n")
        fbsim = build / "bin" / "fbsim"
        without = min(timed_run(fbsim, plain, work / "out") for _ in range(args.repeat))
        with_ = min(timed_run(fbsim, with_checkpoints, work / "out_checkpoints") for _ in range(args.repeat))
        size = (work / "out_checkpoints" / "checkpoint.h5").stat().st_size
        rows.append({"kind": kind, "bodies": n, "steps": args.steps, "wall_s": round(without, 4),
                     "wall_with_checkpoints_s": round(with_, 4),
                     "ms_per_checkpoint": round(1e3 * max(with_ - without, 0.0) / (args.steps + 1), 3),
                     "checkpoint_mb": round(size / 1e6, 4)})
        r = rows[-1]
        print(f"{kind:6s} {n:5d} bodies: {r['ms_per_checkpoint']:8.2f} ms, {r['checkpoint_mb']:7.3f} MB per checkpoint "
              f"(runs of {args.steps} steps: {without:.2f} s, {with_:.2f} s with a checkpoint a step)")
    with open(results / "checkpoint_bench.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, results)


def plot(rows, results):
    """checkpoint_bench.png: ms and MB per checkpoint against N (a time within the runs' noise, 0, left out)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, 2, figsize=(9, 3.6))
    for kind, style in (("rigid", "o-"), ("gcms", "s-"), ("ffrf", "^")):
        mine = [r for r in rows if r["kind"] == kind]
        timed = [r for r in mine if r["ms_per_checkpoint"] > 0]
        axes[0].loglog([r["bodies"] for r in timed], [r["ms_per_checkpoint"] for r in timed], style, label=kind)
        axes[1].loglog([r["bodies"] for r in mine], [r["checkpoint_mb"] for r in mine], style, label=kind)
    axes[0].set(xlabel="bodies", ylabel="ms per checkpoint", title="time to write a checkpoint")
    axes[1].set(xlabel="bodies", ylabel="MB", title="checkpoint size")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(results / "checkpoint_bench.png", dpi=120)
    print(f"wrote {results / 'checkpoint_bench.png'}")


if __name__ == "__main__":
    main()

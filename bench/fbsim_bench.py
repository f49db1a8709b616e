#!/usr/bin/python3
"""fbsim end to end: what a user's run costs per step, against the integrator alone.

Runs fbprep once on a slender beam (1 x 0.04 x 0.02 m, E = 5 GPa, rho = 2000, 10 mm elements, 16 free-free modes,
interfaces at both ends), then fbsim on scenes with it and reads `fbsim --json`: `integrator_us_per_step` is the time
inside GeneralizedAlpha::step, `us_per_step` the whole run (checks every 9 steps and at the last, CSV
writing, monitors). Writes results/fbsim_bench.csv and prints a table. See bench/README.md.

    /usr/bin/python3 bench/fbsim_bench.py [--build build] [--work bench/results/work/fbsim]
"""
import argparse
import csv
import json
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent

GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.04, 0.02};
"""

SPEC = """input: beam.geo
unit: m
material: {E: 5e9, nu: 0.3, rho: 2000}
mesh: {size: 0.01}
reduction: {kind: free-free, modes: 16}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}}
"""

# name -> (modes, steps, outputs block, extra top-level lines)
SCENES = {
    "pinned, tip position every step": (16, 10000, "outputs:\n  tip: {body: bar, interface: tip, quantities: [position]}\n", ""),
    "pinned, no outputs": (16, 10000, "", ""),
    "pinned, tip every 10 steps + monitors": (
        16, 10000, "outputs:\n  tip: {body: bar, interface: tip, quantities: [position, velocity]}\n", "monitors: true\n"),
    "pinned, 4 modes, tip every step": (4, 10000, "outputs:\n  tip: {body: bar, interface: tip, quantities: [position]}\n", ""),
}


def scene_text(modes, steps, outputs, extra, every):
    return (f"bodies:\n  bar: {{file: beam.fbh5, modes: {modes}}}\n"
            "joints:\n  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}\n"
            "gravity: [0, -9.81, 0]\n"
            f"integrator: {{type: generalized-alpha, rho_inf: 0.9, step: 1.0e-4, end: {steps * 1e-4:.6g}, "
            f"output_every: {every}}}\n" + outputs + extra)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--work", default=str(REPO / "bench/results/work/fbsim"))
    parser.add_argument("--runs", type=int, default=3, help="runs per scene; the fastest is kept")
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    (work / "beam.geo").write_text(GEO)
    (work / "beam.yaml").write_text(SPEC)
    # --order 1: the mesh of its recorded results (the default is quadratic from 0.13)
    subprocess.run([f"{args.build}/bin/fbprep", "beam.yaml", "-o", "beam.fbh5", "--order", "1", "--quiet"], cwd=work,
                   check=True)
    rows = []
    print(f"{'scene':40s} {'modes':>5s} {'steps':>6s} {'iter/step':>9s} {'integrator us':>13s} {'fbsim us':>9s} {'overhead':>8s}")
    for name, (modes, steps, outputs, extra) in SCENES.items():
        every = 10 if "every 10" in name else 1
        (work / "scene.yaml").write_text(scene_text(modes, steps, outputs, extra, every))
        best = None
        for _ in range(args.runs):
            out = subprocess.run([f"{args.build}/bin/fbsim", "scene.yaml", "-o", "out", "--json"], cwd=work,
                                 check=True, capture_output=True, text=True).stdout
            summary = json.loads(out)
            if best is None or summary["us_per_step"] < best["us_per_step"]:
                best = summary
        overhead = best["us_per_step"] / best["integrator_us_per_step"] - 1.0
        row = dict(scene=name, modes=modes, steps=best["steps"],
                   iterations_per_step=best["newton_iterations"] / best["steps"],
                   integrator_us_per_step=best["integrator_us_per_step"], fbsim_us_per_step=best["us_per_step"],
                   overhead=overhead)
        rows.append(row)
        print(f"{name:40s} {modes:5d} {row['steps']:6d} {row['iterations_per_step']:9.2f} "
              f"{row['integrator_us_per_step']:13.1f} {row['fbsim_us_per_step']:9.1f} {100 * overhead:7.1f}%")
    target = REPO / "bench/results/fbsim_bench.csv"
    with open(target, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print("wrote", target)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""The cost of a force that is a Python function of t (issue 31), per call and per step.

The bracket pendulum (meshes/bracket.yaml, linear tetrahedra, 6 modes) pushed at bore_2 by a force of 2.5 N along z,
run from Python three ways: with the scene file's constant force (no Python in the steps), with a Python function that
returns a list, and with one that returns a NumPy array. The same scene through fbsim gives the end-to-end reference.
Each run is repeated, the three in turns, and the fastest kept (the machine's noise is one-sided). The function counts its calls, so the
extra cost per call is (its run - the constant run) / calls.

    PYTHONPATH=build/python /usr/bin/python3 bench/python_force_bench.py [--build build] [--steps 10000]

Writes bench/results/python_force.csv and prints the table.
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def scene(folder, push, steps, step):
    import flexbody
    s = flexbody.Scene(folder)
    s.add_body("bracket", file="bracket.fbh5", modes=6)
    s.add_joint("pivot", type="revolute", body="bracket", interface="bore_1", axis=[0, 0, 1])
    s.add_force("push", body="bracket", interface="bore_2", **push)
    s.gravity = [0, -9.81, 0]
    s.set_integrator(rho_inf=0.9, step=step, end=steps * step)
    s.add_output("tip", body="bracket", interface="bore_3", quantities=["position"])
    return s


def timed_runs(folder, pushes, steps, step, repeats):
    """The fastest of `repeats` runs of each push, taken in turns (a slow phase of the machine hits all alike)."""
    best = [None] * len(pushes)
    summaries = [None] * len(pushes)
    for _ in range(repeats):
        for k, push in enumerate(pushes):
            sim = scene(folder, push, steps, step).simulate()
            start = time.perf_counter()
            sim.run()
            elapsed = time.perf_counter() - start
            best[k] = elapsed if best[k] is None else min(best[k], elapsed)
            summaries[k] = sim.summary()
    return best, summaries


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--steps", type=int, default=10000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", default=str(REPO / "bench/results/python_force.csv"))
    args = parser.parse_args()
    sys.path.insert(0, str(Path(args.build) / "python"))
    folder = REPO / "bench/results/work/python_force"
    folder.mkdir(parents=True, exist_ok=True)
    body = folder / "bracket.fbh5"
    if not body.exists():
        subprocess.run([str(Path(args.build) / "bin/fbprep"), str(REPO / "meshes/bracket.yaml"), "--order", "1",
                        "--modes", "6", "-o", str(body), "-q"], check=True)
    step = 1e-3
    calls = [0]

    def as_list(t):
        calls[0] += 1
        return [0.0, 0.0, 2.5]

    z = np.array([0.0, 0.0, 2.5])

    def as_array(t):
        calls[0] += 1
        return z

    pushes = [{"force": [0, 0, 2.5]}, {"force": as_list}, {"force": as_array}]
    names = ["scene file's constant force", "Python function, list", "Python function, NumPy array"]
    times, summaries = timed_runs(folder, pushes, args.steps, step, args.repeats)
    constant = times[0]
    per_run_calls = calls[0] // args.repeats // 2  # both functions count; each run makes the same calls
    rows = [(name, elapsed, summary["newton_iterations"], per_run_calls if k else 0)
            for k, (name, elapsed, summary) in enumerate(zip(names, times, summaries))]
    (folder / "scene.yaml").write_text(json.dumps(scene(folder, {"force": [0, 0, 2.5]}, args.steps, step).to_dict()))
    fbsim = min(json.loads(subprocess.run([str(Path(args.build) / "bin/fbsim"), "scene.yaml", "-o", "out", "--json"],
                                          cwd=folder, capture_output=True, text=True, check=True).stdout)["wall_s"]
                for _ in range(args.repeats))

    print(f"{args.steps} steps of {step} s; fastest of {args.repeats} runs each")
    print(f"{'run':34} {'us/step':>9} {'calls/step':>11} {'us/call':>9} {'Newton it./step':>16}")
    with open(args.out, "w", newline="") as f:
        out = csv.writer(f)
        out.writerow(["run", "us_per_step", "calls_per_step", "extra_us_per_call", "newton_iterations_per_step"])
        for name, elapsed, iterations, n_calls in rows + [("fbsim (wall_s of --json)", fbsim, rows[0][2], 0)]:
            per_step = 1e6 * elapsed / args.steps
            per_call = 1e6 * (elapsed - constant) / n_calls if n_calls else 0.0
            print(f"{name:34} {per_step:9.1f} {n_calls / args.steps:11.2f} {per_call:9.2f} {iterations / args.steps:16.2f}")
            out.writerow([name, f"{per_step:.2f}", f"{n_calls / args.steps:.3f}", f"{per_call:.3f}",
                          f"{iterations / args.steps:.3f}"])
    print(f"wrote {os.path.relpath(args.out)}")


if __name__ == "__main__":
    main()

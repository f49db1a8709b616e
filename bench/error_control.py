"""Error control on the sample bracket pendulum: steps, steps taken again, Newton matrices and error of `step: auto`
against fixed steps (docs/formulations.md "Error Control" quotes the table).

The scene is meshes/bracket_pendulum.yaml's (0.5 s, 6 modes, rho_inf 0.9, bore_3's position every 16 ms), in the
GCMS and, with --formulation ffrf, in the FFRF. The error is bore_3's largest distance over the rows from a fixed
1e-5 s run of the same formulation. Step counts, matrices and errors are deterministic; the CPU column is one run's.

    fbprep meshes/bracket.yaml -o build/bracket.fbh5
    /usr/bin/python3 bench/error_control.py [--build build] [--formulation gcms|ffrf]     # about 1 minute
"""
import argparse
import json
import pathlib
import subprocess

import numpy as np

TOLERANCES = [1e-6, 1e-7, 1e-8, 1e-9]
FIXED_STEPS = [2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
REFERENCE_STEP = 1e-5


def scene(body_file, formulation, step):
    body = f"{{file: {body_file}, modes: 6{', formulation: ffrf' if formulation == 'ffrf' else ''}}}"
    return (f"bodies:\n  bracket: {body}\n"
            "joints:\n  pivot: {type: revolute, body: bracket, interface: bore_1, to: ground, axis: [0, 0, 1]}\n"
            "gravity: [0, -9.81, 0]\n"
            f"integrator: {{type: generalized-alpha, rho_inf: 0.9, {step}, end: 0.5, output_interval: 0.016}}\n"
            "outputs:\n  bore_3: {body: bracket, interface: bore_3, quantities: [position]}\n")


def run(fbsim, folder, name, text):
    (folder / f"{name}.yaml").write_text(text)
    out = subprocess.run([fbsim, f"{name}.yaml", "-o", name, "--json"], cwd=folder, check=True,
                         capture_output=True, text=True)
    summary = json.loads(out.stdout)
    rows = np.loadtxt(folder / name / "bore_3.csv", delimiter=",", skiprows=1)
    return summary, rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build")
    parser.add_argument("--formulation", choices=["gcms", "ffrf"], default="gcms")
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    body_file = build / "bracket.fbh5"
    if not body_file.exists():
        raise SystemExit(f"{body_file}: missing; make it with fbprep meshes/bracket.yaml -o {body_file}")
    folder = build / "bench-error-control"
    folder.mkdir(exist_ok=True)
    fbsim = build / "bin" / "fbsim"
    _, reference = run(fbsim, folder, "reference", scene(body_file, args.formulation, f"step: {REFERENCE_STEP}"))

    def error(rows):
        if rows.shape != reference.shape or not np.allclose(rows[:, 0], reference[:, 0], rtol=0, atol=1e-12):
            raise SystemExit("the rows' times differ from the reference's")
        return np.linalg.norm(rows[:, 1:4] - reference[:, 1:4], axis=1).max()

    print(f"bracket pendulum, {args.formulation}, 6 modes, 0.5 s; error: bore_3 against h = {REFERENCE_STEP} s")
    print(f"{'run':>14} {'steps':>7} {'again':>6} {'matrices':>9} {'error [m]':>10} {'CPU [s]':>8}")
    for tolerance in TOLERANCES:
        summary, rows = run(fbsim, folder, f"auto_{tolerance:g}",
                            scene(body_file, args.formulation, f"step: auto, error_tolerance: {tolerance}"))
        print(f"{'E = %g' % tolerance:>14} {summary['steps']:7d} {summary['rejected_steps']:6d} "
              f"{summary['newton_matrices']:9d} {error(rows):10.2e} {summary['cpu_s']:8.3f}")
    for step in FIXED_STEPS:
        summary, rows = run(fbsim, folder, f"fixed_{step:g}", scene(body_file, args.formulation, f"step: {step}"))
        print(f"{'h = %g' % step:>14} {summary['steps']:7d} {summary['retried_steps']:6d} "
              f"{summary['newton_matrices']:9d} {error(rows):10.2e} {summary['cpu_s']:8.3f}")


if __name__ == "__main__":
    main()

"""Error control (`step: auto`) against fixed steps in fbsim: steps, steps taken again, Newton matrices, error and CPU
time (docs/formulations.md "Error Control" quotes the pendulum's table, docs/accuracy-and-speed.md the chains').

--scene pendulum (default): meshes/bracket_pendulum.yaml's scene (0.5 s, rho_inf 0.9, bore_3's position every 16 ms)
with --modes (default 6) and --formulation gcms|ffrf; the fixed steps include 16, 8 and 4 ms, where the GCMS failed
before failed steps were taken again in halves ("again" counts those halvings for a fixed step).
--scene chain: bench/scale_scenes.py's chain of --bodies brackets (--kind rigid|gcms|ffrf, 6 modes) pinned end to end,
falling from the horizontal under gravity for --end s (default 0.2), the last bracket's bore_2 sampled every end/50.

The error is the sampled point's largest distance over the rows from a fixed 1e-5 s run of the same scene. Step
counts, matrices and errors are deterministic; the CPU column is fbsim's (one run).

    fbprep meshes/bracket.yaml -o build/bracket.fbh5
    /usr/bin/python3 bench/error_control.py [--build build] [--formulation gcms|ffrf] [--modes 12]   # about 1 minute
    /usr/bin/python3 bench/error_control.py --scene chain --kind rigid --bodies 64                  # about 1 minute
"""
import argparse
import json
import pathlib
import subprocess
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
from scale_scenes import KINDS, Bracket, chain_scene  # noqa: E402  (the chains, beside this script)

TOLERANCES = [1e-6, 1e-7, 1e-8, 1e-9]
REFERENCE_STEP = 1e-5


def integrator(step, end, interval):
    return f"integrator: {{type: generalized-alpha, rho_inf: 0.9, {step}, end: {end}, output_interval: {interval}}}\n"


def pendulum(body_file, formulation, modes, step):
    body = f"{{file: {body_file}, modes: {modes}{', formulation: ffrf' if formulation == 'ffrf' else ''}}}"
    return (f"bodies:\n  bracket: {body}\n"
            "joints:\n  pivot: {type: revolute, body: bracket, interface: bore_1, to: ground, axis: [0, 0, 1]}\n"
            "gravity: [0, -9.81, 0]\n" + integrator(step, 0.5, 0.016) +
            "outputs:\n  tip: {body: bracket, interface: bore_3, quantities: [position]}\n")


def chain(body_file, kind, bodies, step, end):
    text, _, _ = chain_scene(body_file, Bracket(body_file), kind, bodies, 1)
    text = "\n".join(line for line in text.splitlines() if not line.startswith("integrator:")) + "\n"
    return (text + integrator(step, end, end / 50) +
            f"outputs:\n  tip: {{body: b{bodies - 1}, interface: bore_2, quantities: [position]}}\n")


def run(fbsim, folder, name, text):
    (folder / f"{name}.yaml").write_text(text)
    out = subprocess.run([fbsim, f"{name}.yaml", "-o", name, "--json"], cwd=folder, check=True,
                         capture_output=True, text=True)
    summary = json.loads(out.stdout)
    rows = np.loadtxt(folder / name / "tip.csv", delimiter=",", skiprows=1)
    return summary, rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build")
    parser.add_argument("--scene", choices=["pendulum", "chain"], default="pendulum")
    parser.add_argument("--formulation", choices=["gcms", "ffrf"], default="gcms", help="pendulum")
    parser.add_argument("--modes", type=int, default=6, help="pendulum")
    parser.add_argument("--kind", choices=sorted(KINDS), default="rigid", help="chain")
    parser.add_argument("--bodies", type=int, default=64, help="chain")
    parser.add_argument("--end", type=float, default=0.2, help="chain [s]")
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    body_file = build / "bracket.fbh5"
    if not body_file.exists():
        raise SystemExit(f"{body_file}: missing; make it with fbprep meshes/bracket.yaml -o {body_file}")
    folder = build / "bench-error-control"
    folder.mkdir(exist_ok=True)
    fbsim = build / "bin" / "fbsim"
    if args.scene == "pendulum":
        def scene(step):
            return pendulum(body_file, args.formulation, args.modes, step)
        fixed_steps = [1.6e-2, 8e-3, 4e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
        title = f"bracket pendulum, {args.formulation}, {args.modes} modes, 0.5 s; error: bore_3"
        tag = f"pendulum_{args.formulation}_{args.modes}"
    else:
        def scene(step):
            return chain(body_file, args.kind, args.bodies, step, args.end)
        fixed_steps = [2e-3, 1e-3, 5e-4, 2e-4, 1e-4]
        title = f"chain of {args.bodies} brackets, {args.kind}, {args.end:g} s; error: the last bore_2"
        tag = f"chain_{args.kind}_{args.bodies}"
    _, reference = run(fbsim, folder, f"{tag}_reference", scene(f"step: {REFERENCE_STEP}"))

    def error(rows):
        if rows.shape != reference.shape or not np.allclose(rows[:, 0], reference[:, 0], rtol=0, atol=1e-12):
            raise SystemExit("the rows' times differ from the reference's")
        return np.linalg.norm(rows[:, 1:4] - reference[:, 1:4], axis=1).max()

    print(f"{title} against h = {REFERENCE_STEP} s")
    print(f"{'run':>14} {'steps':>7} {'again':>6} {'matrices':>9} {'error [m]':>10} {'CPU [s]':>8}")
    for tolerance in TOLERANCES:
        summary, rows = run(fbsim, folder, f"{tag}_auto_{tolerance:g}", scene(f"step: auto, error_tolerance: {tolerance}"))
        print(f"{'E = %g' % tolerance:>14} {summary['steps']:7d} {summary['rejected_steps']:6d} "
              f"{summary['newton_matrices']:9d} {error(rows):10.2e} {summary['cpu_s']:8.3f}", flush=True)
    for step in fixed_steps:
        try:
            summary, rows = run(fbsim, folder, f"{tag}_fixed_{step:g}", scene(f"step: {step}"))
        except subprocess.CalledProcessError as e:
            print(f"{'h = %g' % step:>14} failed: {e.stderr.strip().splitlines()[-1][:100]}")
            continue
        print(f"{'h = %g' % step:>14} {summary['steps']:7d} {summary['retried_steps']:6d} "
              f"{summary['newton_matrices']:9d} {error(rows):10.2e} {summary['cpu_s']:8.3f}", flush=True)


if __name__ == "__main__":
    main()

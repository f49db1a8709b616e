"""How far one-ulp changes of a scene's input move fbsim's results through the Newton iteration's history (issue 46).

Runs scale_invariance_test's scenes (the test writes them and their body files into its scratch folder), then each
scene again with one number changed by 1, 2, ... ulps (the drive's speed of the spun beam, gravity of the pendulum, the
push's force, the free spin's rate), and prints per scene and scale the largest difference of the modal coordinates
from the unchanged run, relative to their largest value, and how many runs moved by more than 1e-9. docs/limits.md
("The Integrator") and scale_invariance_test.cpp quote it: the spun beam's modes spread by up to 1.25e-5 (15 of 120
runs above 1e-9), the others by at most 9.4e-9.

    /usr/bin/python3 bench/newton_history_spread.py [--build build] [--runs 60]     # about 1 minute
"""
import argparse
import math
import pathlib
import subprocess

import numpy as np

# scene -> the number to change (every occurrence: the spun beam's speed is its initial spin and the drive's), as the
# test writes it at 1 m and at 100 m, with the text around it that makes it unique
SCENES = {
    "spun": {1: ("", "330", ""), 100: ("", "3.2999999999999998", "")},
    "pendulum": {1: ("[0, ", "-9.8100000000000005", ", 0]"), 100: ("[0, ", "-0.098100000000000007", ", 0]")},
    "push": {1: ("force: [0, ", "1000", ", 0]"), 100: ("force: [0, ", "10000000", ", 0]")},
}


def modes(path):
    return np.loadtxt(path, delimiter=",", skiprows=1)[:, 1:]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--build", default="build")
    parser.add_argument("--runs", type=int, default=60, help="perturbed runs per scene and scale")
    args = parser.parse_args()
    build = pathlib.Path(args.build).resolve()
    subprocess.run([build / "bin" / "preprocess_tests", "--gtest_filter=ScaleInvariance.ScenesWithTheBeamScaleExactly"],
                   check=True, stdout=subprocess.DEVNULL)
    scratch = build / "test-scratch" / "ScaleInvariance.ScenesWithTheBeamScaleExactly"
    print(f"{'scene':10} {'scale':>6} {'runs':>5} {'largest spread':>15} {'runs > 1e-9':>12}")
    for scene, literals in SCENES.items():
        for scale, (before, literal, after) in literals.items():
            text = (scratch / f"{scene}-beam-{scale}.yaml").read_text()
            if before + literal + after not in text:
                raise SystemExit(f"{scene}-beam-{scale}.yaml: '{before + literal + after}' not found")
            reference = modes(scratch / f"{scene}-beam-{scale}-out" / "modes.csv")
            largest = np.abs(reference).max()
            value, spreads = float(literal), []
            for k in range(args.runs):
                value = math.nextafter(value, math.inf)
                name = f"spread-{scene}-{scale}-{k}"
                (scratch / f"{name}.yaml").write_text(text.replace(before + literal + after, before + repr(value) + after))
                subprocess.run([build / "bin" / "fbsim", f"{name}.yaml", "-o", f"{name}-out", "-q"], cwd=scratch,
                               check=True)
                spreads.append(np.abs(modes(scratch / f"{name}-out" / "modes.csv") - reference).max() / largest)
            print(f"{scene:10} {scale:>4} m {args.runs:>5} {max(spreads):>15.3e} {sum(s > 1e-9 for s in spreads):>12}")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Geometric stiffening end to end (issue 29): what it costs per step, and the spinning cantilever's flapwise frequency.

Runs fbprep once on a steel cantilever 1 x 0.03 x 0.02 m (Craig-Bampton with an rbe2 root, 6 fixed-interface modes,
10 mm quadratic tetrahedra, `geometric_stiffness: true`), then fbsim:

1. Cost: the beam driven about y at 150 rad/s (1.43 omega_1; smooth ramp over 0.5 s), 1 s at h = 1e-4 s, GCMS and
   FFRF (mean-axis frame), with the file's geometric stiffness and with `geometric_stiffness: false` (the spin guard
   off, so that the linear model runs too; in the root frame the linear model diverges at this spin, as it should). `fbsim --json`: us per step, Newton iterations per step; the fastest of --runs runs.
2. Accuracy: the beam driven about z (the beam bends flapwise, along z, out of the plane of rotation) at 0 to 3
   omega_1, with gravity along -z switched on at t = 0, which sets the tip vibrating about its sag. The flapwise
   frequency from the tip's zero crossings about its mean over the last 10 periods, against the rotating
   Euler-Bernoulli cantilever (Rayleigh-Ritz, x^2 ... x^9) scaled by each run's frequency at rest, and Southwell's
   line f^2 = f0^2 + 1.1933 Omega^2. GCMS and FFRF in the root frame, with and without stiffening.

Writes results/stiffening_bench.csv, results/stiffening_frequencies.csv and results/stiffening_bench.png, prints
tables. See bench/README.md.

    /usr/bin/python3 bench/stiffening_bench.py [--build build] [--work bench/results/work/stiffening]
"""
import argparse
import csv
import json
import math
import subprocess
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parent.parent
SOUTHWELL = 1.1933

GEO = """SetFactory("OpenCASCADE");
Box(1) = {0, 0, 0, 1, 0.03, 0.02};
"""

SPEC = """input: beam.geo
unit: m
material: steel
mesh: {size: 0.01}
reduction: {kind: craig-bampton, modes: 6}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}, coupling: rbe2}
  tip: {select: {plane: {point: [1, 0, 0], normal: [1, 0, 0]}}, coupling: rbe3}
geometric_stiffness: true
"""


def scene(formulation, stiffening, axis, speed, ramp, step, end, gravity=None, root_frame=True):
    frame = ", frame: {interface: root}" if formulation == "ffrf" and root_frame else ""
    text = (f"bodies:\n  beam: {{file: beam.fbh5, formulation: {formulation}{frame}, "
            f"geometric_stiffness: {'true' if stiffening else 'false'}}}\n"
            f"joints:\n  hub: {{type: driven-revolute, body: beam, interface: root, to: ground, axis: {axis}, "
            f"speed: {speed}, ramp: {ramp}}}\n")
    if gravity:
        text += f"gravity: {gravity}\n"
    text += (f"integrator: {{type: generalized-alpha, rho_inf: 0.95, step: {step:.6g}, end: {end:.6g}, "
             "spin_warning: 0, spin_limit: 0, stiffened_spin_warning: 0, stiffened_spin_limit: 0, "
             "deformation_limit: 0}\n"
             "outputs:\n  tip: {body: beam, interface: tip, quantities: [position]}\n")
    return text


def fbsim(build, work, name, text, fatal=True):
    (work / f"{name}.yaml").write_text(text)
    run = subprocess.run([str(Path(build) / "bin/fbsim"), f"{name}.yaml", "-o", f"{name}_out", "--json"], cwd=work,
                         capture_output=True, text=True)
    if run.returncode != 0:
        if fatal:
            raise SystemExit(f"fbsim {name}: {run.stderr.strip()}")
        return None
    return json.loads(run.stdout)


def beam_ratio(spin_over_rest):
    """The rotating Euler-Bernoulli cantilever's first flapwise frequency over its value at rest."""
    n = 8
    k = np.zeros((n, n))
    g = np.zeros((n, n))
    m = np.zeros((n, n))
    for i in range(n):
        for j in range(n):
            p, q = i + 2.0, j + 2.0
            k[i, j] = p * (p - 1) * q * (q - 1) / (p + q - 3)
            g[i, j] = 0.5 * p * q * (1 / (p + q - 1) - 1 / (p + q + 1))
            m[i, j] = 1 / (p + q + 1)

    def lowest(spin):
        from scipy.linalg import eigh
        return math.sqrt(eigh(k + spin * spin * g, m, eigvals_only=True)[0])

    rest = lowest(0.0)
    return lowest(spin_over_rest * rest) / rest


def frequency(csv_path, after, periods_hint):
    """rad/s from the zero crossings of z about its mean after time `after`."""
    data = np.loadtxt(csv_path, delimiter=",", skiprows=1)
    t, z = data[:, 0], data[:, 3]
    keep = t > after
    t, z = t[keep], z[keep] - z[keep].mean()
    crossings = []
    for i in range(1, len(z)):
        if (z[i] > 0) != (z[i - 1] > 0):
            crossings.append(t[i] - (t[i] - t[i - 1]) * z[i] / (z[i] - z[i - 1]))
    if len(crossings) < 4:
        return float("nan")
    return 2 * math.pi / ((crossings[-1] - crossings[0]) / (0.5 * (len(crossings) - 1)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", default=str(REPO / "build"))
    parser.add_argument("--work", default=str(REPO / "bench/results/work/stiffening"))
    parser.add_argument("--runs", type=int, default=3, help="runs per cost scene; the fastest is kept")
    args = parser.parse_args()
    work = Path(args.work)
    work.mkdir(parents=True, exist_ok=True)
    (work / "beam.geo").write_text(GEO)
    (work / "beam.yaml").write_text(SPEC)
    prep = subprocess.run([str(Path(args.build) / "bin/fbprep"), "beam.yaml", "-o", "beam.fbh5", "-q"], cwd=work,
                          capture_output=True, text=True)
    if prep.returncode != 0:
        raise SystemExit(f"fbprep: {prep.stderr.strip()}")
    results = REPO / "bench/results"

    # 1. Cost per step.
    cost = []
    for formulation in ("gcms", "ffrf"):
        for stiffening in (False, True):
            best = None
            for _ in range(args.runs):
                j = fbsim(args.build, work, f"cost_{formulation}_{int(stiffening)}",
                          scene(formulation, stiffening, "[0, 1, 0]", 150, 0.5, 1e-4, 1.0, root_frame=False))
                if best is None or j["us_per_step"] < best["us_per_step"]:
                    best = j
            cost.append({"formulation": formulation, "stiffening": stiffening, "us_per_step": best["us_per_step"],
                         "iterations_per_step": best["newton_iterations"] / best["steps"],
                         "newton_matrices": best["newton_matrices"]})
    for row in cost:
        base = next(r for r in cost if r["formulation"] == row["formulation"] and not r["stiffening"])
        row["ratio"] = row["us_per_step"] / base["us_per_step"]
    with open(results / "stiffening_bench.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(cost[0].keys()))
        writer.writeheader()
        writer.writerows(cost)
    print("| formulation | stiffening | us/step | Newton iterations/step | Newton matrices | ratio |")
    print("|---|---|---|---|---|---|")
    for r in cost:
        print(f"| {r['formulation']} | {'on' if r['stiffening'] else 'off'} | {r['us_per_step']:.1f} | "
              f"{r['iterations_per_step']:.2f} | {r['newton_matrices']} | {r['ratio']:.2f} |")

    # 2. The flapwise frequency against the spin.
    omega_rest = {}
    rows = []
    for formulation in ("gcms", "ffrf"):
        for stiffening in (True, False):
            for ratio in (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0):
                spin = ratio * 105.0
                guess = 105.0 * (beam_ratio(ratio) if stiffening else 1.0)
                step = min(2 * math.pi / guess / 100, 0.025 / spin if spin > 0 else 1.0)
                ramp = 0.2
                end = ramp + 12 * 2 * math.pi / guess
                name = f"flap_{formulation}_{int(stiffening)}_{int(100 * ratio)}"
                # Unstiffened, the in-plane bending (157.5 rad/s at rest) softens as its square minus the spin's
                # squared: the linear model diverges from about 1.5 omega_1 on, which is recorded as NaN.
                ran = fbsim(args.build, work, name, scene(formulation, stiffening, "[0, 0, 1]", spin, ramp, step, end,
                                                          "[0, 0, -9.81]"), fatal=stiffening)
                w = frequency(work / f"{name}_out" / "tip.csv", end - 10 * 2 * math.pi / guess, 10) if ran else math.nan
                if ratio == 0.0:
                    omega_rest[formulation] = w
                w0 = omega_rest[formulation]
                expected = w0 * beam_ratio(spin / w0)
                rows.append({"formulation": formulation, "stiffening": stiffening, "spin_over_omega1": ratio,
                             "spin_rad_s": spin, "frequency_rad_s": w, "rotating_beam_rad_s": expected,
                             "southwell_rad_s": math.sqrt(w0 * w0 + SOUTHWELL * spin * spin),
                             "error": w / expected - 1})
    with open(results / "stiffening_frequencies.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)
    print()
    print("| formulation | stiffening | Omega/omega_1 | flapwise [rad/s] | rotating beam | Southwell | error |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['formulation']} | {'on' if r['stiffening'] else 'off'} | {r['spin_over_omega1']:.1f} | "
              f"{r['frequency_rad_s']:.2f} | {r['rotating_beam_rad_s']:.2f} | {r['southwell_rad_s']:.2f} | "
              f"{100 * r['error']:+.2f} % |")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    spins = np.linspace(0, 3, 61)
    ax.plot(spins, [beam_ratio(s) for s in spins], "k-", label="rotating Euler-Bernoulli beam")
    ax.plot(spins, np.sqrt(1 + SOUTHWELL * spins ** 2), "k:", label="Southwell, S = 1.1933")
    styles = {("gcms", True): ("o", "C0"), ("ffrf", True): ("s", "C1"), ("gcms", False): ("x", "C0"),
              ("ffrf", False): ("+", "C1")}
    for (formulation, stiffening), (marker, color) in styles.items():
        pts = [r for r in rows if r["formulation"] == formulation and r["stiffening"] == stiffening]
        w0 = omega_rest[formulation]
        ax.plot([r["spin_rad_s"] / w0 for r in pts], [r["frequency_rad_s"] / w0 for r in pts], marker, color=color,
                fillstyle="none", linestyle="none",
                label=f"fbsim {formulation.upper()}{' (root frame)' if formulation == 'ffrf' else ''}, "
                      f"{'stiffened' if stiffening else 'linear'}")
    ax.set_xlabel("spin / first frequency at rest")
    ax.set_ylabel("flapwise frequency / at rest")
    ax.set_title("Cantilever spun about its root (fbprep beam, 6 Craig-Bampton modes)")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(results / "stiffening_bench.png", dpi=120)
    print(f"\nwrote {results / 'stiffening_bench.csv'}, {results / 'stiffening_frequencies.csv'}, "
          f"{results / 'stiffening_bench.png'}")


if __name__ == "__main__":
    main()

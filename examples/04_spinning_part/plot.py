#!/usr/bin/python3
"""Example 04's picture: the spinning cantilever's tip sag under gravity against the spin, in the GCMS and the FFRF,
with and without geometric stiffness, beside the rotating Euler-Bernoulli beam's.

    plot.py BEAM.fbh5 RUN_DIR OUT.png     (RUN_DIR: fbsim's output directory)
"""
import sys
from pathlib import Path

import h5py
import matplotlib.pyplot as plt
import numpy as np

LENGTH, WIDTH, THICKNESS = 1.0, 0.03, 0.02  # beam.geo [m]; it sags along z, through its thickness
ROOT_Y, ROOT_Z = 0.015, 0.01                # the root's centre, on the spin axis
SETTLED = 0.6                               # [s]: the ringing gravity starts has died out by then


def beam_sag(spin, youngs, density, g=9.81):
    """Tip sag [m] of a uniform Euler-Bernoulli cantilever under its weight, spinning at `spin` [rad/s] about an
    axis through its root, normal to it: EI w'''' - (N w')' = -rho A g with the tension N = rho A spin^2 (L^2 - x^2)/2.
    Rayleigh-Ritz with (x/L)^2 ... (x/L)^9, whose integrals are exact; at rest it gives q L^4 / (8 EI)."""
    area, inertia = WIDTH * THICKNESS, WIDTH * THICKNESS ** 3 / 12
    p = np.arange(2, 10, dtype=float)[:, None]
    q = p.T
    k = p * (p - 1) * q * (q - 1) / (p + q - 3)                 # bending
    tension = 0.5 * p * q * (1 / (p + q - 1) - 1 / (p + q + 1))  # centrifugal tension
    load = 1 / (p[:, 0] + 1)                                    # uniform weight
    scale = density * area * g * LENGTH ** 4 / (youngs * inertia)
    s2 = density * area * spin ** 2 * LENGTH ** 4 / (youngs * inertia)
    return np.array([scale * np.linalg.solve(k + s * tension, load).sum() for s in np.atleast_1d(s2)])


def main():
    body, run, target = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    with h5py.File(body, "r") as f:  # names from formats/SCHEMA.md
        youngs, density = (f["material"].attrs[k] for k in ("youngs_modulus", "density"))
        omega_1 = 2 * np.pi * f["reduction/fixed_interface_frequencies_hz"][0]  # the root clamped: the cantilever's

    fig, ax = plt.subplots(figsize=(8, 4.5), dpi=100)
    styles = {"gcms_stiffened": ("C0", "-", "GCMS, geometric stiffness"),
              "gcms_linear": ("C0", ":", "GCMS, geometric_stiffness: false"),
              "ffrf_stiffened": ("C1", "--", "FFRF (root frame), geometric stiffness"),
              "ffrf_linear": ("C1", ":", "FFRF (root frame), geometric_stiffness: false")}
    final = {}
    for name, (colour, line, label) in styles.items():
        data = np.loadtxt(run / f"{name}.csv", delimiter=",", skiprows=1, ndmin=2)
        t, x, y, z = data.T
        spin = np.gradient(np.unwrap(np.arctan2(y - ROOT_Y, x)), t) if len(t) > 2 else np.zeros_like(t)
        keep = t >= min(SETTLED, t[-1])
        ax.plot(spin[keep] / omega_1, 1e3 * (ROOT_Z - z[keep]), color=colour, ls=line, lw=1.6, label=label)
        final[name] = (spin[-1], ROOT_Z - z[-1])
    top = max(s for s, _ in final.values())
    spins = np.linspace(0, max(top, 0.05 * omega_1), 60)
    ax.plot(spins / omega_1, 1e3 * beam_sag(spins, youngs, density), "k-", lw=0.8, alpha=0.6,
            label="rotating Euler-Bernoulli beam")
    ax.set_xlabel(f"spin / first bending frequency ({omega_1:.0f} rad/s)")
    ax.set_ylabel("tip sag under gravity [mm]")
    ax.set_ylim(bottom=0)
    ax.set_title("steel cantilever 1 m x 30 x 20 mm spun up about its root, gravity along the spin axis", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(target, dpi=100)
    reference = beam_sag(top, youngs, density)[0]
    print(f"wrote {target}: tip sag at {top:.0f} rad/s ({top / omega_1:.2f} omega_1), "
          f"beam theory {1e3 * reference:.3f} mm; "
          + ", ".join(f"{name} {1e3 * sag:.3f} mm" for name, (_, sag) in final.items()))


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Example 03's picture: the slider's travel with its difference from a rigid rod's, and the flexible rod's mid-span
deflection, against time.

    plot.py RUN_DIR OUT.png     (RUN_DIR: fbsim's output directory)
"""
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

R, L = 0.05, 0.25  # crank radius and rod length, bore to bore [m], as in slider_crank.yaml


def load(run, name):
    """A position output: t [s] and x, y, z [m] as columns."""
    return np.loadtxt(run / f"{name}.csv", delimiter=",", skiprows=1, ndmin=2)


def main():
    run, target = Path(sys.argv[1]), Path(sys.argv[2])
    pin, slider = load(run, "crank_pin"), load(run, "slider")
    crank_end, slider_end, mid = load(run, "rod_crank_end"), load(run, "rod_slider_end"), load(run, "rod_mid")
    t = pin[:, 0]
    # The crank angle from its pin; a rigid rod would put the slider at r cos(phi) + sqrt(L^2 - r^2 sin(phi)^2).
    phi = np.arctan2(pin[:, 2], pin[:, 1])
    rigid = R * np.cos(phi) + np.sqrt(L ** 2 - (R * np.sin(phi)) ** 2)
    # Mid-span deflection: the mid ring's distance from the chord between the two bores, in the mechanism's plane.
    chord = slider_end[:, 1:3] - crank_end[:, 1:3]
    normal = np.stack([-chord[:, 1], chord[:, 0]], axis=1) / np.linalg.norm(chord, axis=1)[:, None]
    deflection = np.sum((mid[:, 1:3] - 0.5 * (crank_end[:, 1:3] + slider_end[:, 1:3])) * normal, axis=1)
    modes = np.loadtxt(run / "rod_modes.csv", delimiter=",", skiprows=1, ndmin=2)[:, 1:]

    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 4.5), dpi=100, sharex=True)
    top.plot(t, 1e3 * slider[:, 1], "C0-", lw=1.0)
    top.set_ylabel("slider x [mm]", color="C0")
    twin = top.twinx()
    twin.plot(t, 1e6 * (slider[:, 1] - rigid), "C3-", lw=0.8)
    twin.set_ylabel("slider x - rigid rod's [µm]", color="C3")
    top.set_title("slider-crank, crank spun up to 30 rev/s over 0.1 s; aluminium rod 250 x 6 x 10 mm", fontsize=10)
    bottom.plot(t, 1e3 * deflection, "C2-", lw=0.8)
    bottom.set_ylabel("rod mid-span\ndeflection [mm]")
    bottom.set_xlabel("time [s]")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(target, dpi=100)
    print(f"wrote {target}: slider within {1e6 * np.abs(slider[:, 1] - rigid).max():.1f} µm of a rigid rod's; "
          f"rod mid-span deflection up to {1e3 * np.abs(deflection).max():.3f} mm; largest modal coordinate "
          f"{np.abs(modes).max():.3g} kg^1/2 m")


if __name__ == "__main__":
    main()

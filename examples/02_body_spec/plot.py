#!/usr/bin/python3
"""Example 02's picture: where the body spec put its interfaces and its output region on the bracket, the fillet's
von Mises stress at the end of the bolted run, and the fillet's peak stress over time against the bolted first
frequency that the body file holds.

    plot.py BODY.fbh5 RUN_DIR OUT.png     (RUN_DIR: fbsim's output directory, with fillet.csv)
"""
import sys
from pathlib import Path

import h5py
import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection


def von_mises(s):
    """von Mises stress of rows of (xx, yy, zz, xy, xz, yz)."""
    xx, yy, zz, xy, xz, yz = s.T
    return np.sqrt(0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3 * (xy ** 2 + xz ** 2 + yz ** 2))


def main():
    body, run, target = Path(sys.argv[1]), Path(sys.argv[2]), Path(sys.argv[3])
    with h5py.File(body, "r") as f:  # names from formats/SCHEMA.md
        # Input-frame positions in mm (the spec's unit): body-frame nodes plus the centre of mass.
        nodes = 1e3 * (f["mesh/nodes"][...] + f["mass"].attrs["center_of_mass_input"])
        triangles = f["mesh/surface_triangles"][...]
        bores = {name: (f[f"interfaces/{name}/nodes"][...], f[f"interfaces/{name}"].attrs["coupling"].decode())
                 for name in f["interfaces"].attrs["order"].decode().split(",")}
        fillet = f["recovery/fillet/nodes"][...]
        bolted_hz = f["reduction/fixed_interface_frequencies_hz"][0]
        free_hz = f["reduction/frequencies_hz"][0]

    # fillet.csv: t, then sxx_N ... syz_N for each node N of the region (six columns per node, in the file's order).
    with open(run / "fillet.csv") as f:
        header = f.readline().split(",")
    columns = [int(c.split("_")[1].split()[0]) for c in header[1::6]]  # the node of each group of six
    assert columns == list(fillet), "fillet.csv's nodes are the body file's /recovery/fillet/nodes"
    data = np.loadtxt(run / "fillet.csv", delimiter=",", skiprows=1, ndmin=2)
    t = data[:, 0]
    stress = data[:, 1:].reshape(len(t), -1, 6)
    mises = von_mises(stress.reshape(-1, 6)).reshape(len(t), -1) / 1e6  # MPa, per time and node

    fig = plt.figure(figsize=(10, 4.5), dpi=100)
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    ax.add_collection3d(Poly3DCollection(nodes[triangles], facecolor=(0.85, 0.85, 0.85, 0.35), linewidths=0.0))
    for (name, (ids, coupling)), colour in zip(bores.items(), ("k", "k", "C0")):
        ax.scatter(*nodes[ids].T, s=2, c=colour, depthshade=False)
        ax.text(*nodes[ids].mean(axis=0) + (0, 0, 12), f"{name}\n{coupling}", fontsize=8, color=colour, ha="center")
    shown = ax.scatter(*nodes[fillet].T, s=6, c=mises[-1], cmap="viridis", depthshade=False)
    fig.colorbar(shown, ax=ax, shrink=0.6, pad=0.02, label=f"fillet: von Mises at {1e3 * t[-1]:.0f} ms [MPa]")
    ax.set_xlim(0, 90), ax.set_ylim(0, 40), ax.set_zlim(0, 60)
    ax.set_box_aspect((90, 40, 60), zoom=1.25)  # true proportions
    ax.view_init(elev=22, azim=-62)
    ax.set_axis_off()
    ax.set_title("bracket_cb.yaml: interfaces and the output region", fontsize=10)

    ax = fig.add_subplot(1, 2, 2)
    ax.plot(1e3 * t, mises.max(axis=1), "C0-")
    period = 1e3 / bolted_hz
    for k in range(int(1e3 * t[-1] / period) + 1):  # the ringing follows the file's bolted first frequency
        ax.axvline(0.5 * period + k * period, color="0.85", lw=0.8, zorder=0)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("largest von Mises stress on the fillet [MPa]")
    ax.set_title(f"bolted, 200 N at bore_3; grey lines every 1 / {bolted_hz:.0f} Hz\n"
                 f"(fixed-interface mode 1; the free body's first mode: {free_hz:.0f} Hz)", fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(target, dpi=100)
    print(f"wrote {target}: fillet peak {mises[-1].max():.1f} MPa at t = {1e3 * t[-1]:.1f} ms, "
          f"bolted first frequency {bolted_hz:.0f} Hz")


if __name__ == "__main__":
    main()

#!/usr/bin/python3
"""Example 01's picture: the bracket at its most stressed ParaView frame, coloured by von Mises stress, its elastic
displacement exaggerated, and the path of its third bore. Also the picture at the top of the project's README.

    plot.py RUN_DIR OUT.png     (RUN_DIR: fbsim's output directory, with bracket.pvd and bore_3.csv)
"""
import base64
import csv
import struct
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np
from mpl_toolkits.mplot3d.art3d import Poly3DCollection

TYPES = {"Float64": "<f8", "Float32": "<f4", "Int64": "<i8", "Int32": "<i4", "UInt8": "u1"}


def data_array(element):
    """A VTK XML DataArray written by flexbody (format/vtk_xml.hpp): base64 of a UInt64 byte count, then the data."""
    raw = base64.b64decode(element.text.strip())
    count = struct.unpack("<Q", raw[:8])[0]
    values = np.frombuffer(raw[8:8 + count], dtype=TYPES[element.get("type")])
    components = int(element.get("NumberOfComponents", "1"))
    return values.reshape(-1, components) if components > 1 else values


def read_vtu(path):
    """Points [m], point arrays by name, and triangles (0-based) of one .vtu frame."""
    piece = ET.parse(path).getroot().find(".//Piece")
    arrays = {a.get("Name"): data_array(a) for a in piece.find("PointData")}
    cells = {a.get("Name"): data_array(a) for a in piece.find("Cells")}
    return data_array(piece.find("Points/DataArray")), arrays, cells["connectivity"].reshape(-1, 3)


def frames(pvd):
    """(time [s], .vtu path) of a ParaView collection."""
    root = ET.parse(pvd).getroot()
    return [(float(d.get("timestep")), pvd.parent / d.get("file")) for d in root.iter("DataSet")]


def main():
    run, target = Path(sys.argv[1]), Path(sys.argv[2])
    series = frames(run / "bracket.pvd")
    # The most stressed frame: the one to look at.
    peaks = [(read_vtu(path)[1]["von_mises"].max(), t, path) for t, path in series]
    peak, t_peak, path = max(peaks)
    points, arrays, triangles = read_vtu(path)
    u = arrays["displacement"]
    size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    scale = 0.05 * size / max(np.linalg.norm(u, axis=1).max(), 1e-300)  # largest displacement drawn at 5 % of the size
    shown = points + (scale - 1.0) * u
    stress = arrays["von_mises"] / 1e6  # MPa

    fig = plt.figure(figsize=(10, 4.5), dpi=100)
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    faces = Poly3DCollection(shown[triangles], linewidths=0.0)
    colours = plt.get_cmap("viridis")(plt.Normalize(0.0, stress.max())(stress[triangles].mean(axis=1)))
    faces.set_facecolor(colours)
    ax.add_collection3d(faces)
    low, high = shown.min(axis=0), shown.max(axis=0)
    centre, half = 0.5 * (low + high), 0.5 * (high - low).max()
    for set_lim, c in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre):
        set_lim(c - half, c + half)
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=20, azim=-60)
    ax.set_axis_off()
    mappable = plt.cm.ScalarMappable(cmap="viridis", norm=plt.Normalize(0.0, stress.max()))
    fig.colorbar(mappable, ax=ax, shrink=0.7, label="von Mises stress [MPa]")
    ax.set_title(f"t = {t_peak:.2f} s, elastic displacement x {scale:.3g}", fontsize=10)

    with open(run / "bore_3.csv") as f:
        rows = list(csv.DictReader(f))
    columns = list(rows[0].keys())
    x_key = next(c for c in columns if c.startswith("position_x") or c.endswith("x [m]") or c == "x")
    y_key = next(c for c in columns if c.startswith("position_y") or c.endswith("y [m]") or c == "y")
    t_key = columns[0]
    t = np.array([float(r[t_key]) for r in rows])
    x = np.array([float(r[x_key]) for r in rows])
    y = np.array([float(r[y_key]) for r in rows])
    path_ax = fig.add_subplot(1, 2, 2)
    path_ax.plot(x, y, color="tab:blue", lw=1.2)
    path_ax.plot(x[0], y[0], "o", color="tab:green", label="start")
    path_ax.plot(x[-1], y[-1], "s", color="tab:red", label=f"t = {t[-1]:.2f} s")
    path_ax.set_aspect("equal", adjustable="datalim")
    path_ax.set_xlabel(f"{x_key}")
    path_ax.set_ylabel(f"{y_key}")
    path_ax.set_title("path of bore_3 (the pivot is bore_1)", fontsize=10)
    path_ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(target)
    print(f"wrote {target}: peak von Mises {peak / 1e6:.3g} MPa at t = {t_peak:.3g} s")


if __name__ == "__main__":
    main()

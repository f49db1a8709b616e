#!/usr/bin/python3
"""Read a flexbody body file with h5py: print its mass, frequencies and interfaces, and draw its first mode shapes.

    read_body.py BODY.fbh5 [OUT.png]     (OUT.png, default result.png: the first four modes over the surface)

Only names from formats/SCHEMA.md are used. Everything in the file is SI (m, kg, s) in the body frame, whose origin
is the centre of mass; /mass/center_of_mass_input takes a point back to the CAD's frame.
"""
import os
import sys

import h5py
import matplotlib
import numpy as np

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402 (after the backend is chosen)
from mpl_toolkits.mplot3d.art3d import Poly3DCollection  # noqa: E402

SHOWN = 4  # modes drawn


def text(value):
    """Fixed-length strings read as bytes (SCHEMA.md, "Conventions")."""
    return value.decode() if isinstance(value, bytes) else str(value)


def names(group):
    """The names a group's `order` attribute lists (interfaces, output regions), in the body spec's order."""
    order = text(group.attrs["order"])
    return order.split(",") if order else []


def main():
    path = sys.argv[1]
    target = sys.argv[2] if len(sys.argv) > 2 else "result.png"
    with h5py.File(path, "r") as f:  # h5py skips the 512-byte seal in front: it is an HDF5 user block
        if text(f.attrs["format"]) != "flexbody":
            raise SystemExit(f"{path}: not a flexbody body file")
        com = f["mass"].attrs["center_of_mass_input"]
        print(f"{path}: format version {f.attrs['format_version']}, made by {text(f.attrs['created_by'])} "
              f"from {text(f.attrs['source_file'])} (read in {text(f.attrs['input_unit'])})")
        material = f["material"].attrs
        print(f"material      {text(material['name'])}: E = {material['youngs_modulus']:.4g} Pa, "
              f"nu = {material['poisson_ratio']}, rho = {material['density']:.4g} kg/m^3")
        print(f"mass          {f['mass'].attrs['total']:.6g} kg, centre of mass {np.round(com, 6)} m (input frame)")
        print(f"inertia       about the centre of mass [kg m^2], diagonal {np.diag(f['mass/inertia_about_com'][...])}")

        nodes = f["mesh/nodes"][...]                        # (n_n, 3) m, body frame
        triangles = f["mesh/surface_triangles"][...]        # (n_t, 3) node indices
        print(f"mesh          {len(nodes)} nodes, {len(f['mesh/tets'])} tetrahedra of order "
              f"{f['mesh'].attrs['element_order']}, {len(triangles)} surface triangles")

        frequencies = f["reduction/frequencies_hz"][...]
        print(f"modes         {len(frequencies)} {text(f['reduction'].attrs['kind'])} modes [Hz]: "
              + ", ".join(f"{x:.1f}" for x in frequencies))
        if "fixed_interface_frequencies_hz" in f["reduction"] and len(f["reduction/fixed_interface_frequencies_hz"]):
            print("              with every rbe2 interface clamped [Hz]: "
                  + ", ".join(f"{x:.1f}" for x in f["reduction/fixed_interface_frequencies_hz"][...]))
        # upsilon[i, 3m + k] = component k of mode m at node i (kg^-1/2: mass-normalised modes).
        upsilon = f["reduction/upsilon"][...]

        for name in names(f["interfaces"]):
            g = f[f"interfaces/{name}"]
            point = 1e3 * (g.attrs["reference_point"] + com)  # input frame, mm
            print(f"interface     {name}: {text(g.attrs['coupling'])}, {len(g['nodes'])} nodes, "
                  f"centre [{point[0]:.2f}, {point[1]:.2f}, {point[2]:.2f}] mm (input frame)")
        if "recovery" in f:
            for name in names(f["recovery"]):
                print(f"output region {name}: {len(f[f'recovery/{name}/nodes'])} nodes with stress modes")
        if "geometric_stiffness" in f:
            cases = text(f["geometric_stiffness"].attrs["cases"]).split(",")
            print(f"prestress     {len(cases)} geometric stiffness cases: {', '.join(cases)}")

    # The first modes over the surface, each scaled so that its largest displacement is 8 % of the part's size.
    points = 1e3 * (nodes + com)  # mm, input frame
    size = np.linalg.norm(points.max(axis=0) - points.min(axis=0))
    shown = min(SHOWN, len(frequencies))
    fig = plt.figure(figsize=(8, 4.5), dpi=100)
    for m in range(shown):
        mode = upsilon[:, 3 * m:3 * m + 3]                 # (n_n, 3): node displacements in mode m
        length = np.linalg.norm(mode, axis=1)
        moved = points + mode * (0.08 * size / length.max())
        ax = fig.add_subplot(2, (shown + 1) // 2, m + 1, projection="3d")
        faces = Poly3DCollection(moved[triangles], linewidths=0.0)
        faces.set_facecolor(plt.get_cmap("viridis")(length[triangles].mean(axis=1) / length.max()))
        ax.add_collection3d(faces)
        low, high = points.min(axis=0) - 0.1 * size, points.max(axis=0) + 0.1 * size
        ax.set_xlim(low[0], high[0]), ax.set_ylim(low[1], high[1]), ax.set_zlim(low[2], high[2])
        ax.set_box_aspect(high - low, zoom=1.4)
        ax.view_init(elev=22, azim=-62)
        ax.set_axis_off()
        ax.set_title(f"mode {m + 1}: {frequencies[m]:.0f} Hz", fontsize=10, y=0.92)
    fig.suptitle(f"{os.path.basename(path)}: the first mode shapes, coloured by "
                 "displacement (yellow: largest)", fontsize=10)
    fig.subplots_adjust(left=0, right=1, bottom=0, top=0.92, wspace=0, hspace=0.05)
    fig.savefig(target, dpi=100)
    print(f"wrote {target}")


if __name__ == "__main__":
    main()

"""fuzz_body_files.py's constants, the seal (as formats/SCHEMA.md shows it) and the two base body files."""
import hashlib
import os
import subprocess
import sys

try:
    import h5py
except ImportError as error:  # ctest SKIP_RETURN_CODE
    print(f"fuzz_body_files.py: skipped: {error} (install python3-h5py)")
    sys.exit(77)


SKIP = 77
SEAL = 512
METADATA_BYTES = 4096
FAMILIES = ("sealed", "resealed", "checksummed", "semantic")
MUST, MAY = "must refuse", "may accept"
DAMAGED = "damaged or modified after it was written"

BOX_GEO = 'SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 0.1, 0.02, 0.02};\n'
BAR_SPEC = """input: box.geo
unit: m
mesh: {size: 0.02}
reduction: {modes: 2}
interfaces:
  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}
load_points:
  tip: {select: {plane: {point: [0.1, 0, 0], normal: [1, 0, 0]}}, loads: [fy]}
output_regions:
  near_root: {select: {box: {min: [-0.001, -1, -1], max: [0.021, 1, 1]}}}
  everything: {select: all}
"""
# Scenes: 10 steps that read every part of the body (all modes, interfaces, regions, stresses, ParaView frames).
SCENES = {
    "box": """bodies:
  box: {file: case.fbh5, modes: all, angular_velocity: [0, 0, 1]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-4, end: 1.0e-3}
outputs:
  region: {body: box, region: body, quantities: [displacement, stress]}
  modes: {body: box, quantities: [modal_coordinates]}
paraview: {bodies: [box], every: 5, stresses: true}
""",
    "bar": """bodies:
  bar: {file: case.fbh5, modes: all}
joints:
  pivot: {type: revolute, body: bar, interface: root, to: ground, axis: [0, 0, 1]}
forces:
  push: {body: bar, interface: tip, force: [0, -10, 0]}
gravity: [0, -9.81, 0]
integrator: {step: 1.0e-4, end: 1.0e-3}
outputs:
  tip: {body: bar, interface: tip, quantities: [position, orientation]}
  region: {body: bar, region: near_root, quantities: [displacement, stress]}
  modes: {body: bar, quantities: [modal_coordinates]}
paraview: {bodies: [bar], every: 5, stresses: true}
""",
}
BASES = ("box", "bar")


# ----------------------------------------------------------------------------------------------------------------
# The seal, exactly as formats/SCHEMA.md ("Seal") shows it


def reseal(path):
    with open(path, "r+b") as f:
        f.seek(512)
        hdf5 = f.read()
        text = (f"flexbody seal 1\nalgorithm sha256\nhdf5_bytes {len(hdf5)}\n"
                f"digest {hashlib.sha256(hdf5).hexdigest()}\n")
        f.seek(0)
        f.write(text.encode("ascii").ljust(512, b"\0"))


def seal_bytes(data):
    """`data` (a whole file) with its first 512 bytes replaced by the seal of the rest (reseal, in memory)."""
    hdf5 = data[SEAL:]
    text = (f"flexbody seal 1\nalgorithm sha256\nhdf5_bytes {len(hdf5)}\n"
            f"digest {hashlib.sha256(hdf5).hexdigest()}\n")
    return text.encode("ascii").ljust(512, b"\0") + hdf5


# ----------------------------------------------------------------------------------------------------------------
# Base files


def make_bases(fbprep, directory, timeout):
    """Writes box.fbh5 and bar.fbh5 with fbprep into `directory`; returns {name: path}."""
    os.makedirs(directory, exist_ok=True)
    with open(os.path.join(directory, "box.geo"), "w") as f:
        f.write(BOX_GEO)
    with open(os.path.join(directory, "bar.yaml"), "w") as f:
        f.write(BAR_SPEC)
    commands = {
        "box": [fbprep, "box.geo", "--unit", "m", "--mesh-size", "0.02", "--modes", "2", "-o", "box.fbh5", "--quiet"],
        "bar": [fbprep, "bar.yaml", "-o", "bar.fbh5", "--quiet"],
    }
    paths = {}
    for name, command in commands.items():
        run = subprocess.run(command, cwd=directory, capture_output=True, text=True, timeout=max(60, 10 * timeout))
        if run.returncode != 0:
            raise SystemExit(f"fuzz_body_files.py: fbprep could not make the base file {name}.fbh5: {run.stderr.strip()}")
        paths[name] = os.path.join(directory, name + ".fbh5")
    return paths


def raw_ranges(path):
    """Byte ranges [begin, end) of the contiguous raw data of every dataset of a body file: what is not in them
    (after the seal) is HDF5 metadata (superblock, object headers, B-trees, heaps) or free space."""
    ranges = []
    with h5py.File(path, "r") as f:
        def visit(_, obj):
            if isinstance(obj, h5py.Dataset) and obj.id.get_create_plist().get_layout() == h5py.h5d.CONTIGUOUS:
                offset, size = obj.id.get_offset(), obj.id.get_storage_size()
                if offset is not None and size:
                    ranges.append((offset, offset + size))
        f.visititems(visit)
    return sorted(ranges)


def metadata_ranges(path, size):
    ranges, at = [], SEAL
    for begin, end in raw_ranges(path):
        if begin > at:
            ranges.append((at, begin))
        at = max(at, end)
    if at < size:
        ranges.append((at, size))
    return ranges

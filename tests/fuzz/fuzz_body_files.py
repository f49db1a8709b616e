#!/usr/bin/python3
"""Fuzz run of flexbody body files through both entry points (issue 13).

Two small valid body files are made with fbprep (a box with its default whole-body region; the same box with
two rbe3 interfaces, a load point and two output regions), then copies of them are changed and each copy goes
through `fbprep inspect --json FILE` and through `fbsim SCENE` with a scene that loads it. Three families of
changes, each case reproducible from (family, seed, index) alone:

  sealed     byte-level changes of the sealed file (bit flips, zeroed or overwritten blocks, truncations, spliced
             bytes; half aimed at the first 4 KiB, a quarter at HDF5 metadata): the seal must refuse every one as
             damaged (exit code 2, "damaged or modified after it was written").
  resealed   the same changes after the 512-byte seal, then re-sealed with hashlib exactly as formats/SCHEMA.md
             shows: libhdf5 and the semantic checks see the damage. A file may be refused or accepted (a flipped
             bit in raw data can be a plausible value), but never with a signal, a hang, bad_alloc or more than
             one line.
  checksummed  byte-level changes inside HDF5's checksummed metadata (the version-2 superblock and object
             headers), with HDF5's lookup3 checksum and the seal recomputed: what an attacker who knows the format
             hands libhdf5 (a review crashed it in 3 of 300 such files). May be refused or accepted.
  semantic   edits with h5py, then re-sealed: deleted, reshaped and retyped datasets and attributes, NaN and Inf,
             asymmetric or indefinite G, K_hat with a negative eigenvalue, wrong format versions, strings for
             numbers, variable-length strings, huge declared dimensions, out-of-range indices, filters, external
             storage and links, soft-link loops, long strings with control characters, scaled stress modes...
             Each case is tagged "must refuse" (an acceptance is a silent acceptance) or "may accept", with the
             reason next to the mutator.

Forbidden outcomes (the script exits 1 if any occurs): a signal, a hang (the time limit), bad_alloc (or
length_error), a sanitizer report, a silent acceptance, stderr other than exactly one `TOOL: error:` line on a
refusal (fbsim may add its `fbsim: warning:` lines), a line from the HDF5 library, control characters on stderr,
anything on stderr when inspect accepts, stdout on a refusal, a line over --max-line bytes, and, for the sealed family, any answer but the seal's.

Requires Python 3 with numpy and h5py (Debian: python3-h5py); without h5py it exits with code 77 (ctest SKIP).
Run `fuzz_body_files.py --help` for the options; README.md ("Evidence", fuzz rows) gives the long run.
"""

import argparse
import collections
import concurrent.futures
import hashlib
import json
import multiprocessing
import os
import random
import re
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time

try:
    import h5py
    import numpy as np
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


# ----------------------------------------------------------------------------------------------------------------
# Families sealed and resealed: byte-level changes


def byte_mutation(good, meta, rng, index, floor):
    """A changed copy of `good` (never equal to it) at or after byte `floor`, and what was done. index % 4: 0 and
    2 aim at the first 4 KiB after `floor`, 1 at HDF5 metadata (outside the datasets' raw data), 3 anywhere."""
    size = len(good)
    aim = ("first 4 KiB", "metadata", "first 4 KiB", "anywhere")[index % 4]

    def position(span=1):
        """A position p with p + span <= size, aimed as above."""
        if aim == "first 4 KiB":
            return rng.randrange(floor, max(floor + 1, min(size - span + 1, floor + METADATA_BYTES)))
        if aim == "metadata":
            usable = [(b, min(e, size - span + 1)) for b, e in meta if min(e, size - span + 1) > b]
            if usable:
                total = sum(e - b for b, e in usable)
                k = rng.randrange(total)
                for b, e in usable:
                    if k < e - b:
                        return b + k
                    k -= e - b
        return rng.randrange(floor, size - span + 1)

    for _ in range(100):
        data = bytearray(good)
        kind = rng.choice(("bit flip", "bit flip", "zeroed block", "truncation", "random byte", "0xff x 8",
                           "random 8 bytes", "splice"))
        if kind == "bit flip":
            at, bit = position(), rng.randrange(8)
            data[at] ^= 1 << bit
            what = f"bit {bit} of byte {at} flipped"
        elif kind == "zeroed block":
            length = rng.choice((1, 4, 8, 16, 64))
            at = position(length)
            data[at:at + length] = bytes(length)
            what = f"bytes {at} to {at + length - 1} zeroed"
        elif kind == "truncation":
            length = max(position(), floor + 1)
            del data[length:]
            what = f"truncated to {length} bytes"
        elif kind == "random byte":
            at = position()
            data[at] = rng.randrange(256)
            what = f"byte {at} set to {data[at]}"
        elif kind == "0xff x 8":
            at = position(8)
            data[at:at + 8] = b"\xff" * 8
            what = f"bytes {at} to {at + 7} set to 0xff"
        elif kind == "random 8 bytes":  # e.g. an address or a length of HDF5's 8 bytes
            at = position(8)
            value = rng.choice((rng.getrandbits(64), rng.getrandbits(32), 1 << rng.randrange(64)))
            data[at:at + 8] = value.to_bytes(8, "little")
            what = f"bytes {at} to {at + 7} set to {value} (little-endian 64 bits)"
        else:  # splice: copy a block of the file over another place (a plausible-looking header or address)
            length = rng.choice((8, 16, 32, 64))
            at, source = position(length), rng.randrange(floor, size - length + 1)
            data[at:at + length] = good[source:source + length]
            what = f"bytes {source} to {source + length - 1} copied over bytes {at} to {at + length - 1}"
        if bytes(data) != good:
            return bytes(data), f"{kind} ({aim}): {what}"
    raise RuntimeError("no change found")


M = 0xFFFFFFFF
def _rot(x, k): return ((x << k) | (x >> (32 - k))) & M
def lookup3(data, initval=0):
    """Bob Jenkins' lookup3 hashlittle, as HDF5's H5_checksum_lookup3 (the checksum of its version-2 metadata)."""
    length = len(data)
    a = b = c = (0xdeadbeef + length + initval) & M
    i = 0
    while length > 12:
        a = (a + int.from_bytes(data[i:i + 4], "little")) & M
        b = (b + int.from_bytes(data[i + 4:i + 8], "little")) & M
        c = (c + int.from_bytes(data[i + 8:i + 12], "little")) & M
        a = (a - c) & M; a ^= _rot(c, 4); c = (c + b) & M
        b = (b - a) & M; b ^= _rot(a, 6); a = (a + c) & M
        c = (c - b) & M; c ^= _rot(b, 8); b = (b + a) & M
        a = (a - c) & M; a ^= _rot(c, 16); c = (c + b) & M
        b = (b - a) & M; b ^= _rot(a, 19); a = (a + c) & M
        c = (c - b) & M; c ^= _rot(b, 4); b = (b + a) & M
        length -= 12
        i += 12
    if length == 0:
        return c
    tail = bytes(data[i:i + length]) + bytes(12 - length)
    a = (a + int.from_bytes(tail[0:4], "little")) & M
    b = (b + int.from_bytes(tail[4:8], "little")) & M
    c = (c + int.from_bytes(tail[8:12], "little")) & M
    c ^= b; c = (c - _rot(b, 14)) & M
    a ^= c; a = (a - _rot(c, 11)) & M
    b ^= a; b = (b - _rot(a, 25)) & M
    c ^= b; c = (c - _rot(b, 16)) & M
    a ^= c; a = (a - _rot(c, 4)) & M
    b ^= a; b = (b - _rot(a, 14)) & M
    c ^= b; c = (c - _rot(b, 24)) & M
    return c


def checksummed_structures(data):
    """[(begin, end)] of the checksummed HDF5 metadata through which a change reaches the parser: the version-2
    superblock and every version-2 object header (each OHDR chunk 0 and the OCHK continuation chunks its
    continuation messages point to), each ending in its lookup3 checksum. Only structures whose stored checksum
    matches are listed (a signature found inside raw data is not one)."""
    base = SEAL
    if data[base:base + 8] != b"\x89HDF\r\n\x1a\n" or data[base + 8] not in (2, 3):
        return []
    out = [(base, base + 48)]

    def continuations(begin, end, flags):  # the (address, length) of every continuation message in a chunk
        pos = begin
        while pos + 4 <= end:
            kind, size = data[pos], int.from_bytes(data[pos + 1:pos + 3], "little")
            pos += 4 + (2 if flags & 0x04 else 0)
            if kind == 0x10 and size >= 16:
                yield int.from_bytes(data[pos:pos + 8], "little"), int.from_bytes(data[pos + 8:pos + 16], "little")
            pos += size

    for match in re.finditer(b"OHDR", data):
        at = match.start()
        flags, pos = data[at + 5], at + 6
        pos += (16 if flags & 0x20 else 0) + (4 if flags & 0x10 else 0)
        n = 1 << (flags & 3)
        size = int.from_bytes(data[pos:pos + n], "little")
        pos += n
        chunks = [(at, pos + size + 4, pos, pos + size)]
        for _, _, messages_begin, messages_end in chunks:  # grows while continuation chunks are found
            for address, length in continuations(messages_begin, messages_end, flags):
                c0 = base + address
                if data[c0:c0 + 4] == b"OCHK" and 8 <= length and c0 + length <= len(data):
                    chunks.append((c0, c0 + length, c0 + 4, c0 + length - 4))
        for begin, end, _, _ in chunks:
            if end <= len(data) and lookup3(data[begin:end - 4]) == int.from_bytes(data[end - 4:end], "little"):
                out.append((begin, end))
    return sorted(set(out))


def checksummed_mutation(good, structures, rng):
    """A change inside one checksummed structure (after its signature), its lookup3 checksum recomputed, the
    seal recomputed: what an attacker who knows the format can hand libhdf5."""
    for _ in range(100):
        begin, end = rng.choice(structures)
        data = bytearray(good)
        lo, hi = begin + 4, end - 4  # keep the signature, then the checksum is written anew
        kind = rng.choice(("bit flip", "bit flip", "random byte", "zeroed bytes", "0xff x 8", "random 8 bytes",
                           "small integer"))
        if kind == "bit flip":
            at, bit = rng.randrange(lo, hi), rng.randrange(8)
            data[at] ^= 1 << bit
            what = f"bit {bit} of byte {at}"
        elif kind == "random byte":
            at = rng.randrange(lo, hi)
            data[at] = rng.randrange(256)
            what = f"byte {at} = {data[at]}"
        elif kind == "zeroed bytes":
            length = min(rng.choice((1, 2, 4, 8)), hi - lo)
            at = rng.randrange(lo, hi - length + 1)
            data[at:at + length] = bytes(length)
            what = f"bytes {at} to {at + length - 1} zeroed"
        else:
            length = min(8 if kind != "small integer" else rng.choice((1, 2, 4)), hi - lo)
            at = rng.randrange(lo, hi - length + 1)
            value = {"0xff x 8": (1 << (8 * length)) - 1, "random 8 bytes": rng.getrandbits(8 * length),
                     "small integer": rng.choice((0, 1, 2, 3, 7, 8, 255, 256, 65535))}[kind] % (1 << (8 * length))
            data[at:at + length] = value.to_bytes(length, "little")
            what = f"bytes {at} to {at + length - 1} = {value}"
        data[end - 4:end] = lookup3(bytes(data[begin:end - 4])).to_bytes(4, "little")
        if bytes(data) != good:
            sig = bytes(good[begin:begin + 4]).decode("latin-1")
            sig = "superblock" if sig.startswith("\x89HD") else sig
            return seal_bytes(bytes(data)), f"{kind} in {sig} at {begin}..{end}: {what}, checksum recomputed"
    raise RuntimeError("no change found")


# ----------------------------------------------------------------------------------------------------------------
# Family semantic: edits with h5py, then re-sealed. Each mutator edits the h5py file `f` (opened r+) and returns
# (description, tag, reason); ctx has rng (random.Random), variant() (the main choice, below), work (the case's directory), good (path of an
# unchanged copy beside the case, for links and external storage), path (the case's file).

MUTATORS = []


def mutator(name):
    def register(fn):
        MUTATORS.append((name, fn))
        return fn
    return register


def fixed(value):
    """A fixed-length, NUL-padded string (as fbprep writes them)."""
    data = value.encode("utf-8", "surrogateescape") if isinstance(value, str) else value
    return np.array(data, dtype=f"S{max(1, len(data))}")


def set_attr(obj, name, value, dtype=None):
    if name in obj.attrs:
        del obj.attrs[name]
    if dtype is None:
        obj.attrs[name] = value
    else:
        obj.attrs.create(name, value, dtype=dtype)


def where(obj, name):
    """SCHEMA.md's notation of attribute `name` of object `obj` ("/a" for a root attribute)."""
    return f"/{obj.strip('/')}/{name}" if obj.strip("/") else f"/{name}"


def vlen(value):
    return value, h5py.string_dtype("utf-8")


def attr_type_of(obj, name):
    return h5py.h5a.open(obj.id, name.encode()).get_type()


def replace_dataset(f, path, data=None, **kw):
    """Deletes dataset `path` and creates it again from `data` (or shape/dtype in kw) with creation options kw,
    keeping its attributes (with their exact types)."""
    old = f[path]
    attrs = [(k, old.attrs[k], attr_type_of(old, k)) for k in old.attrs]
    del f[path]
    new = f.create_dataset(path, data=data, **kw)
    for k, v, t in attrs:
        new.attrs.create(k, v, dtype=t.dtype)
    return new


def float_datasets(f):
    out = []
    f.visititems(lambda n, o: out.append(n) if isinstance(o, h5py.Dataset) and o.dtype.kind == "f" and o.size else None)
    return sorted(out)


REQUIRED_DATASETS = ["mesh/nodes", "mesh/tets", "mesh/surface_triangles", "mass/inertia_about_com",
                     "reduction/frequencies_hz", "reduction/relative_residuals", "reduction/upsilon", "gcms/fields",
                     "gcms/field_mode", "gcms/mode_coefficients", "gcms/G", "gcms/K_hat", "interfaces/root/nodes",
                     "interfaces/root/weights", "interfaces/root/y_row", "interfaces/root/rotation",
                     "interfaces/tip/nodes", "recovery/near_root/nodes", "recovery/near_root/stress_modes",
                     "recovery/everything/stress_modes"]
REQUIRED_ATTRS = [("/", "format"), ("/", "format_version"), ("/", "length_unit"), ("/", "mass_unit"),
                  ("/", "time_unit"), ("/", "created_by"), ("/", "created_utc"), ("/", "source_file"),
                  ("/", "source_sha256"), ("/", "input_unit"), ("/", "unit_reason"), ("provenance/options", "order"),
                  ("provenance/options", "modes"), ("provenance/options", "spec"), ("material", "name"),
                  ("material", "youngs_modulus"), ("material", "poisson_ratio"), ("material", "density"),
                  ("mass", "total"), ("mass", "center_of_mass_input"), ("mesh", "element_order"),
                  ("reduction", "kind"), ("reduction", "eigensolver"), ("reduction", "shift"),
                  ("reduction", "static_loads"),  # static_correction_modes is 1: absent = no loads, refused
                  ("gcms", "drop_tolerance"), ("gcms", "dropped_fields"), ("gcms", "condition_mode_gram_before"),
                  ("gcms", "condition_G_before"), ("gcms", "condition_G_after"), ("gcms", "condition_G_scaled_after"),
                  ("interfaces", "order"), ("interfaces/root", "coupling"), ("interfaces/root", "reference_point"),
                  ("recovery", "order"), ("recovery", "stress_components")]
OPTIONAL = [("attr", "/", "declared_unit"), ("dataset", "reduction/fixed_interface_frequencies_hz", None),
            ("attr", "gcms", "condition_G_scaled_before"), ("attr", "mesh/nodes", "unit"),
            ("attr", "gcms/G", "unit"), ("attr", "reduction/upsilon", "unit"), ("group", "recovery", None)]
F64_ATTRS = [("material", "youngs_modulus"), ("material", "poisson_ratio"), ("material", "density"),
             ("mass", "total"), ("mass", "center_of_mass_input"), ("reduction", "shift"), ("gcms", "drop_tolerance"),
             ("gcms", "condition_mode_gram_before"), ("gcms", "condition_G_scaled_after"),
             ("interfaces/root", "reference_point"), ("interfaces/tip", "reference_point")]
INF_ALLOWED = [("gcms", "condition_G_before"), ("gcms", "condition_G_after"), ("gcms", "condition_G_scaled_before")]


@mutator("delete required dataset")
def _(f, c):
    path = c.variant(REQUIRED_DATASETS)
    del f[path]
    return f"/{path} deleted", MUST, "SCHEMA.md Layout: required"


@mutator("delete required attribute")
def _(f, c):
    obj, name = c.variant(REQUIRED_ATTRS)
    del f[obj].attrs[name]
    return f"{where(obj, name)} deleted", MUST, "SCHEMA.md Layout: required"


@mutator("delete required group")
def _(f, c):
    path = c.variant(["mesh", "mass", "material", "gcms", "reduction", "interfaces", "provenance",
                         "provenance/options", "interfaces/root", "interfaces/tip", "recovery/near_root"])
    del f[path]
    return f"/{path} deleted", MUST, "SCHEMA.md Layout: required (or named in an order attribute)"


@mutator("delete optional item")
def _(f, c):
    kind, obj, name = c.variant(OPTIONAL)
    if kind == "attr":
        del f[obj].attrs[name]
        what = f"attribute {name} of /{obj.strip('/')} deleted"
    else:
        del f[obj]
        what = f"/{obj} deleted"
    return what, MAY, "optional in SCHEMA.md (absent = a default); fbsim may refuse the scene naming it"


@mutator("non-finite value in a dataset")
def _(f, c):
    path = c.variant(float_datasets(f))
    data = f[path][()]
    flat = data.reshape(-1)
    at = c.rng.randrange(flat.size)
    flat[at] = c.rng.choice((np.nan, np.inf, -np.inf))
    f[path][...] = data
    return f"/{path} flat entry {at} = {flat[at]}", MUST, "Validity: every floating-point value is finite"


@mutator("non-finite value in an attribute")
def _(f, c):
    obj, name = c.variant(F64_ATTRS + INF_ALLOWED)
    value = np.array(f[obj].attrs[name], dtype="<f8")
    bad = c.rng.choice((np.nan, np.inf, -np.inf))
    if value.ndim:
        value[c.rng.randrange(value.size)] = bad
    else:
        value = np.float64(bad)
    set_attr(f[obj], name, value)
    if (obj, name) in INF_ALLOWED and bad == np.inf:
        return f"{where(obj, name)} = inf", MAY, "Validity: the *_before condition numbers and condition_G_after may be inf"
    return f"{where(obj, name)} holds {bad}", MUST, "Validity: finite (condition numbers: inf at most, never NaN or -inf)"


@mutator("asymmetric G")
def _(f, c):
    G = f["gcms/G"][()]
    n = G.shape[0]
    r, k = c.rng.sample(range(n), 2)
    G[r, k] += 1e-6 * np.sqrt(G[r, r] * G[k, k])
    f["gcms/G"][...] = G
    return f"G[{r}][{k}] += 1e-6 sqrt(G_rr G_cc)", MUST, "Validity: G symmetric to 1e-12 sqrt(G_rr G_cc)"


@mutator("indefinite G")
def _(f, c):
    G = f["gcms/G"][()]
    n = G.shape[0]
    variant = c.variant(3)
    if variant == 0:
        i = c.rng.randrange(n)
        G[i, i] = -abs(G[i, i])
        what = f"G[{i}][{i}] negated"
    elif variant == 1:
        i, j = c.rng.sample(range(4, n), 2)
        G[i, j] = G[j, i] = 1.5
        what = f"G[{i}][{j}] = G[{j}][{i}] = 1.5 (field block indefinite)"
    else:  # indefinite with every check of the diagonal blocks intact except definiteness: a rigid-field coupling
        i, j = c.rng.randrange(1, 4), c.rng.randrange(4, n)
        G[i, j] = G[j, i] = 2 * np.sqrt(G[i, i] * G[j, j])
        what = f"G[{i}][{j}] = G[{j}][{i}] = 2 sqrt(G_ii G_jj) (indefinite, positive diagonal)"
    f["gcms/G"][...] = G
    return what, MUST, "Validity: G positive definite, G[4:][4:] = I"


@mutator("G or mass properties disagree")
def _(f, c):
    variant = c.variant(3)
    if variant == 0:
        f["gcms/G"][...] = f["gcms/G"][()] * 1.001
        return "G *= 1.001", MUST, "Validity: G[0][0] = /mass/total and G[4:][4:] = I"
    if variant == 1:
        set_attr(f["mass"], "total", np.float64(f["mass"].attrs["total"] * (1 + 1e-6)))
        return "/mass/total *= 1 + 1e-6", MUST, "Validity: G[0][0] = /mass/total to 1e-9"
    J = f["mass/inertia_about_com"][()]
    J[0, 0] *= 1 + 1e-6
    f["mass/inertia_about_com"][...] = J
    return "inertia_about_com[0][0] *= 1 + 1e-6", MUST, "Validity: tr(J) I - J = inertia to 1e-9"


@mutator("K_hat not positive semi-definite or asymmetric")
def _(f, c):
    K = f["gcms/K_hat"][()]
    variant = c.variant(3)
    if variant == 0:
        w, V = np.linalg.eigh(K)
        w[0] = -1e-3 * w[-1]
        K = (V * w) @ V.T
        K = (K + K.T) / 2
        what, reason = "smallest eigenvalue of K_hat set to -1e-3 of the largest", "Validity: K_hat PSD"
    elif variant == 1:
        K = -K
        what, reason = "K_hat negated", "Validity: K_hat PSD"
    else:
        r, k = c.rng.sample(range(K.shape[0]), 2)
        K[r, k] += 1e-9 * np.abs(K).max()
        what, reason = f"K_hat[{r}][{k}] += 1e-9 max|K_hat|", "Validity: K_hat symmetric to 1e-12 of its largest entry"
    f["gcms/K_hat"][...] = K
    return what, MUST, reason


@mutator("format_version value")
def _(f, c):
    value = c.rng.choice((0, 1, 2, 5, 99, -1, 2**31 - 1, -2**31))
    set_attr(f, "format_version", np.int32(value))
    return f"/format_version = {value}", MUST, "Versioning: other versions are refused"


@mutator("format_version type")
def _(f, c):
    variants = [
        ("int64 4", np.int64(4), MAY, "the right value in a wider integer type"),
        ("uint8 4", np.uint8(4), MAY, "the right value in a narrower integer type"),
        ("int64 2^32 + 4", np.int64(2**32 + 4), MUST, "not 4 (4 only after truncation to 32 bits)"),
        ("float64 4.0", np.float64(4.0), MAY, "the right value, exactly, as a double"),
        ("float64 4.5", np.float64(4.5), MUST, "not an integer (4 only after truncation)"),
        ("fixed string '4'", fixed("4"), MUST, "format_version is an integer"),
        ("variable-length string '4'", "4", MUST, "format_version is an integer"),
        ("int32 array [4, 4]", np.array([4, 4], dtype="<i4"), MUST, "a scalar"),
        ("int32 array [4]", np.array([4], dtype="<i4"), MAY, "one element, the right value"),
        ("empty (null dataspace)", h5py.Empty("<i4"), MUST, "no value"),
        ("big-endian int32 4", np.array(4, dtype=">i4"), MAY, "the right value, HDF5 converts the byte order"),
        ("int32 3 (version 3 inside a seal)", np.int32(3), MAY,
         "version-3 content is readable; whether a sealed file may say 3 is the reader's choice"),
    ]
    what, value, tag, reason = c.variant(variants)
    set_attr(f, "format_version", value)
    return f"/format_version as {what}", tag, reason


@mutator("string for a number")
def _(f, c):
    obj, name = c.variant(F64_ATTRS + INF_ALLOWED + [("gcms", "dropped_fields"), ("mesh", "element_order"),
                                                       ("reduction", "static_correction_modes")])
    value = f[obj].attrs[name]
    text = " ".join(repr(float(v)) for v in np.ravel(value)) if np.ndim(value) else repr(value.item())
    if c.rng.random() < 0.5:
        set_attr(f[obj], name, fixed(text))
        how = "fixed-length"
    else:
        set_attr(f[obj], name, *vlen(text))
        how = "variable-length"
    return f"{where(obj, name)} = {how} string '{text}'", MUST, "SCHEMA.md Types: f64 / i32, not text"


@mutator("number for a string")
def _(f, c):
    obj, name, value = c.variant([("/", "format", np.float64(1.0)), ("/", "length_unit", np.int32(1)),
                                     ("material", "name", np.int32(7)), ("reduction", "kind", np.int32(0)),
                                     ("interfaces", "order", np.int32(0)), ("recovery", "stress_components", np.float64(6)),
                                     ("interfaces/root", "coupling", np.int32(3))])
    set_attr(f[obj], name, value)
    return f"{where(obj, name)} = {value!r}", MUST, "SCHEMA.md Types: str, a fixed set of values"


@mutator("strings for a dataset")
def _(f, c):
    path = c.variant(["reduction/frequencies_hz", "mesh/nodes", "gcms/field_mode", "interfaces/root/weights"])
    data = f[path][()]
    text = np.array([repr(v).encode() for v in data.reshape(-1)]).reshape(data.shape)
    replace_dataset(f, path, data=text)
    return f"/{path} as fixed-length strings of its values", MUST, "SCHEMA.md Types: f64 / i32, not text"


@mutator("retyped dataset")
def _(f, c):
    variants = [
        ("mesh/nodes", lambda d: d.astype("<f4"), MAY, "HDF5 converts float32 to double; the checks at 1e-12 of "
         "the part's size may refuse the rounded nodes"),
        ("mesh/nodes", lambda d: d.astype(">f8"), MAY, "the same doubles, big-endian: HDF5 converts them exactly"),
        ("mesh/tets", lambda d: d.astype("<i8"), MAY, "the same indices in a wider integer type"),
        ("mesh/tets", lambda d: d.astype("<i2"), MAY, "the same indices (all < 32768) in a narrower type"),
        ("mesh/tets", lambda d: d.astype("<f8"), MAY, "the same indices as exact doubles"),
        ("mesh/tets", lambda d: d.astype("<f8") + 0.5, MUST, "indices that are not integers (HDF5 would truncate)"),
        ("mesh/tets", lambda d: np.where(d == d.max(), 2**32 - 1, d).astype("<u4"), MUST,
         "an index of 2^32 - 1 (out of range; HDF5 clips it to int32)"),
        ("gcms/G", lambda d: d.astype("<f4"), MUST, "float32 rounding breaks G[0][0] = mass (1e-9)"),
        ("gcms/field_mode", lambda d: d.astype("<f8"), MAY, "the same indices as exact doubles"),
        ("gcms/K_hat", lambda d: d.astype("<f2"), MUST, "float16 overflows K_hat's entries (~1e12) to inf"),
        ("reduction/upsilon", lambda d: d.astype("<f2"), MAY,
         "float16 rounding of the modes; nothing in Validity ties them to the fields (a gap if accepted)"),
        ("interfaces/root/nodes", lambda d: d.astype("<i8"), MAY, "the same indices in a wider integer type"),
        ("mesh/nodes", lambda d: np.array([tuple(r) for r in d], dtype=[("x", "<f8"), ("y", "<f8"), ("z", "<f8")]),
         MUST, "a compound type, not f64 (n_n, 3)"),
        ("gcms/G", lambda d: d.astype("<c16"), MUST, "complex numbers, not f64"),
    ]
    path, convert, tag, reason = c.variant(variants)
    data = convert(f[path][()])
    replace_dataset(f, path, data=data)
    return f"/{path} stored as {data.dtype}", tag, reason


@mutator("reshaped dataset")
def _(f, c):
    def pad(d):
        return np.hstack([d, np.zeros((d.shape[0], 1), d.dtype)])
    variants = [
        ("mesh/nodes", pad, MUST), ("mesh/nodes", lambda d: d[:, :2], MUST), ("mesh/nodes", lambda d: d.reshape(-1), MUST),
        ("mesh/nodes", lambda d: d.T.copy(), MUST), ("mesh/nodes", lambda d: d[:0], MUST),
        ("mesh/nodes", lambda d: d[:3], MUST), ("mesh/nodes", lambda d: d[0, 0], MUST),
        ("mesh/tets", lambda d: d[:, :3], MUST), ("mesh/tets", lambda d: d[:0], MUST),
        ("mesh/surface_triangles", lambda d: d[:, :2], MUST),
        ("mesh/surface_triangles", lambda d: d[:0], MAY),  # n_t >= 0; fbsim's stresses need surface nodes
        ("reduction/upsilon", lambda d: d[:, :-1], MUST), ("reduction/frequencies_hz", lambda d: d[:-1], MUST),
        ("reduction/relative_residuals", lambda d: np.append(d, 0.0), MUST),
        ("gcms/G", lambda d: d[:-1, :-1], MUST), ("gcms/K_hat", lambda d: d[:-1, :-1], MUST),
        ("gcms/K_hat", lambda d: d[:, :-1], MUST), ("gcms/field_mode", lambda d: np.append(d, d[-1]), MUST),
        ("gcms/mode_coefficients", lambda d: d[:-1], MUST), ("gcms/fields", lambda d: d[:, :-1], MUST),
        ("mass/inertia_about_com", lambda d: d.reshape(-1), MUST), ("interfaces/root/y_row", lambda d: np.append(d, 0.0), MUST),
        ("interfaces/root/rotation", pad, MUST), ("interfaces/root/weights", lambda d: d[:-1], MUST),
        ("recovery/near_root/stress_modes", lambda d: d[:-6], MUST),
        ("recovery/everything/stress_modes", pad, MUST),
    ]
    path, reshape, tag = c.variant(variants)
    old = f[path].shape
    data = np.asarray(reshape(f[path][()]))
    replace_dataset(f, path, data=data)
    return f"/{path} {old} -> {data.shape}", tag, ("Validity: shapes agree" if tag == MUST else
                                                   "n_t >= 0 is valid (fbsim may refuse ParaView stresses)")


@mutator("reshaped attribute")
def _(f, c):
    variants = [
        ("mass", "center_of_mass_input", lambda v: v[:2]), ("mass", "center_of_mass_input", lambda v: np.append(v, 0.0)),
        ("mass", "center_of_mass_input", lambda v: np.float64(v[0])), ("interfaces/root", "reference_point", lambda v: v[:2]),
        ("mass", "total", lambda v: np.array([v, v])), ("material", "density", lambda v: np.array([], dtype="<f8")),
        ("mesh", "element_order", lambda v: np.array([1, 1], dtype="<i4")),
    ]
    obj, name, reshape = c.variant(variants)
    value = reshape(f[obj].attrs[name])
    set_attr(f[obj], name, value)
    return f"{where(obj, name)} of shape {np.shape(value)}", MUST, "Validity: 3 values / scalar"


@mutator("huge declared dimensions")
def _(f, c):
    variants = [
        ("mesh/nodes", (10**8, 3), "<f8", {}),  # contiguous, storage never allocated (h5py's default: late)
        ("mesh/nodes", (10**8, 3), "<f8", {"chunks": (4096, 3)}),
        ("mesh/nodes", (10**8, 3), "<f8", {"chunks": (4096, 3), "fillvalue": 0.01}),
        ("mesh/tets", (2**31 - 1, 4), "<i4", {"chunks": (4096, 4)}),
        ("gcms/G", (10**5, 10**5), "<f8", {"chunks": (64, 64)}),
        ("recovery/everything/stress_modes", (10**7, 27), "<f8", {"chunks": (1024, 27)}),
        ("reduction/upsilon", (110, 2**40), "<f8", {"chunks": (110, 1024)}),
        ("interfaces/root/nodes", (10**9,), "<i4", {"chunks": (4096,), "maxshape": (None,)}),
        ("mesh/nodes", (2**62, 3), "<f8", {"chunks": (4096, 3), "maxshape": (None, 3)}),
    ]
    path, shape, dtype, kw = c.variant(variants)
    replace_dataset(f, path, shape=shape, dtype=dtype, **kw)
    return f"/{path} declared {shape} {dtype} {kw or 'contiguous'}, nothing written", MUST, \
        "Validity: declared size checked against the file before anything is allocated"


@mutator("huge declared dimensions, compressed data")
def _(f, c):
    rows = c.rng.choice((10**5, 10**6))
    replace_dataset(f, "mesh/nodes", data=np.zeros((rows, 3)), chunks=(65536 if rows > 65536 else rows, 3),
                    compression="gzip", compression_opts=9)
    return f"/mesh/nodes ({rows}, 3) of zeros, gzip (a small file that inflates)", MUST, \
        "Validity: n_n disagrees with every other dataset (and the declared size exceeds the file)"


def index_datasets(f):
    n_n, n_m = f["mesh/nodes"].shape[0], f["reduction/frequencies_hz"].shape[0]
    return n_n, n_m, [("mesh/tets", n_n), ("mesh/surface_triangles", n_n), ("gcms/field_mode", n_m),
                      ("interfaces/root/nodes", n_n), ("interfaces/tip/nodes", n_n), ("recovery/near_root/nodes", n_n),
                      ("recovery/everything/nodes", n_n)]


@mutator("index out of range")
def _(f, c):
    n_n, n_m, datasets = index_datasets(f)
    path, limit = c.rng.choice(datasets)
    data = f[path][()]
    flat = data.reshape(-1)
    bad = c.rng.choice((limit, limit + 1000, -1, 2**31 - 1, -2**31))
    if data.ndim == 1 and bad >= limit:
        at = flat.size - 1  # the last entry: sorted lists stay ascending
    elif data.ndim == 1:
        at = 0
    else:
        at = c.rng.randrange(flat.size)
    flat[at] = bad
    f[path][...] = data
    return f"/{path} flat entry {at} = {bad} (range [0, {limit}))", MUST, "Validity: every index in range"


@mutator("node lists and weights")
def _(f, c):
    variants = ["unsorted", "duplicate", "weights sum", "negative weight", "field_mode decreasing",
                "four fields of one mode", "degenerate tetrahedron", "reference point moved", "y_row[0]", "y_row point"]
    v = c.variant(variants)
    if v in ("unsorted", "duplicate"):
        path = c.rng.choice(["interfaces/root/nodes", "recovery/near_root/nodes"])
        d = f[path][()]
        if v == "unsorted":
            d[0], d[1] = d[1], d[0]
        else:
            d[1] = d[0]
        f[path][...] = d
        return f"/{path}: {v} entries", MUST, "Validity: node lists ascending and unique"
    if v in ("weights sum", "negative weight"):
        d = f["interfaces/root/weights"][()]
        if v == "weights sum":
            d *= 1.001
        else:
            d[0] = -d[0]
        f["interfaces/root/weights"][...] = d
        return f"/interfaces/root/weights: {v}", MUST, "Validity: weights positive, summing to 1 (1e-12)"
    if v in ("field_mode decreasing", "four fields of one mode"):
        d = f["gcms/field_mode"][()]
        if v == "field_mode decreasing":
            d[0], d[-1] = d[-1], d[0]
        else:
            d[:4] = 0
        f["gcms/field_mode"][...] = d
        return f"/gcms/field_mode: {v}", MUST, "Validity: non-decreasing, at most 3 fields per mode"
    if v == "degenerate tetrahedron":
        d = f["mesh/tets"][()]
        i = c.rng.randrange(d.shape[0])
        d[i, 3] = d[i, 0]
        f["mesh/tets"][...] = d
        return f"tetrahedron {i}: node 3 = node 0 (zero volume)", MUST, \
            "Validity: every tetrahedron of non-zero volume (stress bound)"
    if v == "reference point moved":
        p = f["interfaces/root"].attrs["reference_point"].copy()
        p[c.rng.randrange(3)] += 1e-6
        set_attr(f["interfaces/root"], "reference_point", p)
        return "/interfaces/root/reference_point moved by 1e-6 m", MUST, \
            "Validity: the weighted node average to 1e-12 of the part's size"
    d = f["interfaces/root/y_row"][()]
    if v == "y_row[0]":
        d[0] = 1.001
    else:
        d[1] += 1e-6
    f["interfaces/root/y_row"][...] = d
    return f"/interfaces/root/y_row: {v} changed", MUST, "Validity: y_row starts with 1 and the reference point"


@mutator("value out of its range")
def _(f, c):
    variants = [
        ("material", "poisson_ratio", np.float64(0.5)), ("material", "poisson_ratio", np.float64(-1.0)),
        ("material", "youngs_modulus", np.float64(0.0)), ("material", "youngs_modulus", np.float64(-2.1e11)),
        ("material", "density", np.float64(-7850.0)), ("mass", "total", np.float64(0.0)),
        ("gcms", "drop_tolerance", np.float64(1.0)), ("gcms", "condition_G_scaled_after", np.float64(0.5)),
        ("gcms", "dropped_fields", np.int32(1)), ("mesh", "element_order", np.int32(2)),
        ("reduction", "static_correction_modes", np.int32(5)), ("reduction", "static_correction_modes", np.int32(-1)),
        ("/", "length_unit", fixed("mm")), ("/", "time_unit", fixed("ms")), ("/", "mass_unit", fixed("g")),
        ("/", "format", fixed("flexbodz")), ("recovery", "stress_components", fixed("xx,yy,zz,xy,yz,xz")),
        ("reduction", "kind", fixed("guyan")), ("reduction", "kind", fixed("craig-bampton")),
        ("interfaces", "order", fixed("root,tip,nope")), ("interfaces", "order", fixed("root,root,tip")),
        ("recovery", "order", fixed("near_root,body")),
        ("provenance/options", "order", fixed("spec,input,unit,nope")),
    ]
    obj, name, value = c.variant(variants)
    set_attr(f[obj], name, value)
    shown = value.item().decode() if value.dtype.kind == "S" else value.item()
    return f"{where(obj, name)} = {shown!r}", MUST, "Validity: the table's ranges and values"


@mutator("dataset value out of its range")
def _(f, c):
    v = c.variant(4)
    d = f["reduction/frequencies_hz"][()]
    if v == 0:
        d[0], d[1] = d[1], d[0]
        what = "frequencies_hz not ascending"
    elif v == 1:
        d[0] = -d[0]
        what = "frequencies_hz[0] negative"
    elif v == 2:
        d[0] = 0.0
        what = "frequencies_hz[0] = 0"
    else:
        r = f["reduction/relative_residuals"][()]
        r[0] = -1e-12
        f["reduction/relative_residuals"][...] = r
        return "relative_residuals[0] = -1e-12", MUST, "Validity: residuals >= 0"
    f["reduction/frequencies_hz"][...] = d
    return what, MUST, "Validity: frequencies > 0, ascending"


@mutator("informative text changed")
def _(f, c):
    variants = [("material", "name", "unobtainium"), ("reduction", "eigensolver", "lapack"),
                ("interfaces/root", "coupling", "rbe2"), ("interfaces/root", "coupling", "weld"),
                ("/", "created_by", "someone else"), ("/", "source_sha256", "0" * 63)]
    obj, name, value = c.variant(variants)
    set_attr(f[obj], name, fixed(value))
    return f"{where(obj, name)} = '{value}'", MAY, \
        "the table lists values, but Validity does not check this one (rbe2 on free-free modes: fbprep's rule)"


CONTROL = "line one\nHDF5-DIAG: a fake library line\r\x1b[31mred\x1b[0m\ttab\x07\x08\x7f \u202e\u0000end"


@mutator("long text with control characters")
def _(f, c):
    length = c.rng.choice((1000, 70000, 200000))
    text = (CONTROL * (length // len(CONTROL) + 1))[:length]
    normative = c.rng.random() < 0.5
    if normative:
        obj, name = c.rng.choice([("/", "length_unit"), ("/", "format"), ("material", "name"), ("reduction", "kind"),
                                  ("interfaces", "order"), ("recovery", "order"), ("interfaces/root", "coupling"),
                                  ("provenance/options", "order")])
    else:
        obj, name = c.rng.choice([("/", "unit_reason"), ("/", "created_by"), ("/", "source_file"),
                                  ("provenance/options", "spec"), ("mesh/nodes", "unit")])
    if length < 60000 and c.rng.random() < 0.5:  # fixed-length (an object header holds at most 64 KiB)
        set_attr(f[obj], name, fixed(text.replace("\0", " ")))
        how = "fixed-length"
    else:
        set_attr(f[obj], name, *vlen(text.replace("\0", " ")))
        how = "variable-length"
    place = where(obj, name)
    if normative:
        return f"{place} = {how} {length} characters with control characters", MUST, \
            "Validity: a fixed value; the message must stay one line"
    return f"{place} = {how} {length} characters with control characters", MAY, \
        "informative text; stdout may show it, stderr stays empty"


@mutator("odd bytes in a string")
def _(f, c):
    variants = [("/", "length_unit", b"m\0junk", MAY, "NUL-padded fixed-length text ends at the first NUL"),
                ("/", "length_unit", b"\xff\xfe", MUST, "not a unit"),
                ("/", "source_file", b"\xff\xfe\xc0\x80 not utf-8", MAY, "informative text"),
                ("/", "format", b"flexbody\0", MAY, "NUL-padded fixed-length text ends at the first NUL"),
                ("/", "format", b"flexbody ", MUST, "not \"flexbody\" (space-padded)"),
                ("/", "format", b"", MUST, "empty")]
    obj, name, value, tag, reason = c.variant(variants)
    set_attr(f[obj], name, np.array(value, dtype=f"S{max(1, len(value))}"))
    return f"{where(obj, name)} = {value!r} fixed-length", tag, reason


@mutator("variable-length strings")
def _(f, c):
    names = []

    def visit(obj):
        for k in obj.attrs:
            if attr_type_of(obj, k).get_class() == h5py.h5t.STRING:
                names.append((obj, k))
    visit(f)
    f.visititems(lambda _, o: visit(o))
    chosen = names if c.rng.random() < 0.3 else c.rng.sample(names, 3)
    for obj, k in chosen:
        set_attr(obj, k, *vlen(obj.attrs[k].decode()))
    return f"{len(chosen)} string attributes rewritten variable-length (same text)", MAY, \
        "SCHEMA.md Types: readers also accept variable-length strings (version 3); refusing them is also right"


@mutator("vlen sequence for a number")
def _(f, c):
    value = np.empty((1,), dtype=h5py.vlen_dtype("<f8"))
    value[0] = np.array(f["mass"].attrs["center_of_mass_input"], dtype="<f8")
    set_attr(f["mass"], "center_of_mass_input", value, dtype=value.dtype)
    return "/mass/center_of_mass_input as a variable-length sequence of doubles", MUST, "f64 (3)"


@mutator("filters and chunks")
def _(f, c):
    path = c.variant(["mesh/nodes", "reduction/upsilon", "gcms/K_hat", "gcms/G", "recovery/everything/stress_modes",
                         "mesh/tets"])
    variants = [("chunked", {"chunks": True}), ("gzip", {"compression": "gzip"}),
                ("shuffle + gzip", {"compression": "gzip", "shuffle": True}), ("fletcher32", {"fletcher32": True}),
                ("lzf (not in libhdf5)", {"compression": "lzf"})]
    what, kw = c.rng.choice(variants)
    replace_dataset(f, path, data=f[path][()], **kw)
    return f"/{path} rewritten {what}", MAY, \
        "the same values inside the sealed file; SCHEMA.md says contiguous, so refusing filters is also right"


@mutator("lossy filter")
def _(f, c):
    path = c.variant(["gcms/G", "gcms/K_hat", "mesh/nodes"])
    replace_dataset(f, path, data=f[path][()], scaleoffset=2)
    return f"/{path} rewritten with the scale-offset filter (2 decimal digits)", MUST if path != "mesh/nodes" else MAY, \
        "G and K_hat lose their checks' precision (G[0][0] = mass, symmetry); nodes to 1 cm may pass"


@mutator("damaged compressed chunk")
def _(f, c):
    path = c.variant(["mesh/nodes", "gcms/K_hat", "reduction/upsilon"])
    checksum = c.rng.random() < 0.5
    d = replace_dataset(f, path, data=f[path][()], compression="gzip", fletcher32=checksum)
    info = d.id.get_chunk_info(0)
    at = f.userblock_size + info.byte_offset + c.rng.randrange(info.size)  # chunk addresses skip the user block
    c.after.append(("flip", at, c.rng.randrange(8)))
    if checksum:
        return f"/{path} gzip + fletcher32, a bit of its chunk flipped at byte {at}", MUST, \
            "HDF5's Fletcher-32 checksum fails the read"
    return f"/{path} gzip, a bit of its chunk flipped at byte {at}", MAY, "the stream may still inflate to other values"


@mutator("external storage")
def _(f, c):
    variants = ["dev-zero exact", "dev-zero huge", "good copy", "missing file", "stress dev-zero"]
    v = c.variant(variants)
    path = "recovery/everything/stress_modes" if v == "stress dev-zero" else "mesh/nodes"
    old = f[path]
    shape, dtype = old.shape, old.dtype
    if v == "good copy":
        offset, size = old.id.get_offset(), old.id.get_storage_size()
        external = [(os.path.basename(c.good), offset, size)]
    elif v == "missing file":
        external = [("no-such-file.bin", 0, int(np.prod(shape)) * 8)]
    elif v == "dev-zero huge":
        shape = (10**8, 3)
        external = [("/dev/zero", 0, h5py.h5f.UNLIMITED)]
    else:
        external = [("/dev/zero", 0, int(np.prod(shape)) * 8)]
    replace_dataset(f, path, shape=shape, dtype=dtype, external=external)
    return f"/{path} in external storage: {v} ({external[0][0]})", MUST, \
        "its values come from outside the sealed file (the seal covers none of them)"


@mutator("external link")
def _(f, c):
    path = c.variant(["gcms/G", "mesh/nodes", "recovery", "interfaces/root"])
    target = c.rng.choice([os.path.basename(c.good), "no-such-file.fbh5", "/dev/zero"])
    del f[path]
    f[path] = h5py.ExternalLink(target, "/" + path)
    return f"/{path} an external link to {target}:/{path}", MUST, \
        "its values come from outside the sealed file (the seal covers none of them)"


@mutator("soft links")
def _(f, c):
    v = c.variant(["self loop", "two-link loop", "dangling", "group loop", "same data through a link",
                      "hard-link cycle in an unknown group", "hard link to another dataset"])
    if v == "self loop":
        path = c.rng.choice(["gcms/G", "mesh/nodes", "interfaces/root/nodes"])
        del f[path]
        f[path] = h5py.SoftLink("/" + path)
        return f"/{path} a soft link to itself", MUST, "no dataset there"
    if v == "two-link loop":
        del f["gcms/K_hat"]
        f["gcms/K_hat"] = h5py.SoftLink("/gcms/loop")
        f["gcms/loop"] = h5py.SoftLink("/gcms/K_hat")
        return "/gcms/K_hat -> /gcms/loop -> /gcms/K_hat", MUST, "no dataset there"
    if v == "dangling":
        del f["gcms/fields"]
        f["gcms/fields"] = h5py.SoftLink("/nowhere/fields")
        return "/gcms/fields a dangling soft link", MUST, "no dataset there"
    if v == "group loop":
        del f["interfaces/tip"]
        f["interfaces/tip"] = h5py.SoftLink("/interfaces")
        return "/interfaces/tip a soft link to /interfaces (a group cycle)", MUST, "tip's items are missing"
    if v == "same data through a link":
        f.move("gcms/G", "hidden_G")
        f["gcms/G"] = h5py.SoftLink("/hidden_G")
        return "/gcms/G moved to /hidden_G, a soft link in its place", MAY, \
            "the same values inside the sealed file; refusing links is also right"
    if v == "hard-link cycle in an unknown group":
        f.create_group("extra")
        f["extra/root"] = f["/"]
        f["extra/self"] = f["extra"]
        return "/extra holds hard links to / and to itself (a cycle)", MAY, "Validity: readers ignore unknown groups"
    f["gcms/K_hat_old"] = f["gcms/K_hat"]
    del f["gcms/K_hat"]
    f["gcms/K_hat"] = f["gcms/G"]
    return "/gcms/K_hat a hard link to /gcms/G", MUST, "Validity: K_hat is 3 n_f x 3 n_f"


@mutator("unknown content")
def _(f, c):
    v = c.variant(3)
    if v == 0:
        g = f.create_group("zz_unknown")
        for i in range(1000):
            g.attrs[f"a{i}"] = np.float64(i)
        return "/zz_unknown with 1000 attributes", MAY, "Validity: readers ignore what they do not know"
    if v == 1:
        f.create_dataset("gcms/zz_huge", shape=(10**9, 10**3), dtype="<f8", chunks=(1024, 8))
        return "/gcms/zz_huge declared 10^9 x 10^3, never written", MAY, "Validity: readers ignore unknown datasets"
    f["mesh"].attrs.create("zz_note", "x" * 100000, dtype=h5py.string_dtype())
    return "/mesh/zz_note a 100,000-character variable-length string", MAY, "Validity: unknown attributes are ignored"


@mutator("scaled stress modes")
def _(f, c):
    path = c.rng.choice(["recovery/near_root/stress_modes", "recovery/everything/stress_modes"])
    v = c.variant(["x2", "x1e3", "x1e6", "one entry x1e6", "zero"])
    d = f[path][()]
    if v == "one entry x1e6":
        i = np.unravel_index(np.abs(d).argmax(), d.shape)
        d[i] *= 1e6
    elif v == "zero":
        d[...] = 0.0
    else:
        d *= float(v[1:])
    f[path][...] = d
    tag = MAY if v in ("x2", "zero") else MUST
    return f"/{path} {v}", tag, ("within the bound (fbprep's stress modes use 3-9 % of it)" if tag == MAY else
                                 "Validity: no entry above (3|lambda| + 2 mu) 4 max|field| / h_min")


@mutator("scaled modal data")
def _(f, c):
    path = c.rng.choice(["gcms/mode_coefficients", "reduction/upsilon", "gcms/fields", "gcms/K_hat",
                         "interfaces/root/rotation"])
    factor = c.rng.choice((2.0, -1.0, 1e6))
    f[path][...] = f[path][()] * factor
    if path == "gcms/K_hat" and factor < 0:
        return f"/{path} x {factor}", MUST, "Validity: K_hat positive semi-definite"
    return f"/{path} x {factor}", MAY, \
        "Validity has no check tying this to the rest (upsilon = fields C, K_hat to the frequencies): a gap if accepted"


@mutator("plausible but inconsistent")
def _(f, c):
    v = c.variant(["y_row fields x2", "frequencies x2", "residuals x1e6", "static load renamed", "shift x10",
                   "condition numbers x10", "mode coefficients sign"])
    if v == "y_row fields x2":
        d = f["interfaces/root/y_row"][()]
        d[4:] *= 2
        f["interfaces/root/y_row"][...] = d
    elif v == "frequencies x2":
        f["reduction/frequencies_hz"][...] = f["reduction/frequencies_hz"][()] * 2
    elif v == "residuals x1e6":
        f["reduction/relative_residuals"][...] = f["reduction/relative_residuals"][()] * 1e6
    elif v == "static load renamed":
        set_attr(f["reduction"], "static_loads", fixed("tip:fz"))
    elif v == "shift x10":
        set_attr(f["reduction"], "shift", np.float64(f["reduction"].attrs["shift"] * 10))
    elif v == "condition numbers x10":
        for name in ("condition_G_after", "condition_G_before", "condition_mode_gram_before"):
            set_attr(f["gcms"], name, np.float64(f["gcms"].attrs[name] * 10))
    else:
        d = f["gcms/mode_coefficients"][()]
        d[:, 0] = -d[:, 0]
        f["gcms/mode_coefficients"][...] = d
    return v, MAY, "each value is plausible alone; Validity has no check tying it to the rest (a gap if accepted: " \
        "y_row[4:] = weighted fields, frequencies to K_hat, C = fields^T M_s upsilon)"


@mutator("nodes moved")
def _(f, c):
    d = f["mesh/nodes"][()]
    d[:, c.rng.randrange(3)] += 1e-3
    f["mesh/nodes"][...] = d
    return "/mesh/nodes shifted by 1 mm", MUST, "Validity: each reference point is the weighted node average"


# Whole-file changes after the h5py edit (ctx.after): the seal itself.
@mutator("seal variants")
def _(f, c):
    v = c.variant(["stripped", "stripped, version 3", "bytes appended", "uppercase digest", "sha512",
                      "text after the seal", "length off by one"])
    if v == "stripped, version 3":
        set_attr(f, "format_version", np.int32(3))
    c.after.append(("seal", v))
    tag = MAY if v in ("stripped, version 3", "bytes appended") else MUST
    reason = {"stripped, version 3": "an unsealed version-3 file (read unprotected, or refused: both right)",
              "bytes appended": "appended bytes covered by a valid seal; HDF5 ignores bytes past its end"}.get(
        v, "Seal: the first 512 bytes must be exactly the seal of the rest (a version-4 file without one too)")
    return f"seal: {v}", tag, reason


def finish_seal(path, variant, rng):
    with open(path, "rb") as fh:
        data = fh.read()
    if variant in ("stripped", "stripped, version 3"):
        data = data[SEAL:]
    elif variant == "bytes appended":
        data = seal_bytes(data + bytes(rng.randrange(256) for _ in range(rng.choice((1, 100, 4096)))))
    else:
        hdf5 = data[SEAL:]
        digest = hashlib.sha256(hdf5).hexdigest()
        lines = ["flexbody seal 1", "algorithm sha256", f"hdf5_bytes {len(hdf5)}", f"digest {digest}"]
        if variant == "uppercase digest":
            lines[3] = f"digest {digest.upper()}"
        elif variant == "sha512":
            lines[1], lines[3] = "algorithm sha512", f"digest {hashlib.sha512(hdf5).hexdigest()}"
        elif variant == "length off by one":
            lines[2] = f"hdf5_bytes {len(hdf5) + 1}"
        text = "\n".join(lines) + "\n" + ("comment\n" if variant == "text after the seal" else "")
        data = text.encode("ascii").ljust(SEAL, b"\0") + hdf5
    with open(path, "wb") as fh:
        fh.write(data)


class Context:
    def __init__(self, rng, work, good, path, round_, offset):
        self.rng, self.work, self.good, self.path, self.after = rng, work, good, path, []
        self.round, self.offset, self.variants_drawn = round_, offset, 0

    def variant(self, options):
        """A mutator's main choice (`options` a sequence or a count): round-robin over the rounds of the run (case
        index // number of mutators), shifted by the seed, so that a run of k rounds tries k variants of every
        mutator; later choices in the same case are random."""
        n = options if isinstance(options, int) else len(options)
        if self.variants_drawn:
            k = self.rng.randrange(n)
        else:
            k = (self.round + self.offset) % n
        self.variants_drawn += 1
        return k if isinstance(options, int) else options[k]


def semantic_mutation(base_bytes, rng, seed, index, work, path):
    """Writes case `index` of the semantic family to `path`; returns (kind, description, tag, reason)."""
    name, fn = MUTATORS[index % len(MUTATORS)]
    good = os.path.join(work, "good.fbh5")  # an unchanged copy beside the case, for links and external storage
    with open(good, "wb") as fh:
        fh.write(base_bytes)
    with open(path, "wb") as fh:
        fh.write(base_bytes)
    ctx = Context(rng, work, good, path, index // len(MUTATORS), random.Random(f"offset {seed} {name}").randrange(1000))
    cwd = os.getcwd()
    os.chdir(work)  # external names resolve relative to the case's directory, as the tools will see them
    try:
        with h5py.File(path, "r+") as f, np.errstate(all="ignore"):  # float16 overflow is meant
            description, tag, reason = fn(f, ctx)
    finally:
        os.chdir(cwd)
    reseal(path)
    for step in ctx.after:
        if step[0] == "flip":
            with open(path, "r+b") as fh:
                fh.seek(step[1])
                byte = fh.read(1)[0] ^ (1 << step[2])
                fh.seek(step[1])
                fh.write(bytes([byte]))
            reseal(path)
        elif step[0] == "seal":
            finish_seal(path, step[1], rng)
    return name, description, tag, reason


# ----------------------------------------------------------------------------------------------------------------
# Running the tools


class Run:
    __slots__ = ("exit_code", "signal", "timed_out", "elapsed", "out", "err")


def run_bounded(command, cwd, timeout, mem_limit_mb, env):
    def limits():
        if mem_limit_mb:
            size = mem_limit_mb * 1024 * 1024
            resource.setrlimit(resource.RLIMIT_AS, (size, size))
        resource.setrlimit(resource.RLIMIT_CORE, (0, 0))

    r = Run()
    start = time.monotonic()
    proc = subprocess.Popen(command, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            start_new_session=True, preexec_fn=limits, env=env)
    try:
        out, err = proc.communicate(timeout=timeout)
        r.timed_out = False
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        r.timed_out = True
    r.elapsed = time.monotonic() - start
    r.exit_code = proc.returncode if proc.returncode >= 0 else None
    r.signal = -proc.returncode if proc.returncode < 0 and not r.timed_out else 0
    r.out, r.err = out.decode("utf-8", "replace"), err.decode("utf-8", "replace")
    return r


# Outcomes, in the order of the table. The first group is allowed, the rest forbidden.
ALLOWED = ("refused", "refused as damaged", "accepted", "run stopped")
FORBIDDEN = ("silent acceptance", "signal", "timeout", "bad_alloc", "sanitizer", "not one line", "library noise",
             "control characters", "overlong line", "stdout on refusal", "stderr on acceptance", "not refused as damaged")
OUTCOMES = ALLOWED + FORBIDDEN


def classify(tool, run, family, tag, max_line):
    """Returns the run's outcome (one of OUTCOMES) and a short note."""
    prefix = f"{tool}: "
    # ASAN_OPTIONS=allocator_may_return_null=1 makes ASan's malloc fail as the C library's does (libhdf5 then
    # reports an error) and say so on a line of its own, which is not the tool's
    lines = [l for l in run.err.splitlines() if not re.match(r"==\d+==WARNING: AddressSanitizer failed to allocate", l)]
    errors = [l for l in lines if not l.startswith("fbsim: warning: ")] if tool == "fbsim" else lines
    if run.timed_out:
        return "timeout", f"still running after {run.elapsed:.1f} s"
    if run.signal:
        name = signal.Signals(run.signal).name if run.signal in signal.Signals._value2member_map_ else str(run.signal)
        return "signal", f"killed by {name}" + (f"; stderr: {run.err.strip()[:300]}" if run.err.strip() else "")
    err = "\n".join(lines)
    if re.search(r"bad_alloc|length_error|bad_array_new_length|cannot allocate|out of memory", err, re.I):
        return "bad_alloc", err.strip()[:300]
    if re.search(r"Sanitizer|runtime error:", err):
        return "sanitizer", err.strip()[:300]
    if any(len(l.encode()) > max_line for l in lines):
        return "overlong line", f"a stderr line of {max(len(l.encode()) for l in lines)} bytes"
    if any(not l.startswith(prefix) for l in lines):  # e.g. HDF5-DIAG or "HDF5: infinite loop closing library"
        return "library noise", run.err.strip()[:300]
    if re.search(r"[\x00-\x09\x0b-\x1f\x7f]", err):  # text from the file must reach the terminal cleaned
        return "control characters", repr(re.findall(r"[\x00-\x09\x0b-\x1f\x7f]", err)[:5])
    if run.exit_code == 0:
        if errors:
            return "stderr on acceptance", run.err.strip()[:300]
        if family == "sealed":
            return "not refused as damaged", "accepted"
        return ("silent acceptance" if tag == MUST else "accepted"), ""
    if len(errors) != 1 or not errors[0].startswith(prefix + "error: "):
        return "not one line", f"{len(errors)} lines: {run.err.strip()[:300]}"
    if run.out.strip() and (tool == "fbprep" or run.exit_code == 2):
        return "stdout on refusal", run.out.strip()[:200]
    if family == "sealed":
        if run.exit_code == 2 and DAMAGED in errors[0]:
            return "refused as damaged", ""
        return "not refused as damaged", f"exit code {run.exit_code}: {errors[0][:300]}"
    if tool == "fbsim" and run.exit_code == 1:  # the body was read and the run began: the reader accepted it
        return ("silent acceptance" if tag == MUST else "run stopped"), errors[0][:300]
    return "refused", ""


# ----------------------------------------------------------------------------------------------------------------
# Cases


def case_id(family, seed, index):
    return f"{family}:{seed}:{index}"


def parse_case_id(text):
    try:
        family, seed, index = text.split(":")
        assert family in FAMILIES
        return family, int(seed), int(index)
    except (ValueError, AssertionError):
        raise SystemExit(f"fuzz_body_files.py: a case id is FAMILY:SEED:INDEX with FAMILY one of {', '.join(FAMILIES)}, "
                         f"got '{text}'")


def case_rng(family, seed, index):
    return random.Random(f"flexbody-fuzz {family} {seed} {index}")  # str seeds hash with SHA-512: stable


STATE = {}


def init_worker(config):
    STATE.update(config)
    STATE["bytes"] = {}
    STATE["meta"] = {}
    STATE["structures"] = {}
    for name, path in config["bases"].items():
        with open(path, "rb") as fh:
            STATE["bytes"][name] = fh.read()
        STATE["meta"][name] = metadata_ranges(path, len(STATE["bytes"][name]))
        STATE["structures"][name] = checksummed_structures(STATE["bytes"][name])
        if len(STATE["structures"][name]) < 2:  # the superblock and at least one object header whose checksum matched
            raise SystemExit(f"fuzz_body_files.py: {path}: no version-2 HDF5 object headers with a matching lookup3 "
                             "checksum; the checksummed family needs them")


def run_case(family, seed, index, keep=False):
    rng = case_rng(family, seed, index)
    base = BASES[index % 2] if family != "semantic" else "bar"
    good = STATE["bytes"][base]
    work = tempfile.mkdtemp(prefix=f"{family}-{index}-", dir=STATE["work"])
    path = os.path.join(work, "case.fbh5")
    result = {"id": case_id(family, seed, index), "family": family, "index": index, "base": base}
    try:
        if family == "semantic":
            kind, description, tag, reason = semantic_mutation(good, rng, seed, index, work, path)
        elif family == "checksummed":
            data, description = checksummed_mutation(good, STATE["structures"][base], rng)
            with open(path, "wb") as fh:
                fh.write(data)
            kind = description.split(" at ")[0]
            tag, reason = MAY, "changed HDF5 metadata with valid checksums and seal: may read as another valid file"
        else:
            floor = 0 if family == "sealed" else SEAL
            data, description = byte_mutation(good, STATE["meta"][base], rng, index, floor)
            if family == "resealed":
                data = seal_bytes(data)
            with open(path, "wb") as fh:
                fh.write(data)
            kind = description.split(" (")[0]
            tag, reason = (MUST, "the seal must refuse it as damaged") if family == "sealed" else \
                (MAY, "damaged bytes under a valid seal: a changed value can be plausible")
    except Exception as error:  # a mutator that could not be applied is a harness bug: report it loudly
        shutil.rmtree(work, ignore_errors=True)
        result.update(kind="harness error", description=f"{type(error).__name__}: {error}", tag=MAY, reason="",
                      tools={}, harness_error=True)
        return result
    result.update(kind=kind, description=description, tag=tag, reason=reason, tools={})
    with open(os.path.join(work, "scene.yaml"), "w") as fh:
        fh.write(SCENES[base])
    commands = {"fbprep": [STATE["fbprep"], "inspect", "--json", "case.fbh5"],
                "fbsim": [STATE["fbsim"], "scene.yaml", "-o", "out", "-q"]}
    failed = False
    for tool, command in commands.items():
        run = run_bounded(command, work, STATE["timeout"], STATE["mem_limit"], STATE["env"])
        outcome, note = classify(tool, run, family, tag, STATE["max_line"])
        failed |= outcome in FORBIDDEN
        result["tools"][tool] = {"outcome": outcome, "note": note, "exit_code": run.exit_code, "signal": run.signal,
                                 "timed_out": run.timed_out, "seconds": round(run.elapsed, 3),
                                 "stderr": run.err[:2000], "stderr_lines": len(run.err.splitlines())}
        with open(os.path.join(work, f"{tool}.stderr"), "w") as fh:
            fh.write(run.err)
        with open(os.path.join(work, f"{tool}.stdout"), "w") as fh:
            fh.write(run.out[:65536])
    result["failed"] = failed
    shutil.rmtree(os.path.join(work, "out"), ignore_errors=True)
    if failed or keep:
        keep_dir = os.path.join(STATE["out"], "failures" if failed and not keep else "cases",
                                result["id"].replace(":", "-"))
        shutil.rmtree(keep_dir, ignore_errors=True)
        shutil.move(work, keep_dir)
        with open(os.path.join(keep_dir, "case.json"), "w") as fh:
            json.dump(result, fh, indent=1)
        result["kept"] = keep_dir
    else:
        shutil.rmtree(work, ignore_errors=True)
    return result


# ----------------------------------------------------------------------------------------------------------------
# Report


def table(results):
    counts = collections.OrderedDict()
    for fam in FAMILIES:
        for tool in ("fbprep", "fbsim"):
            counts[(fam, tool)] = collections.Counter()
    for r in results:
        for tool, t in r["tools"].items():
            counts[(r["family"], tool)][t["outcome"]] += 1
    used = [o for o in OUTCOMES if any(c[o] for c in counts.values())]
    head = "| family | tool | cases | " + " | ".join(used) + " |"
    lines = [head, "|" + "---|" * (3 + len(used))]
    for (fam, tool), c in counts.items():
        n = sum(c.values())
        if n:
            lines.append(f"| {fam} | {tool} | {n} | " + " | ".join(str(c[o]) for o in used) + " |")
    return "\n".join(lines)


def kind_table(results):
    """Per semantic mutator: cases, tag counts and outcomes of both tools, so gaps in may-accept kinds show."""
    rows = collections.OrderedDict()
    for r in results:
        if r["family"] != "semantic":
            continue
        row = rows.setdefault(r["kind"], collections.Counter())
        row["cases"] += 1
        for tool, t in r["tools"].items():
            row[f"{tool} {t['outcome']}"] += 1
    lines = ["| semantic kind | cases | fbprep | fbsim |", "|---|---|---|---|"]
    for kind, c in rows.items():
        def cell(tool):
            return ", ".join(f"{o} {c[f'{tool} {o}']}" for o in OUTCOMES if c[f"{tool} {o}"])
        lines.append(f"| {kind} | {c['cases']} | {cell('fbprep')} | {cell('fbsim')} |")
    return "\n".join(lines)


def failure_list(results, limit):
    lines = []
    for r in results:
        if not r.get("failed") and not r.get("harness_error"):
            continue
        if r.get("harness_error"):
            lines.append(f"- {r['id']}: HARNESS ERROR {r['description']}")
            continue
        bad = ", ".join(f"{tool}: {t['outcome']} ({' '.join(t['note'].split())[:160]})" if t["note"] else
                        f"{tool}: {t['outcome']}"
                        for tool, t in r["tools"].items() if t["outcome"] in FORBIDDEN)
        lines.append(f"- {r['id']} [{r['kind']}; {r['tag']}] {r['description'][:160]}: {bad}")
    if len(lines) > limit:
        lines = lines[:limit] + [f"- ... and {len(lines) - limit} more (results.jsonl)"]
    return "\n".join(lines)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cases", type=int, default=100, help="cases per family (default 100)")
    parser.add_argument("--families", default=",".join(FAMILIES), help="comma-separated subset of " + ", ".join(FAMILIES))
    parser.add_argument("--seed", type=int, default=20261123, help="the run's seed (default 20261123)")
    parser.add_argument("--jobs", type=int, default=2, help="cases run in parallel (default 2)")
    parser.add_argument("--fbprep", default=shutil.which("fbprep") or "fbprep")
    parser.add_argument("--fbsim", default=shutil.which("fbsim") or "fbsim")
    parser.add_argument("--out", default=None, help="output directory: base files, results.jsonl, summary.md, "
                        "failures/<id>/ (default: a new directory under /tmp)")
    parser.add_argument("--timeout", type=float, default=10.0, help="seconds per tool run (default 10)")
    parser.add_argument("--mem-limit", type=int, default=4096, help="address-space limit per tool run in MiB, so "
                        "that a huge allocation fails as bad_alloc instead of swapping (default 4096; 0 = none, "
                        "needed with AddressSanitizer)")
    parser.add_argument("--max-line", type=int, default=2000, help="longest stderr line in bytes (default 2000)")
    parser.add_argument("--case", action="append", default=[], metavar="FAMILY:SEED:INDEX",
                        help="run only this case (repeatable), keep its files in OUT/cases/ and print it")
    parser.add_argument("--list-kinds", action="store_true", help="print the semantic mutators and exit")
    args = parser.parse_args()

    if args.list_kinds:
        for i, (name, _) in enumerate(MUTATORS):
            print(f"{i:3} {name}")
        return 0
    families = [x for x in args.families.split(",") if x]
    if any(x not in FAMILIES for x in families):
        parser.error(f"--families: one of {', '.join(FAMILIES)}")
    for tool in ("fbprep", "fbsim"):
        path = getattr(args, tool)
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            parser.error(f"--{tool}: no executable '{path}'")
    out = os.path.abspath(args.out or tempfile.mkdtemp(prefix="fuzz-body-files-"))
    os.makedirs(out, exist_ok=True)
    shutil.rmtree(os.path.join(out, "failures"), ignore_errors=True)
    work = os.path.join(out, "work")
    os.makedirs(work, exist_ok=True)

    started = time.monotonic()
    bases = make_bases(os.path.abspath(args.fbprep), os.path.join(out, "base"), args.timeout)
    env = dict(os.environ, LC_ALL="C")
    config = {"bases": bases, "fbprep": os.path.abspath(args.fbprep), "fbsim": os.path.abspath(args.fbsim),
              "timeout": args.timeout, "mem_limit": args.mem_limit, "max_line": args.max_line, "out": out,
              "work": work, "env": env}

    # The base files themselves must read through both tools, or every answer below means nothing.
    init_worker(config)
    for base in BASES:
        check = tempfile.mkdtemp(dir=work)
        shutil.copy(bases[base], os.path.join(check, "case.fbh5"))
        with open(os.path.join(check, "scene.yaml"), "w") as fh:
            fh.write(SCENES[base])
        for tool, command in {"fbprep": [config["fbprep"], "inspect", "--json", "case.fbh5"],
                              "fbsim": [config["fbsim"], "scene.yaml", "-o", "out", "-q"]}.items():
            run = run_bounded(command, check, max(args.timeout, 60), args.mem_limit, env)
            if run.exit_code != 0 or run.err:
                raise SystemExit(f"fuzz_body_files.py: the unchanged {base}.fbh5 does not pass {tool} "
                                 f"(exit {run.exit_code}, signal {run.signal}): {run.err.strip()[:500]}")
        shutil.rmtree(check)

    if args.case:
        keep = True
        todo = [parse_case_id(c) for c in args.case]
    else:
        keep = False
        todo = [(fam, args.seed, i) for fam in families for i in range(args.cases)]

    results = []
    if args.jobs <= 1 or len(todo) == 1:
        results = [run_case(*t, keep=keep) for t in todo]
    else:
        context = multiprocessing.get_context("fork")
        with concurrent.futures.ProcessPoolExecutor(args.jobs, mp_context=context, initializer=init_worker,
                                                    initargs=(config,)) as pool:
            futures = [pool.submit(run_case, *t, keep=keep) for t in todo]
            step, done, failing = max(100, len(todo) // 20), 0, 0
            for fut in concurrent.futures.as_completed(futures):
                done += 1
                failing += bool(fut.result().get("failed"))
                if done % step == 0 and done < len(todo):
                    print(f"fuzz_body_files.py: {done} of {len(todo)} cases, {failing} with a forbidden outcome, "
                          f"{time.monotonic() - started:.0f} s", file=sys.stderr, flush=True)
            results = [fut.result() for fut in futures]
    elapsed = time.monotonic() - started
    shutil.rmtree(work, ignore_errors=True)

    with open(os.path.join(out, "results.jsonl"), "w") as fh:
        for r in results:
            fh.write(json.dumps(r) + "\n")
    failed = [r for r in results if r.get("failed")]
    harness = [r for r in results if r.get("harness_error")]
    summary = [f"# Body-file fuzz run: seed {args.seed}, {len(results)} cases ({len(results) * 2} tool runs), "
               f"{elapsed:.1f} s with {args.jobs} jobs", "", table(results), ""]
    if any(r["family"] == "semantic" for r in results):
        summary += [kind_table(results), ""]
    summary += [f"{len(failed)} cases with a forbidden outcome" + (f", {len(harness)} harness errors" if harness else "")
                + (f" (kept in {out}/failures)" if failed else ""), ""]
    if failed or harness:
        summary += [failure_list(results, 200), ""]
    text = "\n".join(summary)
    with open(os.path.join(out, "summary.md"), "w") as fh:
        fh.write(text)
    print(text)
    if args.case:
        for r in results:
            print(json.dumps(r, indent=1))
    print(f"output: {out}")
    return 1 if failed or harness else 0


if __name__ == "__main__":
    sys.exit(main())

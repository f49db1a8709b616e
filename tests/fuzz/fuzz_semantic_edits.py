"""fuzz_body_files.py's semantic family, part 2: indices, node lists, ranges, texts, the seal, and a case made from
them (the mutators register in fuzz_semantic.py's list, in this order after its own)."""
import hashlib
import os
import random
import sys

try:
    import h5py
    import numpy as np
except ImportError as error:  # ctest SKIP_RETURN_CODE
    print(f"fuzz_body_files.py: skipped: {error} (install python3-h5py)")
    sys.exit(77)

from fuzz_base import MAY, MUST, SEAL, reseal, seal_bytes
from fuzz_semantic import (MUTATORS, attr_type_of, fixed, mutator, replace_dataset, set_attr, vlen,  # noqa: F401
                           where)


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

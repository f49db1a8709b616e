"""fuzz_body_files.py's semantic family, part 1: the mutators' registry and helpers, and the edits of datasets,
attributes, types and values (fuzz_semantic_edits.py: the rest)."""
import sys

try:
    import h5py
    import numpy as np
except ImportError as error:  # ctest SKIP_RETURN_CODE
    print(f"fuzz_body_files.py: skipped: {error} (install python3-h5py)")
    sys.exit(77)

from fuzz_base import MAY, MUST


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

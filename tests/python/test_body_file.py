"""flexbody.read_body (issue 31): a body file's datasets as read-only NumPy views with the documented shapes, dtypes
and units, equal to what h5py reads from the same file; the reader's errors as BodyFileError."""
import gc
import re
import shutil
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

import flexbody

REPO = Path(__file__).resolve().parents[2]


def project_version():
    text = (REPO / "CMakeLists.txt").read_text()
    return re.search(r"project\(flexbody VERSION ([0-9.]+)", text).group(1)


def test_version_is_the_projects():
    assert flexbody.__version__ == project_version()


def test_shapes_dtypes_and_units(bracket_file):
    body = flexbody.read_body(bracket_file)
    n_n = body.nodes.shape[0]
    n_f = body.fields.shape[1]
    assert body.unit == "m" and body.format_version == 4 and body.sealed
    assert body.mode_kind == "free-free" and body.element_order == 1
    assert body.nodes.shape == (n_n, 3) and body.nodes.dtype == np.float64
    assert body.elements.shape[1] == 4 and body.elements.dtype == np.int32
    assert body.elements.min() == 0 and body.elements.max() == n_n - 1
    assert body.surface_triangles.shape[1] == 3 and body.surface_triangles.dtype == np.int32
    assert body.frequencies_hz.shape == (6,) and np.all(np.diff(body.frequencies_hz) > 0)
    assert body.upsilon.shape == (n_n, 18) and body.mode_shapes.shape == (6, n_n, 3)
    assert body.G.shape == (4 + n_f, 4 + n_f) and body.K_hat.shape == (3 * n_f, 3 * n_f)
    assert body.mode_coefficients.shape == (n_f, 18) and body.field_mode.shape == (n_f,)
    assert body.center_of_mass.shape == (3,) and body.inertia.shape == (3, 3)
    # The steel bracket in metres: a mass of grams to a kilogram, its nodes within 0.1 m of the centre of mass (the
    # origin), the material as declared.
    assert 0.01 < body.mass < 1.0 and np.abs(body.nodes).max() < 0.1
    assert body.material["name"] == "steel" and body.material["youngs_modulus"] == pytest.approx(2.1e11, rel=0.05)
    assert body.provenance["input_unit"] == "mm" and body.provenance["source_file"] == "bracket.step"
    # G's corner is the mass; its next 3 x 3 block the second moment, whose trace is the inertia's half trace.
    assert body.G[0, 0] == pytest.approx(body.mass, rel=1e-12)
    assert np.trace(body.G[1:4, 1:4]) == pytest.approx(0.5 * np.trace(body.inertia), rel=1e-10)


def test_interfaces_and_output_regions(bracket_file):
    body = flexbody.read_body(bracket_file)
    assert list(body.interfaces) == ["bore_1", "bore_2", "bore_3"]
    for interface in body.interfaces.values():
        assert interface.coupling == "rbe3"
        assert interface.nodes.dtype == np.int32 and interface.weights.shape == interface.nodes.shape
        assert interface.weights.sum() == pytest.approx(1.0, abs=1e-12)
        # Its point is the weighted mean of its nodes (SCHEMA.md), 30 mm between bore_1 and bore_2.
        np.testing.assert_allclose(interface.reference_point, interface.weights @ body.nodes[interface.nodes],
                                   atol=1e-15)
    gap = body.interfaces["bore_2"].reference_point - body.interfaces["bore_1"].reference_point
    assert np.linalg.norm(gap) == pytest.approx(0.030, abs=1e-5)
    for region in body.output_regions.values():
        assert region.stress_modes.shape == (6 * region.nodes.size, 3 * body.fields.shape[1])


def test_the_same_numbers_as_h5py(bracket_file):
    body = flexbody.read_body(bracket_file)
    with h5py.File(bracket_file, "r") as f:
        np.testing.assert_array_equal(body.nodes, f["mesh/nodes"][...])
        np.testing.assert_array_equal(body.elements, f["mesh/tets"][...])
        np.testing.assert_array_equal(body.frequencies_hz, f["reduction/frequencies_hz"][...])
        assert body.mass == f["mass"].attrs["total"]


def test_modes_stiffness_and_mass_agree(bracket_file):
    """Mode m's body-frame field coordinates ξ̄_f = C[f, 3m:3m+3] (M-orthonormal) give ω_m² = ξ̄ᵀ K̂ ξ̄: the file's
    frequencies from its GCMS blocks, to the reduction's round-off."""
    body = flexbody.read_body(bracket_file)
    for m, f in enumerate(body.frequencies_hz):
        xi = body.mode_coefficients[:, 3 * m:3 * m + 3].reshape(-1)  # index 3 f + d
        assert xi @ body.K_hat @ xi == pytest.approx((2 * np.pi * f) ** 2, rel=1e-8)


def test_views_are_read_only_and_share_the_readers_storage(bracket_file):
    body = flexbody.read_body(bracket_file)
    shapes, upsilon = body.mode_shapes, body.upsilon
    assert np.shares_memory(shapes, upsilon)  # no copy: the same storage seen two ways
    np.testing.assert_array_equal(shapes[2, :, 1], upsilon[:, 3 * 2 + 1])
    with pytest.raises(ValueError):
        body.nodes[0, 0] = 1.0
    assert np.shares_memory(body.nodes, body.nodes)  # each access is a view of the one storage
    # An array, or an interface, keeps the body's storage alive after the Body is gone.
    nodes, expected = body.nodes, body.nodes.copy()
    bore = body.interfaces["bore_1"]
    weights = bore.weights.copy()
    del body, shapes, upsilon
    gc.collect()
    np.testing.assert_array_equal(nodes, expected)
    np.testing.assert_array_equal(bore.weights, weights)
    assert bore.name == "bore_1"


def test_a_damaged_file_raises_the_readers_message(bracket_file, build_dir, tmp_path):
    damaged = tmp_path / "damaged.fbh5"
    shutil.copy(bracket_file, damaged)
    with open(damaged, "r+b") as f:  # one byte in the middle of the file, as a bad disk or transfer would
        f.seek(damaged.stat().st_size // 2)
        byte = f.read(1)
        f.seek(-1, 1)
        f.write(bytes([byte[0] ^ 0xFF]))
    with pytest.raises(flexbody.BodyFileDamaged) as caught:
        flexbody.read_body(damaged)
    assert isinstance(caught.value, flexbody.BodyFileError)
    cli = subprocess.run([str(build_dir / "bin/fbprep"), "inspect", str(damaged)], capture_output=True, text=True)
    assert cli.returncode != 0
    assert str(caught.value) in cli.stderr  # the same one line as fbprep's
    with pytest.raises(flexbody.BodyFileError, match="missing.fbh5"):
        flexbody.read_body(tmp_path / "missing.fbh5")


def test_require_seal_false_still_checks_the_seal_it_finds(bracket_file):
    body = flexbody.read_body(bracket_file, require_seal=False)
    assert body.sealed  # checked and matching

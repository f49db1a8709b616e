"""flexbody.prep (issue 31): fbprep's pipeline from Python on a body spec, given as its file or as a dict, writes the
body file fbprep writes (the same numbers) and returns fbprep --json's report; a spec fbprep refuses raises SpecError
with its line."""
import json
import shutil
import subprocess

import numpy as np
import pytest
import yaml

import flexbody

# What differs between two runs of the same spec: the clock, the memory, and the paths given.
VARYING = {"timings_s", "stage_peak_memory_mb", "peak_memory_mb", "output", "output_bytes", "input", "seconds"}


def steady(report):
    """The report without what varies from run to run."""
    if isinstance(report, dict):
        return {k: steady(v) for k, v in report.items() if k not in VARYING}
    if isinstance(report, list):
        return [steady(v) for v in report]
    return report


@pytest.fixture()
def spec_folder(small_bar, tmp_path):
    for name in ("bar.geo", "bar.yaml"):
        shutil.copy(small_bar.parent / name, tmp_path / name)
    return tmp_path


def test_prep_from_a_dict_or_a_file_equals_fbprep(spec_folder, build_dir):
    cli = subprocess.run([str(build_dir / "bin/fbprep"), "bar.yaml", "-o", "cli.fbh5", "--json"], cwd=spec_folder,
                         capture_output=True, text=True, check=True)
    expected = json.loads(cli.stdout)
    spec = yaml.safe_load((spec_folder / "bar.yaml").read_text())
    from_dict = flexbody.prep(spec, spec_folder / "dict.fbh5", base=spec_folder)
    from_file = flexbody.prep(spec_folder / "bar.yaml", spec_folder / "file.fbh5")
    assert list(from_dict) == list(expected)  # the --json fields, in fbprep's order
    assert steady(from_dict) == steady(expected)
    assert steady(from_file) == steady(expected)
    assert from_dict["output"] == str(spec_folder / "dict.fbh5")
    reference = flexbody.read_body(spec_folder / "cli.fbh5")
    for name in ("dict.fbh5", "file.fbh5"):
        body = flexbody.read_body(spec_folder / name)
        # The same mesher (delaunay, reproducible), assembly and eigensolver: the same doubles.
        for field in ("nodes", "elements", "frequencies_hz", "G", "K_hat", "upsilon"):
            np.testing.assert_array_equal(getattr(body, field), getattr(reference, field), err_msg=field)
        assert dict(body.provenance["options"])["output"] == str(spec_folder / name)


def test_a_spec_fbprep_refuses_raises_its_line(spec_folder):
    (spec_folder / "bad.yaml").write_text("input: bar.geo\nunit: m\nmesh: {size: -1}\n")
    with pytest.raises(flexbody.SpecError, match=r"bad.yaml:3: "):
        flexbody.prep(spec_folder / "bad.yaml", spec_folder / "bad.fbh5")
    with pytest.raises(flexbody.SpecError, match=r"^body spec: unit 'parsec' is not one of mm, cm, m, in"):
        flexbody.prep({"input": "bar.geo", "unit": "parsec"}, spec_folder / "bad.fbh5", base=spec_folder)
    with pytest.raises(RuntimeError, match="nothere.step"):
        flexbody.prep({"input": "nothere.step"}, spec_folder / "bad.fbh5", base=spec_folder)
    assert not (spec_folder / "bad.fbh5").exists()
    assert issubclass(flexbody.SpecError, ValueError)

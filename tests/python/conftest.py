"""Fixtures of the Python package's tests: the build (FLEXBODY_BUILD, set by CTest) and a body file made once per
session from the sample bracket (fbprep, linear tetrahedra, 6 modes: a few seconds)."""
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def build_dir():
    return Path(os.environ.get("FLEXBODY_BUILD", REPO / "build")).resolve()


@pytest.fixture(scope="session")
def bracket_file(build_dir, tmp_path_factory):
    out = tmp_path_factory.mktemp("bodies") / "bracket.fbh5"
    subprocess.run([str(build_dir / "bin/fbprep"), str(REPO / "meshes/bracket.yaml"), "--order", "1", "--modes", "6",
                    "-o", str(out), "-q"], check=True)
    return out


@pytest.fixture(scope="session")
def small_bar(build_dir, tmp_path_factory):
    """A 0.1 x 0.02 x 0.02 m steel bar, coarse linear tetrahedra, 2 modes, interfaces root (x = 0) and tip (x = 0.1):
    a body file of 135 kB that a scene reads in about 4 ms."""
    folder = tmp_path_factory.mktemp("small_bar")
    (folder / "bar.geo").write_text('SetFactory("OpenCASCADE");\nBox(1) = {0, 0, 0, 0.1, 0.02, 0.02};\n')
    (folder / "bar.yaml").write_text(
        "input: bar.geo\nunit: m\nmesh: {size: 0.02}\nreduction: {modes: 2}\ninterfaces:\n"
        "  root: {select: {plane: {point: [0, 0, 0], normal: [1, 0, 0]}}}\n"
        "  tip: {select: {plane: {point: [0.1, 0, 0], normal: [1, 0, 0]}}}\n")
    subprocess.run([str(build_dir / "bin/fbprep"), "bar.yaml", "--order", "1", "-o", "bar.fbh5", "-q"], cwd=folder,
                   check=True)
    return folder / "bar.fbh5"

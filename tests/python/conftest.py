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

"""fbprep from Python: flexbody.prep(spec, output) runs fbprep's pipeline on a body spec (a file, or a dict with the
same keys) and returns its report, fbprep --json's object, as a dict.

    report = flexbody.prep("meshes/bracket.yaml", "build/bracket.fbh5")
    report = flexbody.prep({"input": "bar.step", "unit": "mm", "reduction": {"modes": 6}}, "bar.fbh5", base="parts")
"""
import json
import os
import warnings

from . import _flexbody

__all__ = ["PrepWarning", "SpecError", "prep"]

SpecError = getattr(_flexbody, "SpecError", None)


class PrepWarning(UserWarning):
    """A warning fbprep prints on stderr (the mesher's: a size implausible for the unit, a remeshing)."""


def _warn(line):
    warnings.warn(line, PrepWarning, stacklevel=3)


def prep(spec, output, base="."):
    """Runs fbprep on the body spec `spec` and writes the body file `output`; returns fbprep --json's report.

    `spec` is a body spec file (.yaml; its input is relative to its folder) or a dict with a spec's keys (docs/fbprep.md;
    its input relative to `base`). A spec fbprep refuses raises SpecError (a ValueError) with its line; a failure of
    the pipeline (an unreadable CAD file, a mesher that fails) raises RuntimeError with fbprep's message. The pipeline
    runs in this process, as fbprep does: it may take minutes for a fine mesh.
    """
    if not hasattr(_flexbody, "_prep_file"):
        raise RuntimeError("this flexbody package was built without the preprocessor (FLEXBODY_BUILD_PREPROCESS=OFF)")
    output = os.fspath(output)
    if isinstance(spec, dict):
        text = _flexbody._prep_document(spec, "body spec", os.fspath(base), output, _warn)
    else:
        text = _flexbody._prep_file(os.fspath(spec), output, _warn)
    return json.loads(text)

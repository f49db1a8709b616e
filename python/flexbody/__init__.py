"""flexbody: flexible bodies from CAD (fbprep) and their simulation, from Python.

    import flexbody
    body = flexbody.read_body("bracket.fbh5")
    body.frequencies_hz          # read-only NumPy views of the file's datasets, SI units

See docs/python.md.
"""
from ._flexbody import (  # noqa: F401  (the package's public names)
    Body,
    BodyFileDamaged,
    BodyFileError,
    Interface,
    OutputRegion,
    __version__,
    read_body,
)

__all__ = ["Body", "BodyFileDamaged", "BodyFileError", "Interface", "OutputRegion", "__version__", "read_body"]

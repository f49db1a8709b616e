"""flexbody: flexible bodies from CAD (fbprep) and their simulation, from Python.

    import flexbody
    body = flexbody.read_body("bracket.fbh5")
    body.frequencies_hz          # read-only NumPy views of the file's datasets, SI units
    report = flexbody.prep("part.yaml", "part.fbh5")   # fbprep's pipeline; its --json report
    sim = flexbody.load_scene("scene.yaml")
    tip = sim.run()["tip"]       # the output's rows: tip.time, tip["x"], ...

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
from .prep import PrepWarning, SpecError, prep  # noqa: F401
from .scene import (  # noqa: F401
    Output,
    Scene,
    SceneError,
    Simulation,
    SimulationWarning,
    StepFailure,
    load_scene,
)

__all__ = ["Body", "BodyFileDamaged", "BodyFileError", "Interface", "Output", "OutputRegion", "PrepWarning", "Scene",
           "SceneError", "Simulation", "SimulationWarning", "SpecError", "StepFailure", "__version__", "load_scene",
           "prep", "read_body"]

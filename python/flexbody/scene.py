"""Scenes and their runs: flexbody.Scene builds a scene in code with the keys of a scene file (docs/scenes.md),
flexbody.load_scene reads one, and both give a Simulation, which fbsim's own reader and run loop drive.

    scene = flexbody.Scene()
    scene.add_body("arm", file="bracket.fbh5", modes=6)
    scene.add_joint("pivot", type="revolute", body="arm", interface="bore_1", axis=[0, 0, 1])
    scene.gravity = [0, -9.81, 0]
    scene.set_integrator(step=1e-3, end=0.5)
    scene.add_output("tip", body="arm", interface="bore_2", quantities=["position"])
    sim = scene.simulate()
    tip = sim.run()["tip"]        # tip.time [s], tip["x"] [m], ...
"""
import copy
import json
import os
import sys
import time
import warnings

from . import _flexbody

__all__ = ["Output", "Scene", "SceneError", "Simulation", "SimulationWarning", "StepFailure", "load_scene"]

SceneError = _flexbody.SceneError
StepFailure = _flexbody.StepFailure


class SimulationWarning(UserWarning):
    """A run's warning line (fbsim prints them on stderr): a conservation law broken, the model's validity."""


class Output:
    """One output's rows: `time` (n,) [s], `values` (n, c), `columns` ("x [m]", ...: the CSV file's header after t).

    out["x"] (or out["x [m]"]) is one column; `units` are the columns' units.
    """

    def __init__(self, name, columns, time, values):
        self.name = name
        self.columns = list(columns)
        self.time = time
        self.values = values

    @property
    def names(self):
        """The columns' names without their units."""
        return [c.split(" [")[0] for c in self.columns]

    @property
    def units(self):
        """The columns' units ("m", "N m", "1", ...; "" for a count)."""
        return [c.split(" [", 1)[1].rstrip("]") if " [" in c else "" for c in self.columns]

    def __getitem__(self, column):
        if column in self.columns:
            return self.values[:, self.columns.index(column)]
        names = self.names
        if column in names:
            return self.values[:, names.index(column)]
        raise KeyError(f"output '{self.name}' has no column '{column}' (columns: {', '.join(self.columns)})")

    def __len__(self):
        return len(self.time)

    def __repr__(self):
        return f"Output('{self.name}', {len(self.time)} rows, columns {self.columns})"


class Simulation:
    """A scene's run (from Scene.simulate or load_scene): the integrator, the run's checks and its outputs.

    Its outputs are kept in memory (`outputs`); with `output_dir` they are also written as fbsim writes them (one CSV
    per output, monitors.csv, ParaView series). Warnings go through Python's warnings as SimulationWarning.
    """

    def __init__(self, native, source):
        self._native = native
        self._source = source

    @property
    def time(self):
        """The time of the last completed step [s]."""
        return self._native.time

    @property
    def end_time(self):
        """The scene's end time [s] (its integrator's `end`)."""
        return self._native.end_time

    @property
    def bodies(self):
        """The bodies' names, in the system's order (that of the state's coordinates)."""
        return self._native.bodies

    def step(self):
        """One step of the scene's step size; rows are recorded every `output_every` steps."""
        self._native.step()

    def run(self, end=None, progress=None):
        """Steps to `end` [s] (default: the scene's end) and returns the outputs (see `outputs`: copies of all the
        rows, so a controller that advances in small pieces calls step() and reads state()).

        The last step is shortened to end on `end`, and its state recorded. `progress(t)` is called every 100 steps;
        without it, a terminal on stderr shows the time. Ctrl-C stops the run at the last completed step
        (KeyboardInterrupt). A failed step raises StepFailure; a force's function that raises stops the run with its
        exception; either leaves the state of the last completed step, recorded in the outputs, and summary()'s
        "termination" ("step failed" or "error", with "termination_message") says so.
        """
        end = self.end_time if end is None else float(end)
        shown = progress is None and sys.stderr.isatty()
        if shown:
            start, started = self.time, time.monotonic()

            def progress(t):
                rate = (t - start) / max(time.monotonic() - started, 1e-9)  # simulated seconds per second
                to_go = (end - t) / rate if rate > 0 else float("inf")
                sys.stderr.write(f"\r  t = {t:.4g} / {end:.4g} s, {_duration(to_go)} to go   ")
                sys.stderr.flush()
        try:
            self._native.run(end, progress)
        finally:
            if shown:
                sys.stderr.write("\n")
        return self.outputs

    @property
    def outputs(self):
        """The rows recorded so far: {output name: Output}, the scene's outputs in its order, then "monitors"."""
        return {name: Output(name, columns, time, values) for name, columns, time, values in self._native.tables()}

    def state(self):
        """The integrator's state: t [s], q, v, qdd, a (generalized-alpha's), lambda (the multipliers), nu (the
        stabilised form's), in the system's layout of coordinates (docs/runtime.md). Copies."""
        return self._native.state()

    def set_state(self, state):
        """Goes on from `state` (a dict from state(), possibly changed; entries left out keep their values), with a
        fresh Newton matrix. A changed q or v that breaks a joint is pulled back onto it by the next step. The
        outputs keep their rows and go on from the state's time (earlier than their last row's when the run is set
        back); the summary's energies and the conservation checks measure from the state set."""
        self._native.set_state(dict(state))

    def summary(self):
        """The run so far as fbsim --json reports it (docs/scenes.md): how it ended ("termination": "running" between
        step() calls, "end reached" after run()), steps, Newton iterations, energies, ..."""
        return json.loads(self._native.summary_json(self._source))


def _duration(seconds):
    """A time to go as fbsim prints it: "42 s", "7.5 min", "3.2 h"."""
    if seconds < 90:
        return f"{seconds:.0f} s"
    return f"{seconds / 60:.1f} min" if seconds < 5400 else f"{seconds / 3600:.1f} h"


def _warn(line):
    warnings.warn(line, SimulationWarning, stacklevel=3)


def load_scene(path, end=None, output_dir=None):
    """The Simulation of the scene file `path` (fbsim's YAML; body files relative to its folder).

    `end` [s] replaces the scene's end time (fbsim --end); `output_dir` also writes the outputs there as fbsim does.
    A scene fbsim refuses raises SceneError with fbsim's line ("scene.yaml:12: ...").
    """
    path = os.fspath(path)
    native = _flexbody._load_scene(path, None if end is None else float(end),
                                   None if output_dir is None else os.fspath(output_dir), _warn)
    return Simulation(native, path)


def _given(keys):
    """The keys given a value: None stands for a key left out (the scene file's default)."""
    return {k: v for k, v in keys.items() if v is not None}


def _marker(keys):
    return {k: keys[k] for k in ("interface", "point", "node") if k in keys}


class Scene:
    """A scene in code: each add_* takes the keys a scene file's entry has, with the same names (docs/scenes.md).

    Body files are read relative to `base` (default: the working directory). The reader is fbsim's: a scene it
    refuses raises SceneError with its message. Only a force's or torque's value may be something a scene file cannot
    hold: a Python function of t [s] returning 3 numbers [N, N m] (global axes).
    """

    def __init__(self, base="."):
        self.base = os.fspath(base)
        self._document = {"bodies": {}}
        self._loads = []  # forces with a function of t: (name, body, marker, force, torque)

    def _section(self, key):
        return self._document.setdefault(key, {})

    def add_body(self, name, file, **keys):
        """A body from a body file: modes ("all", "rigid", "full" or a count), formulation, frame, position,
        rotation ({"axis": [...], "angle_deg": ...}), velocity, angular_velocity, damping, geometric_stiffness."""
        self._section("bodies")[name] = {"file": os.fspath(file), **_given(keys)}

    def add_joint(self, name, type, body, **keys):
        """A joint: type, body and its marker (interface, point or node), to ("ground", the default, or a dict of
        body and marker), axis (revolute, prismatic, driven-revolute), speed and ramp (driven-revolute)."""
        self._section("joints")[name] = {"type": type, "body": body, **_given(keys)}

    def add_force(self, name, body, force=None, torque=None, **keys):
        """A force [N] and/or torque [N m] at a marker (interface, point or node), constant with the scene file's
        ramp and frequency, or a Python function of t [s]. A function must not step its own simulation."""
        keys = _given(keys)
        if callable(force) or callable(torque):
            if "ramp" in keys or "frequency" in keys:
                raise SceneError(f"force '{name}': a function of t carries its own time shape; ramp and frequency "
                                 "belong to constant forces")
            unknown = set(keys) - {"interface", "point", "node"}
            if unknown:
                raise SceneError(f"force '{name}': unknown key(s) {', '.join(sorted(unknown))}")
            def as_function(value):
                if value is None or callable(value):
                    return value
                constant = [float(x) for x in value]
                return lambda t: constant
            self._loads.append((name, body, _marker(keys), as_function(force), as_function(torque)))
            return
        entry = {"body": body, **keys}
        if force is not None:
            entry["force"] = force
        if torque is not None:
            entry["torque"] = torque
        self._section("forces")[name] = entry

    def add_spring(self, name, from_, to, stiffness, **keys):
        """A spring-damper between two ends (each a dict of body and marker, or {"ground": [x, y, z]}): stiffness
        [N/m], damping [N s/m], length [m] (default: the ends' initial distance)."""
        self._section("springs")[name] = {"from": from_, "to": to, "stiffness": stiffness, **_given(keys)}

    @property
    def gravity(self):
        """[m/s^2], global axes."""
        return self._document.get("gravity")

    @gravity.setter
    def gravity(self, g):
        self._document["gravity"] = g

    def set_integrator(self, **keys):
        """step [s] and end [s] (required), rho_inf, tolerance, max_iterations, output_every, output_interval,
        deformation_limit, the spin levels, constraints, linear_solver, coupled_step, min_step: the scene file's
        `integrator` keys. step="auto" with error_tolerance [m per step] (and initial_step, max_step) lets the steps
        follow generalized-alpha's local error estimate; rows then come every output_interval seconds."""
        self._document["integrator"] = _given(keys)

    def add_output(self, name, quantities, **keys):
        """An output: a marker's position, velocity, orientation; a joint's reaction_force, reaction_moment; a
        body's modal_coordinates; an output region's displacement, stress."""
        if isinstance(quantities, str):
            quantities = [quantities]
        self._section("outputs")[name] = {**_given(keys), "quantities": list(quantities)}

    def set_monitors(self, on=True):
        """The monitors table: energies, orthogonality, constraint residuals, Newton iterations per recorded row."""
        self._document["monitors"] = bool(on)

    def set_paraview(self, **keys):
        """ParaView series of the bodies' surfaces (written with output_dir only): bodies, every, stresses."""
        self._document["paraview"] = _given(keys)

    def set_assembly(self, **keys):
        """The initial assembly's tolerance, a fraction of a body's size."""
        self._document["assembly"] = _given(keys)

    def set_output_budget(self, **keys):
        """What a run with an output_dir may write: size ("10 GB", "500MB" or bytes) and files; a run estimated over
        it is refused before its first step (SceneError)."""
        self._document["output_budget"] = _given(keys)

    def to_dict(self):
        """The scene file this scene is (without its functions of t), as a dict: yaml.safe_dump writes it."""
        return copy.deepcopy(self._document)

    def simulate(self, output_dir=None, end=None):
        """The Simulation of this scene at t = 0 (assembled, velocities made consistent). `end` [s] replaces the
        integrator's end; `output_dir` also writes the outputs there as fbsim does."""
        native = _flexbody._build_scene(self._document, "scene", self.base, None if end is None else float(end),
                                        None if output_dir is None else os.fspath(output_dir), list(self._loads),
                                        _warn)
        return Simulation(native, "scene")

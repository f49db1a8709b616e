"""Scenes and runs from Python (issue 31): a scene loaded and one built in code give fbsim's outputs bit for bit; the
outputs have the documented shapes and units; a force's function that raises stops the run with its exception at the
last completed step, from which set_state lets it go on; scenes fbsim refuses raise SceneError with its line."""
import csv
import gc
import json
import subprocess
import tracemalloc
import weakref

import numpy as np
import pytest

import flexbody

# The bracket pendulum of meshes/bracket_pendulum.yaml, 0.05 s, damped, pushed by a ramped force.
SCENE = """\
bodies:
  bracket: {file: bracket.fbh5, modes: 6, damping: {modal: 0.01}}
joints:
  pivot: {type: revolute, body: bracket, interface: bore_1, to: ground, axis: [0, 0, 1]}
forces:
  push: {body: bracket, interface: bore_2, force: [0, 0, 2.5], ramp: 0.02}
gravity: [0, -9.81, 0]
integrator: {rho_inf: 0.9, step: 1.0e-3, end: 0.05, output_every: 5}
outputs:
  bore_3: {body: bracket, interface: bore_3, quantities: [position, velocity]}
  pivot_force: {joint: pivot, quantities: [reaction_force, reaction_moment]}
  modes: {body: bracket, quantities: [modal_coordinates]}
monitors: true
"""


def scene_in_code(base, **push):
    """SCENE, built with flexbody.Scene (the force `push` replaced when given)."""
    scene = flexbody.Scene(base)
    scene.add_body("bracket", file="bracket.fbh5", modes=6, damping={"modal": 0.01})
    scene.add_joint("pivot", type="revolute", body="bracket", interface="bore_1", to="ground", axis=[0, 0, 1])
    scene.add_force("push", body="bracket", interface="bore_2", **(push or {"force": [0, 0, 2.5], "ramp": 0.02}))
    scene.gravity = np.array([0, -9.81, 0])
    scene.set_integrator(rho_inf=0.9, step=1.0e-3, end=0.05, output_every=5)
    scene.add_output("bore_3", body="bracket", interface="bore_3", quantities=["position", "velocity"])
    scene.add_output("pivot_force", joint="pivot", quantities=("reaction_force", "reaction_moment"))
    scene.add_output("modes", body="bracket", quantities=["modal_coordinates"])
    scene.set_monitors()
    return scene


@pytest.fixture()
def folder(bracket_file, tmp_path):
    (tmp_path / "bracket.fbh5").symlink_to(bracket_file)
    (tmp_path / "scene.yaml").write_text(SCENE)
    return tmp_path


def read_csv(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    return rows[0], np.array([[float(x) for x in row] for row in rows[1:]])


def test_loaded_and_built_scenes_give_fbsims_outputs(folder, build_dir):
    cli = subprocess.run([str(build_dir / "bin/fbsim"), "scene.yaml", "-o", "out", "--json"], cwd=folder,
                         capture_output=True, text=True, check=True)
    fbsim_summary = json.loads(cli.stdout)
    loaded = flexbody.load_scene(folder / "scene.yaml")
    built = scene_in_code(folder).simulate()
    for sim in (loaded, built):
        outputs = sim.run()
        assert list(outputs) == ["bore_3", "pivot_force", "modes", "monitors"]
        for name, out in outputs.items():
            header, rows = read_csv(folder / "out" / f"{name}.csv")
            assert header == ["t [s]"] + out.columns
            # The same reader, builder and run loop, and 17 significant digits in the CSV: the same doubles.
            np.testing.assert_array_equal(out.time, rows[:, 0])
            np.testing.assert_array_equal(out.values, rows[:, 1:])
        summary = sim.summary()
        assert list(summary) == list(fbsim_summary)  # the --json fields
        assert summary["steps"] == fbsim_summary["steps"] == 50
        assert summary["newton_iterations"] == fbsim_summary["newton_iterations"]
        assert summary["energy_final_j"] == fbsim_summary["energy_final_j"]
    assert built.summary()["scene"] == "scene"


def test_outputs_have_the_documented_shapes_and_units(folder):
    sim = flexbody.load_scene(folder / "scene.yaml")
    outputs = sim.run()
    rows = 50 // 5 + 1  # t = 0 and every 5th of 50 steps
    bore = outputs["bore_3"]
    assert bore.time.shape == (rows,) and bore.time.dtype == np.float64
    assert bore.values.shape == (rows, 6) and bore.values.dtype == np.float64
    assert bore.names == ["x", "y", "z", "vx", "vy", "vz"] and bore.units == ["m"] * 3 + ["m/s"] * 3
    np.testing.assert_allclose(bore.time, np.linspace(0.0, 0.05, rows), rtol=0, atol=1e-15)
    assert outputs["pivot_force"].units == ["N"] * 3 + ["N m"] * 3
    assert outputs["modes"].values.shape == (rows, 6) and outputs["modes"].units == ["kg^1/2 m"] * 6
    assert outputs["monitors"].names[-1] == "Newton iterations" and outputs["monitors"].units[-1] == ""
    np.testing.assert_array_equal(bore["x"], bore.values[:, 0])
    np.testing.assert_array_equal(bore["vy [m/s]"], bore.values[:, 4])
    with pytest.raises(KeyError, match="no column 'w'"):
        bore["w"]


def test_a_run_in_steps_and_pieces(folder):
    sim = flexbody.load_scene(folder / "scene.yaml")
    assert sim.summary()["termination"] == "running"
    for _ in range(9):
        sim.step()
    assert sim.time != 0.009  # 9 x 1e-3 rounds to 0.009000000000000001
    sim.run(0.009)  # is there
    sim.step()
    assert sim.time == pytest.approx(0.01, abs=1e-15)
    sim.run(0.03)
    assert sim.time == 0.03
    sim.run(0.03)  # there already (up to the time's rounding): nothing to do
    with pytest.raises(ValueError, match="already"):
        sim.run(0.02)
    outputs = sim.run()
    assert outputs["bore_3"].time[-1] == 0.05 and len(outputs["bore_3"]) == 11
    assert sim.summary()["steps"] == 50


def test_error_control_from_python(folder):
    """step="auto": the steps follow the error tolerance, rows come by time and land on it, the summary says so."""
    scene = scene_in_code(folder)
    scene.set_integrator(rho_inf=0.9, step="auto", error_tolerance=1e-7, end=0.05, output_interval=0.005)
    sim = scene.simulate()
    outputs = sim.run()
    times = outputs["bore_3"].time
    assert len(times) == 11
    assert np.allclose(times, 0.005 * np.arange(11), rtol=0, atol=1e-15)  # on each multiple, not a step after it
    summary = sim.summary()
    assert summary["error_tolerance_m"] == 1e-7
    # a step is at most a row's interval, up to the rounding of the difference of two times up to 0.05 s (8 eps each)
    assert summary["smallest_step_s"] <= summary["largest_step_s"] <= 0.005 + 16 * np.finfo(float).eps * 0.05
    assert summary["steps_above_tolerance"] == 0
    with pytest.raises(flexbody.SceneError, match="output_every counts steps"):
        scene.set_integrator(step="auto", error_tolerance=1e-7, end=0.05, output_every=5)
        scene.simulate()


def test_state_and_set_state(folder):
    sim = flexbody.load_scene(folder / "scene.yaml")
    sim.run(0.02)
    state = sim.state()
    assert set(state) == {"t", "q", "v", "qdd", "a", "lambda", "nu"}
    assert state["q"].shape == state["v"].shape == (12 + 3 * 18,)  # τ, A and 18 fields of 6 modes (linear tets)
    sim.run(0.04)
    after = sim.state()
    sim.set_state(state)
    np.testing.assert_array_equal(sim.state()["q"], state["q"])
    sim.run(0.04)
    assert sim.outputs["bore_3"].time[-1] == 0.04 and sim.summary()["steps"] == 60  # 40, then 20 again
    # The same motion again, up to the Newton iteration's error (a fresh Newton matrix where the first run kept one):
    # its tolerance is 1e-6 of a step's predictor distance; measured 2.8e-9 after 20 steps, in coordinates of the
    # bracket's size (0.1 m).
    np.testing.assert_allclose(sim.state()["q"], after["q"], rtol=0, atol=1e-7)
    with pytest.raises(ValueError, match="q has 3 entries"):
        sim.set_state({"q": np.zeros(3)})
    q = sim.state()["q"]
    with pytest.raises(ValueError, match="is not finite"):
        sim.set_state({"v": np.full(q.shape, np.nan)})
    np.testing.assert_array_equal(sim.state()["q"], q)  # a refused state changes nothing
    with pytest.raises(KeyError, match="unknown entry 'x'"):
        sim.set_state({"x": 1.0})


class SensorOff(RuntimeError):
    pass


def test_a_raising_function_stops_the_run_at_the_last_completed_step(folder):
    failing = [True]

    def push(t):
        if failing[0] and t > 0.0325:
            raise SensorOff("the controller's sensor is off")
        return [0.0, 0.0, 2.5 * min(1.0, t / 0.02)]

    sim = scene_in_code(folder, force=push).simulate()
    with pytest.raises(SensorOff, match="sensor is off"):
        sim.run()
    assert sim.time == pytest.approx(0.032, abs=1e-15)  # the 33rd step failed
    summary = sim.summary()
    assert summary["termination"] == "error" and "sensor is off" in summary["termination_message"]
    assert summary["time_s"] == sim.time
    # The last completed step is recorded although rows fall every 5th step (t = 0.030, then 0.035).
    np.testing.assert_allclose(sim.outputs["bore_3"].time[-2:], [0.030, 0.032], rtol=0, atol=1e-15)
    failing[0] = False
    sim.run()  # goes on from there
    assert sim.summary()["termination"] == "end reached"
    reference = scene_in_code(folder, force=lambda t: [0.0, 0.0, 2.5 * min(1.0, t / 0.02)]).simulate()
    expected = reference.run()["bore_3"]
    # The same motion up to the Newton iteration's error after the interruption (a fresh Newton matrix, as in
    # test_state_and_set_state).
    np.testing.assert_allclose(sim.outputs["bore_3"].values[-1], expected.values[-1], rtol=0, atol=1e-7)


def test_ctrl_c_stops_the_run_at_the_last_completed_step(folder):
    """A KeyboardInterrupt (here raised by the progress function, as Ctrl-C would while it runs) stops the run: it
    reaches the caller, the last completed step is recorded, and the summary says the run was stopped."""
    def progress(t):
        raise KeyboardInterrupt

    sim = flexbody.load_scene(folder / "scene.yaml")
    with pytest.raises(KeyboardInterrupt):
        sim.run(0.2, progress=progress)
    assert sim.time == pytest.approx(0.1, abs=1e-12)  # progress is called every 100 steps of 1 ms
    assert sim.outputs["bore_3"].time[-1] == sim.time
    summary = sim.summary()
    assert summary["termination"] == "stopped" and summary["time_s"] == sim.time
    sim.run(0.11)
    assert sim.summary()["termination"] == "end reached"


def test_a_function_may_not_step_its_own_simulation(folder):
    holder = {}

    def meddling(t):
        if "sim" in holder:
            holder["sim"].step()
        return [0.0, 0.0, 0.0]

    holder["sim"] = sim = scene_in_code(folder, force=meddling).simulate()
    with pytest.raises(RuntimeError, match="cannot be called from a force's function"):
        sim.step()
    assert sim.time == 0.0


def test_a_function_must_return_three_finite_numbers(folder):
    with pytest.raises(ValueError, match=r"force 'push' force: the function's value at t = 0 s must be 3 numbers"):
        scene_in_code(folder, force=lambda t: [0.0, 1.0]).simulate()
    with pytest.raises(ValueError, match=r"force 'push' torque: the function's value at t = 0.003 s is not finite"):
        scene_in_code(folder, torque=lambda t: [0.0, 0.0, np.nan if t > 0.0025 else 0.0]).simulate().run()


def test_scenes_fbsim_refuses_raise_its_line(folder):
    (folder / "bad.yaml").write_text(SCENE.replace("modes: 6", "modes: 60"))
    with pytest.raises(flexbody.SceneError, match=r"bad.yaml:2: .*60 modes"):
        flexbody.load_scene(folder / "bad.yaml")
    scene = scene_in_code(folder)
    scene.add_body("extra", file="bracket.fbh5", modez=3)
    with pytest.raises(flexbody.SceneError, match=r"^scene: unknown key 'modez' in body 'extra'"):
        scene.simulate()
    with pytest.raises(flexbody.SceneError, match="ramp and frequency belong to constant forces"):
        scene_in_code(folder).add_force("f", body="bracket", interface="bore_2", force=lambda t: [0, 0, 0], ramp=1)
    assert issubclass(flexbody.SceneError, ValueError)


def test_no_cycles_or_leaks_over_1000_scenes(small_bar):
    # Each scene holds a force whose function refers to the simulation itself (a controller would): a cycle through
    # C++ that the garbage collector must see (tp_traverse) to free it.
    def construct():
        scene = flexbody.Scene(small_bar.parent)
        scene.add_body("bar", file=small_bar.name, damping={"modal": 0.01})
        scene.add_joint("pivot", type="revolute", body="bar", interface="root", axis=np.array([0, 0, 1.0]))
        scene.gravity = [0, -9.81, 0]
        holder = {}

        def controller(t):
            return [0.0, 0.0, 0.0 * holder["sim"].time if "sim" in holder else 0.0]

        scene.add_force("controller", body="bar", interface="tip", force=controller)
        scene.set_integrator(step=1e-3, end=0.01)
        scene.add_output("tip", body="bar", interface="tip", quantities=["position"])
        holder["sim"] = scene.simulate()
        holder["sim"].step()
        return weakref.ref(controller)

    for _ in range(300):  # the caches that the first runs fill (HDF5, NumPy, pybind11, the interpreter's free lists)
        construct()
    gc.collect()
    tracemalloc.start()
    snapshots = [tracemalloc.take_snapshot()]
    alive = []
    for _ in range(2):
        alive += [construct() for _ in range(500)]
        gc.collect()
        snapshots.append(tracemalloc.take_snapshot())
    tracemalloc.stop()
    assert all(ref() is None for ref in alive)  # every cycle collected: the simulations and their functions freed
    # Python's allocations left by each 500 scenes (tracemalloc sees Python's objects, not the C++ simulation's,
    # whose release the collected functions show): caches still filling, less in the second window (measured 100 kB,
    # then 50 kB), not a growth per scene: a leaked function and its closure would be 500 x 1 kB.
    grown = [sum(s.size_diff for s in b.compare_to(a, "filename")) for a, b in zip(snapshots, snapshots[1:])]
    assert grown[1] < 100_000, grown

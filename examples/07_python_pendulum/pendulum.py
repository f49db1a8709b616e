#!/usr/bin/python3
"""Example 07: the bracket pendulum built and run from Python, with a plot of the path of its third bore and of its
modal coordinates, and a push that a Python function of time gives.

    pendulum.py BODY.fbh5 OUT.png [END_S]
"""
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import flexbody

body_file = Path(sys.argv[1])
picture = sys.argv[2]
end = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0

# The scene: the keys of a scene file (docs/scenes.md), in code. Body files are found relative to `base`.
scene = flexbody.Scene(base=body_file.parent)
scene.add_body("bracket", file=body_file.name, modes=6)
scene.add_joint("pivot", type="revolute", body="bracket", interface="bore_1", axis=[0, 0, 1])  # to ground
scene.gravity = [0, -9.81, 0]
# A sideways push on bore_2 for the first 50 ms: half a sine of 0.5 N along z, a Python function of t [s].
scene.add_force("push", body="bracket", interface="bore_2",
                force=lambda t: [0.0, 0.0, 0.5 * np.sin(np.pi * t / 0.05) if t < 0.05 else 0.0])
scene.set_integrator(rho_inf=0.9, step=1e-3, end=end)
scene.add_output("bore_3", body="bracket", interface="bore_3", quantities=["position"])
scene.add_output("modes", body="bracket", quantities=["modal_coordinates"])

sim = scene.simulate()
outputs = sim.run()
summary = sim.summary()
print(f"{summary['steps']} steps, {summary['newton_iterations'] / summary['steps']:.2f} Newton iterations per step, "
      f"{summary['us_per_step']:.0f} us per step; largest constraint residual {summary['max_constraint_residual']:.1e}")

bore, modes = outputs["bore_3"], outputs["modes"]
figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
left.plot(1e3 * bore["x"], 1e3 * bore["y"], color="tab:blue")
left.plot(1e3 * bore["x"][0], 1e3 * bore["y"][0], "o", color="tab:blue", label="start")
left.set_xlabel("x [mm]")
left.set_ylabel("y [mm]")
left.set_aspect("equal")
left.set_title("bore_3's path (the pivot is bore_1)")
left.legend()
for name in modes.names:
    right.plot(modes.time, modes[name], label=name)
right.set_xlabel("t [s]")
right.set_ylabel("modal coordinate [kg^1/2 m]")
right.set_title("the 6 modes' coordinates")
right.legend(fontsize=8, ncol=2)
figure.tight_layout()
figure.savefig(picture, dpi=110)
print(f"wrote {picture}")

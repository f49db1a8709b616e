"""The installed flexbody package reads a body file and runs a scene of it: prints its version, how many modes the
file has, and how many steps a 10 ms swing of it took."""
import os
import sys

import flexbody

path = sys.argv[1]
scene = flexbody.Scene(os.path.dirname(path))
scene.add_body("bracket", file=os.path.basename(path))
scene.add_joint("pivot", type="revolute", body="bracket", interface="bore_1", axis=[0, 0, 1])
scene.gravity = [0, -9.81, 0]
scene.set_integrator(step=1e-3, end=0.01)
sim = scene.simulate()
sim.run()
print(flexbody.__version__, len(flexbody.read_body(path).frequencies_hz), sim.summary()["steps"])

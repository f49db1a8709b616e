#!/usr/bin/python3
"""Example 08: a parameter sweep from Python: the bracket pendulum's error against the step size, with a plot.

Each run is the same scene built in code with another integrator step; the error of bore_3's path is measured against
a run at a step 16 times smaller than the smallest swept, at the times every run records (every 8 ms).

    sweep.py BODY.fbh5 OUT.png [END_S]
"""
import sys
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

import flexbody

body_file = Path(sys.argv[1])
picture = sys.argv[2]
end = float(sys.argv[3]) if len(sys.argv) > 3 else 0.4
record = 8e-3  # s: every run records bore_3 at these times


def bore_path(step):
    scene = flexbody.Scene(base=body_file.parent)
    scene.add_body("bracket", file=body_file.name, modes=6)
    scene.add_joint("pivot", type="revolute", body="bracket", interface="bore_1", axis=[0, 0, 1])
    scene.gravity = [0, -9.81, 0]
    scene.set_integrator(rho_inf=0.9, step=step, end=end, output_every=round(record / step))
    scene.add_output("bore_3", body="bracket", interface="bore_3", quantities=["position"])
    sim = scene.simulate()
    bore = sim.run()["bore_3"]
    return bore.time, bore.values, sim.summary()


steps = [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4]
reference_time, reference, _ = bore_path(steps[-1] / 16)
errors, costs = [], []
print(f"{'step [s]':>10} {'error [m]':>10} {'us/step':>8}")
for h in steps:
    time, path, summary = bore_path(h)
    assert np.allclose(time, reference_time, rtol=0, atol=1e-12)
    errors.append(np.max(np.linalg.norm(path - reference, axis=1)))
    costs.append(summary["us_per_step"])
    print(f"{h:10.2e} {errors[-1]:10.3e} {costs[-1]:8.1f}")
order = np.polyfit(np.log(steps), np.log(errors), 1)[0]
print(f"fitted order: {order:.2f} (generalized-alpha is second order)")

figure, axes = plt.subplots(figsize=(6, 4.5))
axes.loglog(steps, errors, "o-", label=f"bore_3's largest error, fitted order {order:.2f}")
axes.loglog(steps, errors[0] * (np.array(steps) / steps[0]) ** 2, "--", color="gray", label="second order")
axes.set_xlabel("integrator step h [s]")
axes.set_ylabel("largest position error [m]")
axes.set_title(f"the bracket pendulum, {end:g} s of swing")
axes.legend()
figure.tight_layout()
figure.savefig(picture, dpi=110)
print(f"wrote {picture}")

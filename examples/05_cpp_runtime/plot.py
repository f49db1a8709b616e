#!/usr/bin/python3
"""Example 05's picture: the path of the bracket's third bore as pendulum.cpp printed it (t, x, y, z every 10 ms).

    plot.py PATH.csv OUT.png
"""
import sys

import matplotlib.pyplot as plt
import numpy as np

t, x, y, _ = np.loadtxt(sys.argv[1], delimiter=",", skiprows=1, unpack=True)
fig, (path, height) = plt.subplots(1, 2, figsize=(9, 4), dpi=100)
path.plot(1e3 * x, 1e3 * y, ".-", color="tab:blue", ms=3)
path.set_aspect("equal", adjustable="datalim")
path.set_xlabel("x [mm]")
path.set_ylabel("y [mm]")
path.set_title("bore_3 from pendulum.cpp, every 10 ms", fontsize=10)
height.plot(t, 1e3 * y, color="tab:blue")
height.set_xlabel("t [s]")
height.set_ylabel("y [mm]")
height.set_title("its height: the bracket swings about bore_1", fontsize=10)
fig.tight_layout()
fig.savefig(sys.argv[2])
print(f"wrote {sys.argv[2]}")

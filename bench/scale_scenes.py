"""The scenes of bench/scale_bench.py: chains and ladders of the sample bracket as fbsim YAML, its bores' marker
points read from the body file."""
import math

import h5py
import numpy as np

STEP = 1.0e-3  # [s]
KINDS = {  # kind -> the body entry's keys besides file and position
    "rigid": "modes: rigid",
    "gcms": "modes: 6",
    "ffrf": "modes: 6, formulation: ffrf",
}


# --------------------------------------------------------------------------------------------------- the bracket --

class Bracket:
    """What the scenes need from the body file: where the bores' markers sit in the input (CAD) frame.

    fbsim's interface marker is r_c = τ + A X̄_c (+ elastic terms, zero at the start) with X̄_c = y_row[1:4] in the body
    frame (origin at the centre of mass), and a scene's `position` is where the input frame's origin goes
    (τ = position + R c, c = /mass/center_of_mass_input). So, for orientation R, the marker is at
    position + R (c + X̄_c): `point(name)` is c + X̄_c.
    """

    def __init__(self, path):
        with h5py.File(path, "r") as f:
            self.com = np.array(f["mass"].attrs["center_of_mass_input"], dtype=float)
            self.bar = {}
            for name in ("bore_1", "bore_2"):
                group = f["interfaces"][name]
                y = np.array(group["y_row"], dtype=float)
                ref = np.array(group.attrs["reference_point"], dtype=float)
                if abs(y[0] - 1.0) > 1e-12 or np.max(np.abs(y[1:4] - ref)) > 1e-12:
                    raise SystemExit(f"{path}: interface {name}: y_row[1:4] {y[1:4]} is not its reference point {ref}")
                self.bar[name] = y[1:4]

    def point(self, name):
        return self.com + self.bar[name]


def rotation(axis, angle_deg):
    """Eigen's AngleAxisd(angle_deg * pi / 180, axis.normalized()).toRotationMatrix(), as fbsim's scene reader
    forms it."""
    u = np.asarray(axis, dtype=float)
    u = u / np.linalg.norm(u)
    a = angle_deg * math.pi / 180.0
    s_u, c = math.sin(a) * u, math.cos(a)
    c1 = (1.0 - c) * u
    r = np.diag(c1 * u + c)
    r[0, 1], r[1, 0] = c1[0] * u[1] - s_u[2], c1[0] * u[1] + s_u[2]
    r[0, 2], r[2, 0] = c1[0] * u[2] + s_u[1], c1[0] * u[2] - s_u[1]
    r[1, 2], r[2, 1] = c1[1] * u[2] - s_u[0], c1[1] * u[2] + s_u[0]
    return r


def vec(v):
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def common(end):
    """Gravity and the integrator; no outputs, no monitors, no ParaView."""
    return ("gravity: [0, -9.81, 0]\n"
            f"integrator: {{type: generalized-alpha, rho_inf: 0.9, step: {STEP!r}, end: {end!r}}}\n")


def chain_scene(body_file, bracket, kind, n, steps):
    """N brackets in a line along bore_1 -> bore_2 (about +x, 30 mm a link), all in the file's orientation."""
    d = bracket.point("bore_2") - bracket.point("bore_1")
    lines = ["bodies:"]
    for k in range(n):
        lines.append(f"  b{k}: {{file: {body_file}, {KINDS[kind]}, position: {vec(k * d)}}}")
    lines.append("joints:")
    lines.append("  j0: {type: revolute, body: b0, interface: bore_1, to: ground, axis: [0, 0, 1]}")
    for k in range(1, n):
        lines.append(f"  j{k}: {{type: revolute, body: b{k}, interface: bore_1, "
                     f"to: {{body: b{k - 1}, interface: bore_2}}, axis: [0, 0, 1]}}")
    return "\n".join(lines) + "\n" + common(steps * STEP), n, n


LADDER_TILT = 10.0  # [deg]: the rails start this far from hanging straight down (the ladder swings)


def ladder_scene(body_file, bracket, kind, links, steps, closing):
    """A hanging ladder of parallelogram four-bars: 3 links bodies, 4 links joints, `links` closed loops.

    Two rails of `links` brackets each hang from ground pivots 30 mm apart (rail a's and rail c's first bore_1, a
    revolute about z each), every rail bracket turned -90 + LADDER_TILT degrees about z (bore_1 -> bore_2 points down,
    tilted by LADDER_TILT so that the ladder swings); rail links are joined bore_2 -> bore_1 like the chain. Rung j
    (j = 1 .. links) is a bracket turned 90 degrees about x (its bore_1 -> bore_2 horizontal, along +x, and its
    centre of mass below that line) from rail a's node j to rail c's node j (node j: where link j-1's bore_2 meets
    link j's bore_1; the last node is the last links' bore_2). Loop j - 1 is ground or rung j - 1, the two rails' links
    j - 1 and rung j: a parallelogram (rungs stay parallel to the line of the pivots), far from its flat, singular
    shape. Positions follow from the bores' markers as in chain_scene, for the rotated bodies: a marker of a body
    turned by R at `position` p is at p + R (c + X̄_c).

    closing = "revolute": every joint a revolute about z. A planar loop of four revolutes has 3 redundant rows in 3D
    (its out-of-plane force and tilting moments are counted twice); fbsim refuses that for rigid bodies. Flexible
    bodies' elastic coordinates may make the rows independent, and fbsim then runs it (stiff, statically
    indeterminate loops).
    closing = "spherical": the usual fix: every rung hangs between two spherical joints (RSSR-like loops), 4 rows fewer
    per loop: the 3 redundant ones and one more, which frees an idle spin of the rung about its bore-to-bore line
    (a stable pendulum: its centre of mass hangs below the line). The rails keep their revolutes, which hold them in
    the plane.
    """
    ra = rotation([0, 0, 1], -90.0 + LADDER_TILT)
    rr = rotation([1, 0, 0], 90.0)
    p1, p2 = bracket.point("bore_1"), bracket.point("bore_2")
    d = p2 - p1
    rung = rr @ d  # rail c's offset from rail a
    rail = [k * (ra @ d) for k in range(links)]  # rail a's positions (link 0's input-frame origin at the world origin)
    node = [rail[k] + ra @ p1 for k in range(links)] + [rail[links - 1] + ra @ p2]  # rail a's nodes, world
    lines = ["bodies:"]
    tilt = -90.0 + LADDER_TILT
    for name, offset in (("a", np.zeros(3)), ("c", rung)):
        for k in range(links):
            lines.append(f"  {name}{k}: {{file: {body_file}, {KINDS[kind]}, position: {vec(rail[k] + offset)}, "
                         f"rotation: {{axis: [0, 0, 1], angle_deg: {tilt!r}}}}}")
    for j in range(1, links + 1):
        origin = node[j] - rr @ p1  # the rung's input-frame origin: its bore_1 marker lands on rail a's node j
        lines.append(f"  r{j}: {{file: {body_file}, {KINDS[kind]}, position: {vec(origin)}, "
                     "rotation: {axis: [1, 0, 0], angle_deg: 90.0}}")
    joints = []
    for name in ("a", "c"):
        joints.append(f"{name}0: {{type: revolute, body: {name}0, interface: bore_1, to: ground, axis: [0, 0, 1]}}")
    for name in ("a", "c"):
        for k in range(1, links):
            joints.append(f"{name}{k}: {{type: revolute, body: {name}{k}, interface: bore_1, "
                          f"to: {{body: {name}{k - 1}, interface: bore_2}}, axis: [0, 0, 1]}}")
    for j in range(1, links + 1):
        on = (lambda rail_name: f"{{body: {rail_name}{j}, interface: bore_1}}") if j < links else \
             (lambda rail_name: f"{{body: {rail_name}{links - 1}, interface: bore_2}}")
        axis = ", axis: [0, 0, 1]" if closing == "revolute" else ""
        joints.append(f"r{j}a: {{type: {closing}, body: r{j}, interface: bore_1, to: {on('a')}{axis}}}")
        joints.append(f"r{j}c: {{type: {closing}, body: r{j}, interface: bore_2, to: {on('c')}{axis}}}")
    lines.append("joints:")
    lines += ["  " + j for j in joints]
    return "\n".join(lines) + "\n" + common(steps * STEP), 3 * links, len(joints)

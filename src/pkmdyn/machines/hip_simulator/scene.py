"""The hip simulator as a report scene and a topology (``pkmdyn.report``).

Points, base frame [m]: the screw feet ``A{i}`` and tops ``T{i}``, the slider U joints
``U{j}{i} = A_i + L_ji e_z`` (platform j, module i), the platform S joints
``S{j}{i} = o_j + R r_a_i`` and the platform centres ``O{j}`` (the central S joints). Bodies:
each platform a filled triangle of its S joints with spokes to its centre, each lever from its
U joint to its S joint, the screws and the centre post as ground. The two sliders of a module
are one carriage, drawn from the lower to the upper U joint in the colour of its motor torque.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...analysis.mobility import Joint, analyse
from ...report import Scene, SceneActuator, SceneBody, Topology
from ...spatial import euler_to_matrix
from .kinematics import _platform_kinematics
from .params import HipModel

__all__ = ["hip_scene", "hip_scene_from_angles", "hip_topology", "hip_joints", "hip_mobility", "CUT_JOINTS"]

Array = NDArray[np.float64]

#: the joints opened to leave a spanning tree (as in the Pinocchio reference): the six lever-platform S joints
CUT_JOINTS = tuple(f"S{j}{i}" for j in (1, 2) for i in (1, 2, 3))


def _names() -> list[str]:
    names = [f"A{i}" for i in (1, 2, 3)] + [f"T{i}" for i in (1, 2, 3)] + ["base centre"]
    names += [f"U{j}{i}" for j in (1, 2) for i in (1, 2, 3)]
    names += [f"S{j}{i}" for j in (1, 2) for i in (1, 2, 3)]
    return names + ["O1", "O2"]


def hip_scene(model: HipModel, t: Array, R: Array, L: Array, tau: Array) -> Scene:
    """The scene along a motion: ``t (n,)`` [s], platform rotation ``R (n, 3, 3)``, slider
    positions ``L (n, 2, 3)`` [m] [sample, platform, module], motor torques ``tau (n, 3)`` [N m]."""
    g = model.geometry
    n = t.shape[0]
    names = _names()
    ix = {name: k for k, name in enumerate(names)}
    P = np.zeros((n, len(names), 3))
    top = float(np.max(L[:, 0, :])) + 0.25 * g.l
    for i in range(3):
        P[:, ix[f"A{i + 1}"]] = g.A[i]
        P[:, ix[f"T{i + 1}"]] = g.A[i] + np.array([0.0, 0.0, top])
        for j in range(2):
            P[:, ix[f"U{j + 1}{i + 1}"]] = g.A[i]
            P[:, ix[f"U{j + 1}{i + 1}"], 2] = L[:, j, i]
            P[:, ix[f"S{j + 1}{i + 1}"]] = g.o[j] + R @ g.r_a[i]
    for j in range(2):
        P[:, ix[f"O{j + 1}"]] = g.o[j]
    bodies = []
    for j in (1, 2):
        s = tuple(ix[f"S{j}{i}"] for i in (1, 2, 3))
        bodies.append(SceneBody(f"platform {j}", s, closed=True, filled=True))
        bodies.append(SceneBody(f"platform {j} spokes", (s[0], ix[f"O{j}"], s[1])))
        bodies.append(SceneBody(f"platform {j} spoke 3", (ix[f"O{j}"], s[2])))
        for i in (1, 2, 3):
            bodies.append(SceneBody(f"lever {j}{i}", (ix[f"U{j}{i}"], ix[f"S{j}{i}"])))
    for i in (1, 2, 3):
        bodies.append(SceneBody(f"screw {i}", (ix[f"A{i}"], ix[f"T{i}"]), ground=True))
    bodies.append(SceneBody("centre post", (ix["base centre"], ix["O2"], ix["O1"]), ground=True))
    acts = tuple(SceneActuator(f"module {i + 1}", (ix[f"U2{i + 1}"], ix[f"U1{i + 1}"]), tau[:, i],
                               f"motor {i + 1} torque", "N m") for i in range(3))
    joints = tuple(ix[k] for k in names if k[0] in "USO")
    return Scene(t, P, tuple(names), tuple(bodies), acts, path_point=ix["S11"], joint_points=joints)


def hip_scene_from_angles(model: HipModel, t: Array, angles: Array, tau: Array) -> Scene:
    """The scene from platform Euler angles ``angles (n, 3)`` [rad] (the model's sequence) and
    motor torques ``tau (n, 3)`` [N m]; the slider positions from the inverse kinematics (Eq. 2)."""
    R = euler_to_matrix(model.geometry.euler_sequence, np.asarray(angles, dtype=float))
    zero = np.zeros((t.shape[0], 3))
    kin = _platform_kinematics(model, np.asarray(t, dtype=float), R, zero, zero, check_conditioning=False)
    return hip_scene(model, t, R, kin.L, tau)


def hip_topology() -> Topology:
    """Bodies ground, platform1-2, module1-3 (the two sliders of a screw), lever11-23; joints:
    the platforms' central S joints, the screw-driven P joints (actuated), the U joints of the
    levers on the modules and the S joints of the levers on the platforms (cut)."""
    joints = [("S1", "S", "ground", "platform1"), ("S2", "S", "ground", "platform2")]
    joints += [(f"P{i}", "P", "ground", f"module{i}") for i in (1, 2, 3)]
    joints += [(f"U{j}{i}", "U", f"module{i}", f"lever{j}{i}") for j in (1, 2) for i in (1, 2, 3)]
    joints += [(f"S{j}{i}", "S", f"lever{j}{i}", f"platform{j}") for j in (1, 2) for i in (1, 2, 3)]
    return Topology(tuple(joints), "ground", ("P1", "P2", "P3"), CUT_JOINTS)


def hip_joints(model: HipModel) -> list[Joint]:
    """The joints of :func:`hip_topology` at the home pose (R = I), with points and axes, for
    :func:`pkmdyn.analysis.mobility.analyse`."""
    g = model.geometry
    eye = np.eye(3)[None]
    zero = np.zeros((1, 3))
    kin = _platform_kinematics(model, np.zeros(1), eye, zero, zero, check_conditioning=False)

    def pt(v: Array) -> tuple[float, float, float]:
        return (float(v[0]), float(v[1]), float(v[2]))

    z = (0.0, 0.0, 1.0)
    out = [Joint(f"S{j + 1}", "S", "ground", f"platform{j + 1}", pt(g.o[j])) for j in range(2)]
    out += [Joint(f"P{i + 1}", "P", "ground", f"module{i + 1}", pt(g.A[i]), (z,)) for i in range(3)]
    for j in range(2):
        for i in range(3):
            b = g.A[i] + np.array([0.0, 0.0, kin.L[0, j, i]])
            out.append(Joint(f"U{j + 1}{i + 1}", "U", f"module{i + 1}", f"lever{j + 1}{i + 1}", pt(b),
                             (pt(g.t[i]), pt(kin.R_lever[0, i][:, 0]))))
    for j in range(2):
        for i in range(3):
            out.append(Joint(f"S{j + 1}{i + 1}", "S", f"lever{j + 1}{i + 1}", f"platform{j + 1}",
                             pt(g.o[j] + g.r_a[i])))
    return out


def hip_mobility(model: HipModel) -> dict[str, object]:
    """Mobility and over-constraint counts at the home pose (screw theory and Eq. 1 style count)."""
    rep = analyse(hip_joints(model), "ground", "platform1")
    return {"joint counts": rep.joint_counts, "moving links": rep.moving_links,
            "mobility (screw theory, home pose)": rep.mobility, "degrees of freedom of platform 1": rep.output_dof,
            "over-constraints (screw theory)": rep.overconstraints,
            "over-constraints (Eq. 1 count, t = 3S + 4U + 5R + 5P + A - 6n)": rep.eq1_overconstraints,
            "Kutzbach-Gruebler mobility": rep.kutzbach}

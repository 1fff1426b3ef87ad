"""The 4-DOF parallel driving mechanism as a described mechanism, made from its parameters.

The generic engine (:mod:`pkmdyn.multibody`) solves it for every PDM command (``pkmdyn pdm
run``, ``pdm control``, ``sweep --machine pdm``, ``pkmdyn run --machine pdm``); the
hand-derived kinematics of :mod:`.kinematics` (Eq. 2-48) place its bodies and joints, and the
hand-derived dynamics (Eq. 49-83) are its test oracle (``tests/oracles/pdm_newton_euler.py``).
Described at a reference pose (default: home, q = 0): the 14 bodies with
the frames of :class:`.kinematics.BodyState` (origin at the centre of mass, docs/pdm4.md) and
their masses and inertias; the joints of Table I as :func:`.kinematics.mechanism_joints`
gives them at that pose (R2i, the compound joint, as crank-coupler R2i and crank-piston R2i'),
each at the paper's centre (:func:`.kinematics.joint_points`: a revolute joint between two
planar layers half-way between them, a prismatic joint at the cylinder's mouth); the four
prismatic joints actuated, each coordinate the limb length (fixed to moving joint); the
task: x, y of the platform point P and the angles alpha (about the base z axis) and gamma
(about the platform x axis), i.e. the first two angles of the intrinsic sequence ZXY since
``T = Rz(alpha) Rx(gamma)`` (Eq. 3). The cut joints are the paper's, R21', R22', R32, U23
and U24, so the nine over-constrained directions come out at R21', R22' and R32. The nine
elastic links carry their sections and material (beams along their x axis, section 4.2) and
the prismatic joints sit at the cylinders' mouths, so that the generic reactions made unique
by compliance are the paper's (Eq. 63-83).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ...profiles.pdm_motion import PdmMotion
from .inertia import ELASTIC_BODIES
from .kinematics import BODY_NAMES, inverse_kinematics, joint_points, mechanism_joints
from .paper import JOINTS
from .params import PdmModel

__all__ = ["pdm_description", "CUT_JOINTS"]

_JOINT_NAMES = [j[0] for j in JOINTS]
#: the joints opened to leave the spanning tree of the dynamics (one per independent loop)
CUT_JOINTS = ("R21'", "R22'", "R32", "U23", "U24")
_TYPES = {"R": "revolute", "P": "prismatic", "S": "spherical", "U": "universal"}


def _xyz_deg(R: np.ndarray) -> list[float]:
    """Intrinsic XYZ angles [deg] with ``R = Rx(a) Ry(b) Rz(c)``."""
    b = math.asin(max(-1.0, min(1.0, float(R[0, 2]))))
    a = math.atan2(-float(R[1, 2]), float(R[2, 2]))
    c = math.atan2(-float(R[0, 1]), float(R[0, 0]))
    return [math.degrees(a), math.degrees(b), math.degrees(c)]


def pdm_description(model: PdmModel, q_ref: np.ndarray | None = None) -> dict[str, Any]:
    """The description (a dict in the format of ``docs/mechanism_format.md``) of ``model`` at
    the reference pose ``q_ref`` (4,) = (x [m], y [m], alpha [rad], gamma [rad])."""
    q = np.zeros(4) if q_ref is None else np.asarray(q_ref, dtype=float)
    kin = inverse_kinematics(model, PdmMotion(np.zeros(1), q[None], np.zeros((1, 4)), np.zeros((1, 4))),
                             check_strokes=False)
    bodies = []
    for b, name in enumerate(BODY_NAMES):
        st = kin.bodies[b]
        I = model.inertia[b]
        bodies.append({"name": name, "mass_kg": float(model.mass[b]), "com_m": [0.0, 0.0, 0.0],
                       "inertia_kgm2": [[float(v) for v in row] for row in I],
                       "frame_origin_m": [float(v) for v in st.p[0]], "frame_euler_deg": _xyz_deg(st.R[0])})
        if name in ELASTIC_BODIES:  # the links of the over-constrained loops, beams along their x axis
            bodies[-1]["section"] = {"outer_diameter_m": float(model.section_outer[b]),
                                     "inner_diameter_m": float(model.section_inner[b]), "beam_axis": "body_x"}
            bodies[-1]["material"] = {"youngs_modulus_Pa": float(model.youngs_modulus_Pa),
                                      "poisson_ratio": float(model.poisson_ratio)}
    # the prismatic joints' centres at the cylinder's mouth, 2 c1 from its fixed joint (as the
    # reactions of .kinematics.joint_points): the node of the cylinder and piston beams, on both
    # at the mouth (bearing: the cylinder), so the stroke changes the piston's free length (Eq. 63)
    centres = joint_points(model, kin)[0]
    lengths = {"P11": kin.pos.l[0, 0], "P12": kin.pos.l[0, 1], "P23": kin.pos.l[0, 2], "P24": kin.pos.l[0, 3]}
    joints = []
    for j in mechanism_joints(model, q):
        point = centres[_JOINT_NAMES.index(j.name)]
        entry: dict[str, Any] = {"name": j.name, "type": _TYPES[j.kind], "parent": j.body_a, "child": j.body_b,
                                 "point_m": [float(v) for v in point]}
        if j.kind in ("R", "P"):
            entry["axis"] = [float(v) for v in j.axes[0]]
        elif j.kind == "U":
            entry["axes"] = [[float(v) for v in a] for a in j.axes]
        if j.kind == "P":
            entry["actuated"] = True
            entry["position_at_reference_m"] = float(lengths[j.name])
            entry["bearing"] = j.body_a
        joints.append(entry)
    return {
        "mechanism": {"name": "pdm", "source": "4-DOF parallel driving mechanism, Huang et al. (2023); docs/pdm4.md",
                      "gravity_m_s2": [float(v) for v in model.gravity], "cut_joints": list(CUT_JOINTS)},
        "bodies": bodies,
        "joints": joints,
        "task": {"body": "platform", "point_m": [float(v) for v in kin.pos.P[0]], "position": ["x", "y"],
                 "euler_sequence": "ZXY", "orientation": [1, 2]},
    }

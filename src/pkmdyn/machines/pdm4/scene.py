"""The PDM as a report scene and a topology (``pkmdyn.report``).

The scene is the generic one of :func:`pkmdyn.report.scene_from_joints`: every body drawn
through its joint centres (``kinematics.joint_points``, the ``joint_point`` of ``bodies.npz``),
the platform as a filled triangle R4-U23-U24, each limb (cylinder and piston) as one chain in
the colour of its actuator force, and the path of the platform point P.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...analysis.mobility import analyse
from ...profiles.pdm_motion import PdmMotion
from ...report import Scene, Topology, scene_from_joints
from .description import CUT_JOINTS
from .kinematics import inverse_kinematics, joint_points, mechanism_joints
from .paper import JOINTS
from .params import PdmModel

__all__ = ["pdm_scene", "pdm_scene_from_pose", "pdm_topology", "pdm_mobility", "ACTUATED_JOINTS", "CUT_JOINTS"]

Array = NDArray[np.float64]

#: the prismatic joints driven by the actuators, in the order of the forces ``f1_N .. f4_N``
ACTUATED_JOINTS = ("P11", "P12", "P23", "P24")
_LIMBS = ("l11", "l12", "l23", "l24")


def pdm_scene(t: Array, joint_point: Array, force: Array, P: Array | None = None) -> Scene:
    """The scene along a motion: ``t (n,)`` [s]; ``joint_point (n, 19, 3)`` [m] in ``JOINTS``
    order; ``force (n, 4)`` [N] the actuator forces; ``P (n, 3)`` [m] the platform point (its
    path is drawn) or None."""
    actuated = {j: (force[:, k], f"limb {_LIMBS[k]} force", "N") for k, j in enumerate(ACTUATED_JOINTS)}
    extra = {"P (platform point)": P} if P is not None else None
    return scene_from_joints(t, joint_point, JOINTS, actuated, extra_points=extra,
                             path_point="P (platform point)" if P is not None else None)


def pdm_scene_from_pose(model: PdmModel, t: Array, q: Array, force: Array) -> Scene:
    """The scene from poses ``q (n, 4)`` = (x [m], y [m], alpha [rad], gamma [rad]) and actuator
    forces ``force (n, 4)`` [N]; the joint centres from the inverse kinematics."""
    t = np.asarray(t, dtype=float)
    q = np.asarray(q, dtype=float)
    zero = np.zeros_like(q)
    kin = inverse_kinematics(model, PdmMotion(t, q, zero, zero))
    return pdm_scene(t, joint_points(model, kin), force, kin.pos.P)


def pdm_topology() -> Topology:
    """The 14 moving bodies and 19 joints of ``paper.JOINTS``; the four limb P joints actuated."""
    return Topology(tuple(JOINTS), "ground", ACTUATED_JOINTS, CUT_JOINTS)


def pdm_mobility(model: PdmModel) -> dict[str, object]:
    """Mobility and over-constraint counts at the home pose (screw theory and Eq. 1)."""
    rep = analyse(mechanism_joints(model), "ground", "platform")
    return {"joint counts": rep.joint_counts, "moving links": rep.moving_links,
            "mobility (screw theory, home pose)": rep.mobility, "degrees of freedom of the platform": rep.output_dof,
            "over-constraints (screw theory)": rep.overconstraints,
            "over-constraints (Eq. 1 count, t = 3S + 4U + 5R + 5P + A - 6n)": rep.eq1_overconstraints,
            "Kutzbach-Gruebler mobility": rep.kutzbach}

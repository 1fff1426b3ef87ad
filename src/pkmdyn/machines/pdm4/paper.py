"""The PDM paper's view of the engine's results: the columns of ``results.csv`` and the arrays of
``bodies.npz`` in the paper's names (docs/pdm4.md), read off the generic kinematics and joint
reactions of the PDM's description (:func:`.description.pdm_description`).

Nothing here solves the mechanism: :func:`pkmdyn.multibody.solve_kinematics` and
:func:`pkmdyn.multibody.dynamics.joint_reactions` do, for the PDM as for any described mechanism. This
module renames and re-expresses what they give:

- the crank and coupler angles ``theta_1i, theta_2i`` (Eq. 7, 12) and the RPR limb angles
  ``phi_i`` (Eq. 17) are the planar bodies' rotations ``Rz(theta)`` about the base z axis, their
  rates the z components of the bodies' angular velocities and accelerations;
- the SPU limbs' z-x-z angles ``(a, b, g)`` (Eq. 23-27): the limb body's x axis is the limb
  direction ``Q`` and its y axis the second U-joint axis ``U_j2``, so ``a = atan2(Q_x, -Q_y)``,
  ``b = acos(Q_z)``, ``g = atan2(U2_z, (Q x U2)_z)``; their rates from the body's angular
  velocity and acceleration by the inverse of Eq. 30-32 (``w = J_t e_dot``,
  ``wd = J_t e_ddot + J_t_dot e_dot``);
- the joint wrenches as the paper writes them: what ``body_a`` of each joint in :data:`JOINTS`
  exerts on ``body_b`` (the engine gives what the parent exerts on the child), the nine
  over-constrained components of Eq. 70 (``f_z, m_x, m_y`` of R21', R22', R32, base frame,
  moment about the joint point) and the U-joint constraint torques along
  ``U_j3 = U_j1 x U_j2`` (Eq. 28, 58).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ...errors import SingularityError

__all__ = ["BODY_NAMES", "JOINTS", "LIMBS", "LIMB_LABELS", "REDUNDANT_LABELS", "results_columns",
           "dynamics_columns", "bodies_arrays", "loop_gap", "planar_angle", "paper_wrenches"]

Array = NDArray[np.float64]

#: the 14 bodies, in the order of ``bodies.npz``
BODY_NAMES = (
    "platform", "link4", "crank1", "crank2", "coupler1", "coupler2",
    "cylinder1", "cylinder2", "cylinder3", "cylinder4", "piston1", "piston2", "piston3", "piston4",
)
#: every joint: (name, type, body_a, body_b); a file's reaction is what body_a exerts on body_b.
#: R2i is a compound joint (crank-coupler R2i and crank-piston R2i').
JOINTS: tuple[tuple[str, str, str, str], ...] = (
    ("R11", "R", "ground", "crank1"), ("R12", "R", "ground", "crank2"),
    ("R21", "R", "crank1", "coupler1"), ("R22", "R", "crank2", "coupler2"),
    ("R21'", "R", "crank1", "piston1"), ("R22'", "R", "crank2", "piston2"),
    ("R31", "R", "coupler1", "link4"), ("R32", "R", "coupler2", "link4"),
    ("R41", "R", "ground", "cylinder1"), ("R42", "R", "ground", "cylinder2"),
    ("P11", "P", "cylinder1", "piston1"), ("P12", "P", "cylinder2", "piston2"),
    ("R4", "R", "link4", "platform"),
    ("S23", "S", "ground", "cylinder3"), ("S24", "S", "ground", "cylinder4"),
    ("P23", "P", "cylinder3", "piston3"), ("P24", "P", "cylinder4", "piston4"),
    ("U23", "U", "platform", "piston3"), ("U24", "U", "platform", "piston4"),
)
#: the actuated joints (limb lengths l11, l12, l23, l24), in the order of the ``k`` of ``l{k}_m``
LIMBS = ("P11", "P12", "P23", "P24")
LIMB_LABELS = ("limb 1 (RPR, l11)", "limb 2 (RPR, l12)", "limb 3 (SPU, l23)", "limb 4 (SPU, l24)")
#: the nine over-constrained components (Eq. 70, Fig. 22): force along z and moments about x, y
#: (base frame, moment about the joint point) of the reaction at R21' (crank 1 on piston 1), R22'
#: and R32 (coupler 2 on the output link)
REDUNDANT_LABELS = tuple(f"{j}_{c}" for j in ("R21", "R22", "R32") for c in ("fz_N", "mx_Nm", "my_Nm"))
_XYZ = "xyz"
_EULER = ("alpha", "beta", "gamma")


def _vec(cols: dict[str, Array], prefix: str, unit: str, v: Array) -> None:
    for c in range(3):
        cols[f"{prefix}{_XYZ[c]}_{unit}"] = v[:, c]


def planar_angle(R: Array) -> Array:
    """theta of ``R = Rz(theta)`` (n, 3, 3) -> (n,), in (-pi, pi]."""
    return np.arctan2(R[:, 1, 0], R[:, 0, 0])


def _spu_euler(R: Array, w: Array, wd: Array, t: Array | None, limb: str) -> tuple[Array, Array, Array]:
    """z-x-z angles (n, 3) of an SPU limb body and their first and second rates (Eq. 23-32).
    Raises :class:`~pkmdyn.errors.SingularityError` naming the sample and the limb where the limb
    is parallel to the base z axis (the angles' singularity, ``sin b < 1e-6``)."""
    Q, U2, Y = R[:, :, 0], R[:, :, 1], R[:, :, 2]
    bad = np.flatnonzero(np.hypot(Q[:, 0], Q[:, 1]) < 1e-6)
    if bad.size:
        s = int(bad[0])
        when = f"t = {t[s]:.6g} s" if t is not None else f"sample {s + 1}"
        raise SingularityError(f"{when}: {limb} is parallel to the base z axis (Euler singularity)")
    a = np.arctan2(Q[:, 0], -Q[:, 1])
    b = np.arccos(np.clip(Q[:, 2], -1.0, 1.0))
    g = np.arctan2(U2[:, 2], Y[:, 2])
    ca, sa, cb, sb = np.cos(a), np.sin(a), np.cos(b), np.sin(b)
    zero, one = np.zeros_like(a), np.ones_like(a)
    Jt = np.stack([np.stack([zero, ca, sa * sb], -1), np.stack([zero, sa, -ca * sb], -1),
                   np.stack([one, zero, cb], -1)], -2)
    ed = np.linalg.solve(Jt, w[..., None])[..., 0]
    ad, bd = ed[:, 0], ed[:, 1]
    Jtd = np.stack([np.stack([zero, -sa * ad, ca * sb * ad + sa * cb * bd], -1),
                    np.stack([zero, ca * ad, sa * sb * ad - ca * cb * bd], -1),
                    np.stack([zero, zero, -sb * bd], -1)], -2)
    edd = np.linalg.solve(Jt, (wd - np.einsum("nab,nb->na", Jtd, ed))[..., None])[..., 0]
    return np.stack([a, b, g], -1), ed, edd


def loop_gap(m, kin) -> Array:
    """(n,) [m]: the largest distance between the two bodies' points of a cut joint, the
    loops' closure error in metres."""
    gap = np.zeros(len(kin.x))
    for k in np.flatnonzero(m.joint_cut):
        pts = []
        for body, local in ((m.joint_parent[k], m.joint_p_parent[k]), (m.joint_child[k], m.joint_p_child[k])):
            if body < 0:
                pts.append(np.broadcast_to(local, (len(gap), 3)))
            else:
                pts.append(kin.origin[:, body] + np.einsum("nij,j->ni", kin.R[:, body], local))
        gap = np.maximum(gap, np.linalg.norm(pts[0] - pts[1], axis=1))
    return gap


def results_columns(m, kin, home_lengths: Array) -> dict[str, Array]:
    """The kinematics' columns of ``results.csv`` (names in docs/pdm4.md) from the engine's
    kinematics ``kin`` of the PDM's description ``m``; ``home_lengths`` (4,) [m] the limb lengths
    at home (the extensions ``s{k}_m`` are measured from them)."""
    body = {name: m.body_index(name) for name in BODY_NAMES}
    limbs = [m.actuator_names.index(n) for n in LIMBS]
    cols: dict[str, Array] = {"t_s": kin.t}
    for k, name in enumerate(("x_m", "y_m", "alpha_rad", "gamma_rad")):
        cols[name] = kin.x[:, k]
    for k, a in enumerate(limbs):
        cols[f"l{k + 1}_m"] = kin.act_q[:, a]
        cols[f"ld{k + 1}_m_s"] = kin.act_qd[:, a]
        cols[f"ldd{k + 1}_m_s2"] = kin.act_qdd[:, a]
    for k, name in enumerate(("xd_m_s", "yd_m_s", "alphad_rad_s", "gammad_rad_s")):
        cols[name] = kin.xd[:, k]
    for k, name in enumerate(("xdd_m_s2", "ydd_m_s2", "alphadd_rad_s2", "gammadd_rad_s2")):
        cols[name] = kin.xdd[:, k]
    tb = m.task_body
    cols["z_m"] = kin.origin[:, tb, 2] + np.einsum("nj,j->n", kin.R[:, tb, 2], m.task_point)
    for k, a in enumerate(limbs):
        cols[f"s{k + 1}_m"] = kin.act_q[:, a] - home_lengths[k]
    for i in range(2):
        for sym, name in ((f"crank{i + 1}_theta", f"crank{i + 1}"), (f"coupler{i + 1}_theta", f"coupler{i + 1}"),
                          (f"rpr{i + 1}_phi", f"cylinder{i + 1}")):
            b = body[name]
            cols[f"{sym}_rad"] = planar_angle(kin.R[:, b])
            cols[f"{sym}d_rad_s"] = kin.w[:, b, 2]
            cols[f"{sym}dd_rad_s2"] = kin.wd[:, b, 2]
    for j in range(2):
        b = body[f"cylinder{j + 3}"]
        e, ed, edd = _spu_euler(kin.R[:, b], kin.w[:, b], kin.wd[:, b], kin.t, LIMB_LABELS[j + 2])
        for c in range(3):
            base = f"spu{j + 3}_{_EULER[c]}"
            cols[f"{base}_rad"] = e[:, c]
            cols[f"{base}d_rad_s"] = ed[:, c]
            cols[f"{base}dd_rad_s2"] = edd[:, c]
    for name in BODY_NAMES:
        b = body[name]
        _vec(cols, f"{name}_p", "m", kin.p[:, b])
        _vec(cols, f"{name}_v", "m_s", kin.v[:, b])
        _vec(cols, f"{name}_a", "m_s2", kin.a[:, b])
        _vec(cols, f"{name}_w", "rad_s", kin.w[:, b])
        _vec(cols, f"{name}_wd", "rad_s2", kin.wd[:, b])
    cols["loop_residual_m"] = loop_gap(m, kin)
    return cols


def paper_wrenches(m, kin, reac) -> tuple[Array, Array, Array]:
    """Points, forces and moments (n, 19, 3) of :data:`JOINTS`: what body_a exerts on body_b,
    about the joint's centre fixed in body_a (a prismatic joint's at the cylinder's mouth), base
    frame."""
    n = len(kin.x)
    pts, force, moment = (np.empty((n, len(JOINTS), 3)) for _ in range(3))
    for j, (name, _, a, _) in enumerate(JOINTS):
        k = m.joint_index(name)
        parent = m.joint_parent[k]
        on_parent = (m.body_names[parent] if parent >= 0 else "ground") == a
        body, local = (parent, m.joint_p_parent[k]) if on_parent else (m.joint_child[k], m.joint_p_child[k])
        pts[:, j] = local if body < 0 else kin.origin[:, body] + np.einsum("nij,j->ni", kin.R[:, body], local)
        sg = 1.0 if on_parent else -1.0
        f = sg * reac.joint_force[:, k]
        force[:, j] = f
        moment[:, j] = sg * reac.joint_moment[:, k] + np.cross(reac.joint_point[:, k] - pts[:, j], f)
    return pts, force, moment


def dynamics_columns(m, kin, reac, wrenches: tuple[Array, Array, Array], u1_local: Array) -> dict[str, Array]:
    """Actuator forces ``f{k}_N`` (k = 1..4, the order of ``l{k}_m``: the axial force that each
    cylinder exerts on its piston), the nine over-constrained reaction components
    (:data:`REDUNDANT_LABELS`) and the U-joint constraint torques ``U23_torque_Nm, U24_torque_Nm``
    (``wrenches``: :func:`paper_wrenches` of ``reac``; ``u1_local`` (3,): the U joints' first
    axis in the platform frame)."""
    cols: dict[str, Array] = {f"f{k + 1}_N": reac.u[:, m.actuator_names.index(n)] for k, n in enumerate(LIMBS)}
    _, f, mo = wrenches
    names = [j[0] for j in JOINTS]
    for r, joint in enumerate(("R21'", "R22'", "R32")):
        j = names.index(joint)
        for c, v in enumerate((f[:, j, 2], mo[:, j, 0], mo[:, j, 1])):
            cols[REDUNDANT_LABELS[3 * r + c]] = v
    U1 = kin.R[:, m.body_index("platform")] @ np.asarray(u1_local, dtype=float)
    for j in range(2):
        U2 = kin.R[:, m.body_index(f"cylinder{j + 3}"), :, 1]
        U3 = np.cross(U1, U2)
        cols[f"U2{j + 3}_torque_Nm"] = np.einsum("nc,nc->n", mo[:, names.index(f"U2{j + 3}")], U3)
    return cols


def bodies_arrays(m, kin, wrenches: tuple[Array, Array, Array]) -> dict[str, Array]:
    """``bodies.npz``'s arrays of one block: ``R, p, v, w, a, wd`` (n, 14, ...) in
    :data:`BODY_NAMES` order and ``joint_point, joint_force, joint_moment`` (n, 19, 3) in
    :data:`JOINTS` order (``wrenches``: :func:`paper_wrenches`)."""
    b = [m.body_index(name) for name in BODY_NAMES]
    out = {f: getattr(kin, f)[:, b] for f in ("R", "p", "v", "w", "a", "wd")}
    out["joint_point"], out["joint_force"], out["joint_moment"] = wrenches
    return out

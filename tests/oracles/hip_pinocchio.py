"""Independent reference for the hip simulator's motor torques, built on Pinocchio.

The closed-form oracle (:mod:`oracles.hip`, Eq. 7-16) projects every body's
required wrench onto the platforms' angular velocity by virtual work. This module reaches the
same torques by a different route that shares no formula with it:

1. The machine is cut open into a *spanning tree* (:func:`build_tree`)::

       universe -+- platform j (spherical joint about o_j)                       j = 1, 2
                 +- module i (prismatic along +Z at A_i, carries both sliders)   i = 1, 2, 3
                       +- U joint (j, i): revolute about t_i -> revolute about the lever's x
                             -> lever (j, i)

   and the six S joints become loop-closure constraints: the lever tip ``b_ji + l z_lever``
   coincides with the platform point ``o_j + R r_a_i`` (3 equations each, 18 in all).

2. For each sample the tree state is reconstructed from the prescribed platform motion
   ``(R, omega, omega_dot)`` with Pinocchio's own kinematics: the configuration ``q`` that
   closes every loop (Newton iteration on ``phi(q) = 0``), then the velocity ``v`` and the
   acceleration ``a`` that satisfy ``G v = 0`` and ``G a + gamma = 0`` (``G = d phi / d q``,
   ``gamma`` the classical-acceleration drift), with the platforms' entries prescribed.

3. The constrained inverse dynamics is the square linear system (21 x 21)::

       rnea(q, v, a) + Q_f = S^T f + G^T lambda

   where ``rnea`` is Pinocchio's recursive Newton-Euler algorithm (gravity included), ``Q_f``
   the generalized friction forces (what the joints resist with, projected on the tree's
   velocities), ``S`` selects the three prismatic joints (actuated), ``f`` [N] the screw forces
   on the modules and ``lambda`` the 18 closure forces. The platforms' spherical joints are
   unactuated.

4. The lead screw converts the force: ``tau_i = (p / 2 pi) f_i + I_L (2 pi / p) Lddot_i +
   tau_screw_friction_i`` [N m] (the rotor inertia is not part of the tree).

Units are SI throughout; every vector is expressed in the base frame O-XYZ unless a name says
otherwise. Pinocchio's spherical joint uses the *local* (platform-frame) angular velocity:
``v_platform = R^T omega``, ``a_platform = R^T omega_dot``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

if TYPE_CHECKING:  # the parameters' container only: every formula here is the oracle's own
    from pkmdyn.machines.hip_simulator.params import HipModel

__all__ = [
    "TreeInfo",
    "build_tree",
    "closure_residual",
    "solve_state",
    "reference_torques",
    "spanning_tree_rnea_inputs",
]

Array = NDArray[np.float64]

#: the closure residual that a reconstructed configuration must reach [m]
CLOSURE_TOLERANCE_M = 1e-10

_WORLD = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


@dataclass(frozen=True)
class TreeInfo:
    """Indices into the spanning tree built by :func:`build_tree`.

    Joint ids (Pinocchio ``JointIndex``), frame ids and velocity indices. Array axes are
    ``[platform j, module i]`` (j = 0 upper, 1 lower) and, for the U joints, ``[j, i, k]`` with
    k = 0 the revolute about t_i and k = 1 the revolute about the lever's x axis.
    """

    platform_joint: tuple[int, int]  #: spherical joints of platforms 1, 2
    module_joint: tuple[int, int, int]  #: prismatic joints of modules 1, 2, 3
    u_joint: Array  #: (2, 3, 2) int, the two revolutes of each U joint
    tip_frame: Array  #: (2, 3) int, lever tip (S-joint centre on the lever side)
    socket_frame: Array  #: (2, 3) int, S-joint centre on the platform side
    platform_v: Array  #: (2, 3) int, velocity indices of the spherical joints
    module_v: Array  #: (3,) int, velocity indices of the prismatics
    u_v: Array  #: (2, 3, 2) int, velocity indices of the U revolutes
    free_v: Array  #: (15,) int, every velocity index not prescribed by the platform motion
    free_q: Array  #: (15,) int, the matching configuration indices (same order as ``free_v``)
    module_q: Array  #: (3,) int, configuration indices of the prismatics
    platform_q: Array  #: (2, 4) int, configuration indices of the platform quaternions (x, y, z, w)
    slider_offset: float  #: h1 - h2 [m], height of the upper slider above the lower one


def _u_joint_rotation(t_axis: Array) -> Array:
    """Placement rotation of a U joint's first revolute: columns ``(t x e_z, t, e_z)``.

    With this placement the first revolute turns about its local y (= t_i, fixed in the
    slider) and the second about the local x of the first's child frame; the lever frame is
    ``R0 Ry(q1) Rx(q2)``. Its x axis (the second U axis) is then perpendicular to t_i and to
    the lever's z axis, and points along ``t_i x z_lever`` for |q2| < 90 deg, which is the
    lever frame of the model specification.
    """
    ez = np.array([0.0, 0.0, 1.0])
    x = np.cross(t_axis, ez)
    x /= np.linalg.norm(x)
    return np.column_stack((x, t_axis, ez))


def _build(model: HipModel, include: frozenset[str]) -> tuple[pin.Model, TreeInfo]:
    g, m = model.geometry, model.inertia
    dh = float(g.h[0] - g.h[1])
    pm = pin.Model()
    pm.name = "hip_simulator_spanning_tree"
    pm.gravity = pin.Motion(np.array([0.0, 0.0, -m.g]), np.zeros(3))
    zero = pin.Inertia.Zero()

    platform_joint = []
    for j in range(2):
        jid = pm.addJoint(0, pin.JointModelSpherical(), pin.SE3(np.eye(3), g.o[j].copy()), f"platform{j + 1}")
        inertia = pin.Inertia(m.m_m, np.zeros(3), np.diag(m.I_m)) if "platform" in include else zero
        pm.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        platform_joint.append(jid)

    module_joint = []
    u_joint = np.zeros((2, 3, 2), dtype=int)
    lever_inertia = pin.Inertia(m.m_l, np.array([0.0, 0.0, 0.5 * g.l]), np.diag(m.I_l))
    for i in range(3):
        base = np.array([g.A[i, 0], g.A[i, 1], 0.0])
        mid = pm.addJoint(0, pin.JointModelPZ(), pin.SE3(np.eye(3), base), f"module{i + 1}")
        # both sliders on one rigid body: the lower one at the joint origin, the upper dh above
        sliders = pin.Inertia(2.0 * m.m_L, np.array([0.0, 0.0, 0.5 * dh]), np.zeros((3, 3)))
        pm.appendBodyToJoint(mid, sliders if "slider" in include else zero, pin.SE3.Identity())
        module_joint.append(mid)
        R0 = _u_joint_rotation(g.t[i])
        for j in range(2):
            height = dh if j == 0 else 0.0
            u1 = pm.addJoint(mid, pin.JointModelRY(), pin.SE3(R0, np.array([0.0, 0.0, height])), f"u{j + 1}{i + 1}_t")
            pm.appendBodyToJoint(u1, zero, pin.SE3.Identity())
            u2 = pm.addJoint(u1, pin.JointModelRX(), pin.SE3.Identity(), f"u{j + 1}{i + 1}_x")
            pm.appendBodyToJoint(u2, lever_inertia if "lever" in include else zero, pin.SE3.Identity())
            u_joint[j, i] = (u1, u2)

    tip_frame = np.zeros((2, 3), dtype=int)
    socket_frame = np.zeros((2, 3), dtype=int)
    for j in range(2):
        for i in range(3):
            tip = pin.SE3(np.eye(3), np.array([0.0, 0.0, g.l]))
            tip_frame[j, i] = pm.addFrame(pin.Frame(f"tip{j + 1}{i + 1}", int(u_joint[j, i, 1]), tip, pin.FrameType.OP_FRAME))
            sock = pin.SE3(np.eye(3), g.r_a[i].copy())
            socket_frame[j, i] = pm.addFrame(pin.Frame(f"socket{j + 1}{i + 1}", platform_joint[j], sock, pin.FrameType.OP_FRAME))

    platform_v = np.array([[pm.joints[jid].idx_v + k for k in range(3)] for jid in platform_joint])
    platform_q = np.array([[pm.joints[jid].idx_q + k for k in range(4)] for jid in platform_joint])
    module_v = np.array([pm.joints[jid].idx_v for jid in module_joint])
    u_v = np.vectorize(lambda jid: pm.joints[int(jid)].idx_v)(u_joint)
    free_joints = sorted([*module_joint, *(int(x) for x in u_joint.ravel())])
    free_v = np.array([pm.joints[jid].idx_v for jid in free_joints])
    free_q = np.array([pm.joints[jid].idx_q for jid in free_joints])
    module_q = np.array([pm.joints[jid].idx_q for jid in module_joint])
    info = TreeInfo(
        platform_joint=(platform_joint[0], platform_joint[1]),
        module_joint=(module_joint[0], module_joint[1], module_joint[2]),
        u_joint=u_joint,
        tip_frame=tip_frame,
        socket_frame=socket_frame,
        platform_v=platform_v,
        module_v=module_v,
        u_v=u_v,
        free_v=free_v,
        free_q=free_q,
        module_q=module_q,
        platform_q=platform_q,
        slider_offset=dh,
    )
    return pm, info


def build_tree(model: HipModel) -> tuple[pin.Model, TreeInfo]:
    """The machine's spanning tree as a Pinocchio model, and the indices to use it.

    Bodies (SI units, inertias about the centre of mass in the body frame):

    - platform j: spherical joint at ``o_j``, mass ``m_m`` at ``o_j``, ``diag(I_m)``;
    - module i: prismatic joint along +Z through ``A_i`` (configuration = height ``L_2i`` of
      the lower slider), mass ``2 m_L`` (both sliders, rigidly ``h1 - h2`` apart);
    - lever (j, i): U joint at ``b_ji`` (revolute about t_i, then about the lever's x axis),
      mass ``m_l`` at ``(0, 0, l/2)`` in the lever frame (z from b to a, x along the U joint's
      second axis), ``diag(I_xx, I_yy, I_zz)``.

    Frames ``tip{j}{i}`` (lever, ``(0, 0, l)``) and ``socket{j}{i}`` (platform, ``r_a_i``) mark
    the two sides of each S joint. nq = 2*4 + 3 + 12 = 23, nv = 21.
    """
    return _build(model, frozenset({"platform", "lever", "slider"}))


def closure_residual(pin_model: pin.Model, data: pin.Data, info: TreeInfo, q: Array) -> Array:
    """Loop-closure residual ``phi(q)``, ``(2, 3, 3)`` [m]: lever tip minus platform point, base frame."""
    pin.forwardKinematics(pin_model, data, q)
    pin.updateFramePlacements(pin_model, data)
    out = np.empty((2, 3, 3))
    for j in range(2):
        for i in range(3):
            out[j, i] = data.oMf[int(info.tip_frame[j, i])].translation - data.oMf[int(info.socket_frame[j, i])].translation
    return out


def _constraint_jacobian(pin_model: pin.Model, data: pin.Data, info: TreeInfo, q: Array) -> Array:
    """``G = d phi / d q`` as a map on velocities, ``(18, nv)``; rows ordered [j, i, xyz]."""
    pin.computeJointJacobians(pin_model, data, q)
    pin.updateFramePlacements(pin_model, data)
    rows = []
    for j in range(2):
        for i in range(3):
            jt = pin.getFrameJacobian(pin_model, data, int(info.tip_frame[j, i]), _WORLD)[:3]
            js = pin.getFrameJacobian(pin_model, data, int(info.socket_frame[j, i]), _WORLD)[:3]
            rows.append(jt - js)
    return np.vstack(rows)


def _drift(pin_model: pin.Model, data: pin.Data, info: TreeInfo, q: Array, v: Array) -> Array:
    """``gamma = Gdot v``, ``(18,)`` [m/s^2]: classical acceleration of tip minus socket at ``a = 0``."""
    pin.forwardKinematics(pin_model, data, q, v, np.zeros(pin_model.nv))
    pin.updateFramePlacements(pin_model, data)
    out = []
    for j in range(2):
        for i in range(3):
            at = pin.getFrameClassicalAcceleration(pin_model, data, int(info.tip_frame[j, i]), _WORLD).linear
            as_ = pin.getFrameClassicalAcceleration(pin_model, data, int(info.socket_frame[j, i]), _WORLD).linear
            out.append(at - as_)
    return np.concatenate(out)


def _initial_configuration(model: HipModel, pin_model: pin.Model, info: TreeInfo, R: Array) -> Array:
    """A rough start for the Newton iteration: platforms at ``R``, levers vertical.

    The lower slider of module i starts one lever length below the mean height of its two
    S-joint centres; the U angles start at zero. This lies on the assembly branch of the
    specification (slider below its S joint).
    """
    g = model.geometry
    q = pin.neutral(pin_model)
    quat = pin.Quaternion(R).coeffs()  # (x, y, z, w)
    for j in range(2):
        q[info.platform_q[j]] = quat
    a_z = g.o[:, 2][:, None] + (R @ g.r_a.T)[2][None, :]  # (2, 3) heights of a_ji
    q[info.module_q] = 0.5 * (a_z[0] - info.slider_offset + a_z[1]) - g.l
    return q


def _solve_configuration(
    model: HipModel, pin_model: pin.Model, data: pin.Data, info: TreeInfo, R: Array, max_iter: int = 50
) -> tuple[Array, float]:
    """Configuration ``q`` with the platforms at ``R`` and every loop closed.

    Solves ``phi(q_free) = 0`` (18 equations, 15 unknowns, consistent because both platforms
    share ``R``) by Gauss-Newton steps ``dq = -G_free^+ phi``, then checks the result with a fresh
    forward kinematics. Returns ``q`` and ``max |phi|`` [m].
    """
    q = _initial_configuration(model, pin_model, info, R)
    for _ in range(max_iter):
        res = closure_residual(pin_model, data, info, q).ravel()
        if np.max(np.abs(res)) < 1e-14:
            break
        G = _constraint_jacobian(pin_model, data, info, q)[:, info.free_v]
        step = np.linalg.lstsq(G, -res, rcond=None)[0]
        scale = min(1.0, 0.5 / max(np.max(np.abs(step)), 1e-300))  # keep early steps below ~30 deg
        q[info.free_q] += scale * step  # one-dimensional joints: q and v coordinates coincide
    err = float(np.max(np.abs(closure_residual(pin_model, data, info, q))))
    return q, err


def solve_state(
    model: HipModel,
    pin_model: pin.Model,
    data: pin.Data,
    info: TreeInfo,
    R: Array,
    omega: Array,
    omega_dot: Array,
) -> tuple[Array, Array, Array, float]:
    """Tree state ``(q, v, a)`` of one sample and its closure residual [m].

    With ``R (3, 3)``, ``omega, omega_dot (3,)`` (base frame) prescribed on both platforms
    (local spherical velocities ``R^T omega``, ``R^T omega_dot``), the remaining 15 velocities
    and accelerations solve, in the least-squares sense,

        G_free v_free = -G_plat v_plat,     G_free a_free = -G_plat a_plat - gamma(q, v),

    whose residuals are checked (the systems are consistent, 18 equations for 15 unknowns).
    Raises ``RuntimeError`` when the loops cannot be closed or a residual is not small.
    """
    q, err = _solve_configuration(model, pin_model, data, info, R)
    if not err < CLOSURE_TOLERANCE_M:
        raise RuntimeError(f"loop closure failed: residual {err:.3g} m")
    # branch check: each slider below its S joint
    lever_z = [data.oMi[int(info.u_joint[j, i, 1])].rotation[2, 2] for j in range(2) for i in range(3)]
    if min(lever_z) <= 0.0:
        raise RuntimeError("loop closure converged to the wrong assembly branch (slider above its S joint)")
    G = _constraint_jacobian(pin_model, data, info, q)
    free = info.free_v
    plat = info.platform_v.ravel()
    v = np.zeros(pin_model.nv)
    v[plat] = np.tile(R.T @ omega, 2)
    v[free] = np.linalg.lstsq(G[:, free], -G[:, plat] @ v[plat], rcond=None)[0]
    a = np.zeros(pin_model.nv)
    a[plat] = np.tile(R.T @ omega_dot, 2)
    gamma = _drift(pin_model, data, info, q, v)
    a[free] = np.linalg.lstsq(G[:, free], -G[:, plat] @ a[plat] - gamma, rcond=None)[0]
    scale_v = 1.0 + np.max(np.abs(v))
    scale_a = 1.0 + np.max(np.abs(a)) + np.max(np.abs(gamma))
    if np.max(np.abs(G @ v)) > 1e-9 * scale_v or np.max(np.abs(G @ a + gamma)) > 1e-9 * scale_a:
        raise RuntimeError("velocity or acceleration loop closure not satisfied")
    return q, v, a, err


def _reg(w: Array, eps: float) -> Array:
    """Regularised sign (scalar or 3-vector): ``w / sqrt(|w|^2 + eps^2)``."""
    w = np.asarray(w, dtype=float)
    return w / np.sqrt(float(np.dot(np.ravel(w), np.ravel(w))) + eps * eps)


def _friction_forces(
    model: HipModel, pin_model: pin.Model, data: pin.Data, info: TreeInfo, q: Array, v: Array, load: float
) -> tuple[Array, Array, Array]:
    """Generalized friction forces on the tree and the screws' friction torques.

    Each term is the force or torque a joint *resists with* (its power ``>= 0``), projected on
    the tree's velocities; the right-hand side of the constrained dynamics gets ``+Q``.

    Returns ``Q_hip (nv,)`` from the hip joints and thrust bearings alone (Eq. 16), ``Q_joint
    (nv,)`` from the sliders, U joints and S joints, and ``tau_screw (3,)`` [N m] from the screws.
    """
    g, m, f = model.geometry, model.inertia, model.friction
    nv = pin_model.nv
    pin.forwardKinematics(pin_model, data, q, v)
    pin.computeJointJacobians(pin_model, data, q)

    def omega_world(jid: int) -> Array:
        return data.oMi[jid].rotation @ data.v[jid].angular

    def cv(w: Array, coulomb: float, viscous: float, eps: float) -> Array:
        return coulomb * _reg(w, eps) + viscous * w

    Q_hip = np.zeros(nv)
    magnitude = f.r_h * f.mu_h * abs(load) + f.r_t * f.mu_t * abs(load + m.m_m * m.g)
    for j in range(2):
        jid = info.platform_joint[j]
        w = omega_world(jid)
        tau_mf = _reg(w, f.eps_w) * magnitude  # base frame, resists omega
        # power tau_mf . omega = (R^T tau_mf) . v_local
        Q_hip[info.platform_v[j]] += data.oMi[jid].rotation.T @ tau_mf

    Q_joint = np.zeros(nv)
    for i in range(3):
        Ld = v[info.module_v[i]]
        Q_joint[info.module_v[i]] += 2.0 * float(cv(np.float64(Ld), f.slider_coulomb, f.slider_viscous, f.eps_v))
    for j in range(2):
        jp = info.platform_joint[j]
        w_p = omega_world(jp)
        Jp = pin.getJointJacobian(pin_model, data, jp, _WORLD)[3:]
        for i in range(3):
            u1, u2 = (int(x) for x in info.u_joint[j, i])
            w_l = omega_world(u2)
            # U joint: the slider does not rotate, so the relative angular velocity is the lever's
            tau_u = cv(w_l, f.universal_coulomb, f.universal_viscous, f.eps_w)
            axis1 = data.oMi[u1].rotation[:, 1]
            axis2 = data.oMi[u2].rotation[:, 0]
            Q_joint[info.u_v[j, i, 0]] += axis1 @ tau_u
            Q_joint[info.u_v[j, i, 1]] += axis2 @ tau_u
            # S joint: -tau_s on the lever, +tau_s on the platform
            tau_s = cv(w_l - w_p, f.spherical_coulomb, f.spherical_viscous, f.eps_w)
            Jl = pin.getJointJacobian(pin_model, data, u2, _WORLD)[3:]
            Q_joint += (Jl - Jp).T @ tau_s
    theta_dot = 2.0 * np.pi * v[info.module_v] / g.p
    tau_screw = np.array([float(cv(np.float64(x), f.screw_coulomb, f.screw_viscous, f.eps_w)) for x in theta_dot])
    return Q_hip, Q_joint, tau_screw


def _energy(model: HipModel, pin_model: pin.Model, data: pin.Data, info: TreeInfo, q: Array, v: Array) -> float:
    """Kinetic plus potential energy [J] of the tree and the screw rotors (``I_L theta_dot^2 / 2``)."""
    ke = pin.computeKineticEnergy(pin_model, data, q, v)
    pe = pin.computePotentialEnergy(pin_model, data, q)
    theta_dot = 2.0 * np.pi * v[info.module_v] / model.geometry.p
    return float(ke + pe + 0.5 * model.inertia.I_L * np.sum(theta_dot**2))


def reference_torques(
    model: HipModel, t: Array, R: Array, omega: Array, omega_dot: Array, load: Array
) -> dict[str, Array]:
    """Motor torques from Pinocchio's spanning tree with loop-closure multipliers.

    For every sample k the tree state ``(q, v, a)`` is reconstructed (:func:`solve_state`) and
    the square system

        [S^T  G^T] [f; lambda] = rnea(q, v, a) + Q_friction          (21 x 21)

    is solved for the prismatic forces ``f`` (3) and the closure forces ``lambda`` (18); then
    ``tau = (p / 2 pi) f + I_L (2 pi / p) Lddot + tau_screw_friction``.

    Parameters: ``t (n,)`` [s]; ``R (n, 3, 3)`` platform rotation; ``omega, omega_dot (n, 3)``
    [rad/s, rad/s^2] in the base frame; ``load (n,)`` [N] hydraulic force on each platform.

    Returns a dict of ``(n, 3)`` arrays [N m] per motor: ``tau`` (everything), ``no_friction``
    (every friction term off), ``friction`` (all friction), ``hip_friction`` (the hip joints and
    thrust bearings alone), ``platform``, ``lever``, ``slider`` (inertia and gravity of those
    bodies alone) and ``screw`` (rotor inertia); also ``L, Ld, Ldd (n, 3)`` lower-slider
    motion [m, m/s, m/s^2], ``closure_residual (n,)`` [m], ``energy (n,)`` [J] (kinetic plus
    potential energy of the whole machine, rotors included), ``q (n, 23)``, ``v, a (n, 21)``.
    """
    t = np.asarray(t, dtype=float)
    n = t.shape[0]
    load = np.broadcast_to(np.asarray(load, dtype=float), (n,))
    pm, info = build_tree(model)
    data = pm.createData()
    parts = {name: _build(model, frozenset({name})) for name in ("platform", "lever", "slider")}
    part_data = {name: parts[name][0].createData() for name in parts}
    gear = model.geometry.p / (2.0 * np.pi)  # [m/rad]
    I_L = model.inertia.I_L

    out = {
        k: np.zeros((n, 3))
        for k in ("tau", "no_friction", "friction", "hip_friction", "platform", "lever", "slider", "screw", "L", "Ld", "Ldd")
    }
    out["closure_residual"] = np.zeros(n)
    out["energy"] = np.zeros(n)
    out["q"] = np.zeros((n, pm.nq))
    out["v"] = np.zeros((n, pm.nv))
    out["a"] = np.zeros((n, pm.nv))
    S = np.zeros((3, pm.nv))
    S[np.arange(3), info.module_v] = 1.0

    for k in range(n):
        q, v, a, err = solve_state(model, pm, data, info, R[k], omega[k], omega_dot[k])
        G = _constraint_jacobian(pm, data, info, q)
        K = np.hstack((S.T, G.T))  # (21, 21)
        tau_tree = pin.rnea(pm, data, q, v, a).copy()
        part_tau = [pin.rnea(parts[name][0], part_data[name], q, v, a).copy() for name in ("platform", "lever", "slider")]
        Q_hip, Q_joint, tau_sf = _friction_forces(model, pm, data, info, q, v, float(load[k]))
        rhs = np.column_stack([tau_tree + Q_hip + Q_joint, tau_tree, Q_hip, Q_hip + Q_joint, *part_tau])
        sol = np.linalg.solve(K, rhs)
        if not np.allclose(K @ sol, rhs, rtol=1e-9, atol=1e-9 * (1.0 + np.max(np.abs(rhs)))):
            raise RuntimeError(f"t = {t[k]:g} s: the constrained dynamics system is singular")
        motor = gear * sol[:3]  # (3, columns)
        Ldd = a[info.module_v]
        screw = I_L * Ldd / gear
        out["tau"][k] = motor[:, 0] + screw + tau_sf
        out["no_friction"][k] = motor[:, 1] + screw
        out["hip_friction"][k] = motor[:, 2]
        out["friction"][k] = motor[:, 3] + tau_sf
        out["platform"][k], out["lever"][k], out["slider"][k] = motor[:, 4], motor[:, 5], motor[:, 6]
        out["screw"][k] = screw
        out["L"][k] = q[info.module_q]
        out["Ld"][k] = v[info.module_v]
        out["Ldd"][k] = Ldd
        out["closure_residual"][k] = err
        out["energy"][k] = _energy(model, pm, data, info, q, v)
        out["q"][k], out["v"][k], out["a"][k] = q, v, a
    return out


def spanning_tree_rnea_inputs(model: HipModel) -> tuple[pin.Model, pin.Data, Array, Array, Array]:
    """One representative sample of the spanning tree, ready for a bare ``pinocchio.rnea`` call.

    The platforms sit at ``R = Rx(10 deg) Ry(-5 deg) Rz(8 deg)`` with a non-zero angular velocity
    and acceleration; ``(q, v, a)`` close every loop. Returns ``(pin_model, data, q, v, a)``.
    """
    from pkmdyn.spatial import euler_kinematics

    angles = np.deg2rad([[10.0, -5.0, 8.0]])
    rates = np.array([[0.8, -0.5, 0.6]])
    accels = np.array([[2.0, 1.5, -1.0]])
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, angles, rates, accels)
    pm, info = build_tree(model)
    data = pm.createData()
    q, v, a, _ = solve_state(model, pm, data, info, R[0], w[0], wd[0])
    return pm, data, q, v, a

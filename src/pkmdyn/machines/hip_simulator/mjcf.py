"""The hip simulator as a MuJoCo model (MJCF), and the map from its motion to MuJoCo's state.

The machine is written as a kinematic tree with the six S joints as ``connect`` equality
constraints, assembled at the zero pose (``R = I``) so that MuJoCo's reference configuration
``qpos0`` closes every loop::

    world -+- platform{j}   ball joint at o_j; mass m_m (see below), diag(I_m)         j = 1, 2
           +- slider2{i}    slide joint "slide{i}" along +Z through A_i, mass m_L      i = 1, 2, 3
                 +- lever2{i}    U joint: hinge "u2{i}_t" about t_i, then "u2{i}_x" about the
                 |               lever's x axis; mass m_l at (0, 0, l/2), diag(I_l) in the lever frame
                 +- slider1{i}   welded (h1 - h2) above, mass m_L
                       +- lever1{i}  as lever2{i}

21 degrees of freedom (2 x 3 ball, 3 slide, 12 hinge), 6 x 3 loop-closure equations, 3 left.
Body frames: the platforms and sliders are parallel to the base frame; each lever body frame is
the lever frame of the model at the zero pose (x along the U joint's second axis, z from the U
joint to the S joint), its origin at the U-joint centre. A hinge axis is given in its body's
frame and MuJoCo applies a body's joints in order, so the second hinge turns with the first:
the lever frame at any pose is ``F = F0 Rot(F0^T t_i, q_t) Rot(x, q_x)``, the model's U joint.

Actuation: a ``motor`` on each slide joint with ``gear = 2 pi / p``, so that its control is the
motor torque [N m] and the slider force is ``(2 pi / p) tau``; the lead screw's rotor inertia
enters as the slide joint's ``armature = I_L (2 pi / p)^2``. Not in the export: every friction
term (MuJoCo has no load-dependent bearing friction; the hydraulic load acts through the fixed
hip centres and enters the model only through friction) and the ``lever_spin =
"perpendicular"`` assumption (the export is always the physical U joint). A platform of zero
mass (the paper gives none) is written with 1 g: its centre of mass sits on the fixed ball
joint, so the value changes no dynamics.

MuJoCo is an optional dependency (``pip install 'pkmdyn[validate]'``): writing the XML needs
nothing; :func:`load_mujoco` and :func:`mujoco_state` import it when called.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError, PkmdynError
from .kinematics import HipKinematics, platform_kinematics
from .params import HipModel

__all__ = ["mjcf_string", "write_mjcf", "load_mujoco", "mujoco_state", "MIN_PLATFORM_MASS_KG"]

Array = NDArray[np.float64]

#: the mass written for a massless platform (MuJoCo needs a positive mass on a moving body)
MIN_PLATFORM_MASS_KG = 1e-3
#: inertia written for the sliders, which only translate (MuJoCo needs a positive inertia)
_SLIDER_INERTIA_KGM2 = 1e-6


def _f(x: float) -> str:
    return repr(float(x))


def _v(x: Array) -> str:
    return " ".join(_f(c) for c in np.ravel(x))


def _zero_pose(model: HipModel) -> HipKinematics:
    z = np.zeros((1, 3))
    return platform_kinematics(model, np.zeros(1), np.eye(3)[None], z, z, check_conditioning=False)


def mjcf_string(model: HipModel, timestep_s: float = 1e-3) -> str:
    """The machine as an MJCF document (module docstring); SI units, radians.

    ``timestep_s`` [s] is MuJoCo's integration step (RK4); the loop constraints get
    ``solref = (2 timestep, 1)``, the stiffest MuJoCo allows by default at that step, and
    ``solimp = (0.9999, 0.9999, 1e-4)``, MuJoCo's largest impedance: its soft constraints then
    still bend the forward accelerations by a few 1e-4 (relative; ``tests/test_mjcf.py``).
    """
    g, m = model.geometry, model.inertia
    for key, inertia in (("lever_inertia_kgm2", m.I_l), ("platform_inertia_kgm2", m.I_m)):
        a, b, c = (float(x) for x in inertia)
        if not (a + b >= c and b + c >= a and c + a >= b):
            raise ParameterError(
                f"[inertia] {key}: {a:g}, {b:g}, {c:g} kg m^2 are not the principal inertias of a rigid body "
                "(each must be at most the sum of the other two); MuJoCo cannot load such a body"
            )
    kin = _zero_pose(model)
    gear = 2.0 * np.pi / g.p
    dh = float(g.h[0] - g.h[1])
    mass_p = max(m.m_m, MIN_PLATFORM_MASS_KG)
    lines = [
        '<mujoco model="hip_simulator_2x3PUS_S">',
        "  <!-- pkmdyn export of the 2(3PUS+S) hip simulator: kinematic tree, six S joints as connect",
        "       constraints, motors on the slide joints (gear 2 pi / p, control = motor torque [N m]).",
        "       No friction. SI units. -->",
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true"/>',
        f'  <option timestep="{_f(timestep_s)}" integrator="RK4" gravity="0 0 {_f(-m.g)}" solver="Newton"'
        ' tolerance="1e-12" iterations="100" jacobian="dense">',
        '    <flag contact="disable"/>',
        "  </option>",
        "  <default>",
        '    <geom contype="0" conaffinity="0" rgba="0.7 0.7 0.75 1"/>',
        f'    <equality solref="{_f(2.0 * timestep_s)} 1" solimp="0.9999 0.9999 0.0001 0.5 2"/>',
        "  </default>",
        "  <worldbody>",
    ]
    for j in range(2):
        lines += [
            f'    <body name="platform{j + 1}" pos="{_v(g.o[j])}">',
            f'      <joint name="platform{j + 1}" type="ball"/>',
            f'      <inertial pos="0 0 0" mass="{_f(mass_p)}" diaginertia="{_v(m.I_m)}"/>',
            f'      <geom type="cylinder" size="{_f(g.e)} 0.005"/>',
            "    </body>",
        ]

    def lever(j: int, i: int, indent: str) -> list[str]:
        F0 = kin.R_lever[0, i]  # columns x, y, z of the lever frame at the zero pose
        axis_t = F0.T @ g.t[i]
        name = f"{j + 1}{i + 1}"
        return [
            f'{indent}<body name="lever{name}" xyaxes="{_v(F0[:, 0])} {_v(F0[:, 1])}">',
            f'{indent}  <joint name="u{name}_t" type="hinge" axis="{_v(axis_t)}"/>',
            f'{indent}  <joint name="u{name}_x" type="hinge" axis="1 0 0"/>',
            f'{indent}  <inertial pos="0 0 {_f(0.5 * g.l)}" mass="{_f(m.m_l)}" diaginertia="{_v(m.I_l)}"/>',
            f'{indent}  <geom type="capsule" fromto="0 0 0 0 0 {_f(g.l)}" size="0.008"/>',
            f"{indent}</body>",
        ]

    slider_inertia = _v(np.full(3, _SLIDER_INERTIA_KGM2))
    for i in range(3):
        base = np.array([g.A[i, 0], g.A[i, 1], kin.L[0, 1, i]])
        lines += [
            f'    <body name="slider2{i + 1}" pos="{_v(base)}">',
            f'      <joint name="slide{i + 1}" type="slide" axis="0 0 1" armature="{_f(m.I_L * gear**2)}"/>',
            f'      <inertial pos="0 0 0" mass="{_f(m.m_L)}" diaginertia="{slider_inertia}"/>',
            '      <geom type="box" size="0.02 0.02 0.02"/>',
            *lever(1, i, "      "),
            f'      <body name="slider1{i + 1}" pos="0 0 {_f(dh)}">',
            f'        <inertial pos="0 0 0" mass="{_f(m.m_L)}" diaginertia="{slider_inertia}"/>',
            '        <geom type="box" size="0.02 0.02 0.02"/>',
            *lever(0, i, "        "),
            "      </body>",
            "    </body>",
        ]
    lines += ["  </worldbody>", "  <equality>"]
    for j in range(2):
        for i in range(3):
            lines.append(
                f'    <connect name="s{j + 1}{i + 1}" body1="lever{j + 1}{i + 1}" body2="platform{j + 1}" anchor="0 0 {_f(g.l)}"/>'
            )
    lines += ["  </equality>", "  <actuator>"]
    for i in range(3):
        lines.append(f'    <motor name="motor{i + 1}" joint="slide{i + 1}" gear="{_f(gear)}"/>')
    lines += ["  </actuator>", "</mujoco>", ""]
    return "\n".join(lines)


def write_mjcf(model: HipModel, path: str | Path, timestep_s: float = 1e-3) -> Path:
    """Write :func:`mjcf_string` to ``path``; returns the path."""
    path = Path(path)
    try:
        path.write_text(mjcf_string(model, timestep_s), encoding="utf-8")
    except OSError as exc:
        raise PkmdynError(f"--out {path}: cannot write ({exc.strerror or exc})") from None
    return path


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise PkmdynError(
            "MuJoCo is not installed; it is an optional dependency: pip install 'pkmdyn[validate]'"
        ) from None
    return mujoco


def load_mujoco(model: HipModel, timestep_s: float = 1e-3) -> Any:
    """The exported machine as a ``mujoco.MjModel`` (needs the optional MuJoCo package)."""
    return _mujoco().MjModel.from_xml_string(mjcf_string(model, timestep_s))


def mujoco_state(model: HipModel, mj_model: Any, R: Array, omega: Array, omega_dot: Array) -> tuple[Array, Array, Array]:
    """MuJoCo's ``qpos (n, nq), qvel, qacc (n, nv)`` for the platform motion ``R (n, 3, 3)``,
    ``omega, omega_dot (n, 3)`` [rad/s, rad/s^2] (base frame), from the model's exact kinematics.

    Ball joints: the platform's quaternion, ``R^T omega``, ``R^T omega_dot`` (local). Slides:
    lower-slider height minus its zero-pose height, ``Ld``, ``Ldd``. U joints: with ``F0`` the
    lever frame at the zero pose and ``F`` the current one, ``F0^T F = Rot(a, q_t) Rot(x, q_x)``
    (``a = F0^T t_i``) gives the angles; ``omega_l = qd_t t_i + qd_x x`` with ``x`` the current
    second axis, and because ``t_i x x`` is perpendicular to both axes,
    ``qdd_t = omega_l_dot . t_i``, ``qdd_x = omega_l_dot . x``. The levers' motion is always
    that of the U joint (``lever_spin = "u_joint"``), as in the export.
    """
    mujoco = _mujoco()
    if model.geometry.lever_spin != "u_joint":  # MuJoCo's levers turn in their U joints
        model = dataclasses.replace(model, geometry=dataclasses.replace(model.geometry, lever_spin="u_joint"))
    g = model.geometry
    n = R.shape[0]
    kin = platform_kinematics(model, np.zeros(n), R, omega, omega_dot, check_conditioning=False)
    zero = _zero_pose(model)
    qpos = np.tile(mj_model.qpos0, (n, 1))
    qvel = np.zeros((n, mj_model.nv))
    qacc = np.zeros((n, mj_model.nv))
    quat = np.zeros(4)
    for k in range(n):
        mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R[k]).ravel())
        for j in range(2):
            jnt = mj_model.joint(f"platform{j + 1}")
            qpos[k, jnt.qposadr[0] : jnt.qposadr[0] + 4] = quat
            qvel[k, jnt.dofadr[0] : jnt.dofadr[0] + 3] = R[k].T @ omega[k]
            qacc[k, jnt.dofadr[0] : jnt.dofadr[0] + 3] = R[k].T @ omega_dot[k]
    for i in range(3):
        jnt = mj_model.joint(f"slide{i + 1}")
        qpos[:, jnt.qposadr[0]] = kin.L[:, 1, i] - zero.L[0, 1, i]
        qvel[:, jnt.dofadr[0]] = kin.Ld[:, 1, i]
        qacc[:, jnt.dofadr[0]] = kin.Ldd[:, 1, i]
        F0 = zero.R_lever[0, i]
        a = F0.T @ g.t[i]
        G = np.einsum("ab,nac->nbc", F0, kin.R_lever[:, i])  # F0^T F
        g0 = G[:, :, 0]
        q_t = np.arctan2(np.cross(np.array([1.0, 0.0, 0.0]), g0) @ a, g0[:, 0])
        c, s = np.cos(q_t), np.sin(q_t)
        # Rot(a, q_t)^T G by Rodrigues' formula, then the angle about x
        K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
        Rot_a = np.eye(3) + s[:, None, None] * K + (1.0 - c)[:, None, None] * (K @ K)
        N = np.swapaxes(Rot_a, 1, 2) @ G
        q_x = np.arctan2(N[:, 2, 1], N[:, 1, 1])
        x_axis = kin.R_lever[:, i, :, 0]
        for j in range(2):  # both levers of a module share the angles and rates
            jt, jx = mj_model.joint(f"u{j + 1}{i + 1}_t"), mj_model.joint(f"u{j + 1}{i + 1}_x")
            qpos[:, jt.qposadr[0]] = q_t
            qpos[:, jx.qposadr[0]] = q_x
            qvel[:, jt.dofadr[0]] = kin.omega_lever[:, i] @ g.t[i]
            qvel[:, jx.dofadr[0]] = np.einsum("nk,nk->n", kin.omega_lever[:, i], x_axis)
            qacc[:, jt.dofadr[0]] = kin.omega_lever_dot[:, i] @ g.t[i]
            qacc[:, jx.dofadr[0]] = np.einsum("nk,nk->n", kin.omega_lever_dot[:, i], x_axis)
    return qpos, qvel, qacc

"""The hip simulator as a described mechanism: its parameter file turned into a description.

The generic engine (:mod:`pkmdyn.multibody`) then computes the same kinematics as the
closed form of :mod:`.kinematics` (Eq. 1-6), which stays the fast path and becomes the
generic engine's test oracle. Described at the zero pose (R = I):

* two platforms (``upper`` at o_1 = (0, 0, h1), ``lower`` at o_2 = (0, 0, h2)), each on a
  spherical joint at its centre (``S0_upper``, ``S0_lower``, the "+S" of 2(3PUS+S));
* per module i a ``slider_i`` on a prismatic joint along the screw through A_i (``P_i``,
  actuated; its coordinate is the lower slider's position L_2i, Eq. 2; the upper slider is
  the same body, h1 - h2 higher, as the two sliders of one screw move together);
* per module and platform a lever (``lever_<platform>_i``, length l) on a universal joint at
  the slider (first axis t_i fixed in the slider, second axis normal to t_i and to the lever)
  and a spherical joint at the platform point o_j + R r_ai.

Masses and inertias from Table 2: lever mass and principal inertia (x along the U joint's
second axis, z along the lever), the two sliders of a module as one body of twice the slider
mass, the platform's principal inertia in its frame. Each module's motor drives its slider
through a lead screw (``[[actuators]]`` ``motor_i``: lead p, rotor inertia I_L, the screw's
Coulomb and viscous friction on the motor side), so that the motor torques are those of Eq.
7-16; the effort split's groups are the platforms, the levers and the sliders (the parts of
Eq. 14; the screws' rotors and all friction are parts of their own). The task is the upper
platform's Euler angles in the parameter file's sequence.

The hydraulic load is the named load ``hydraulic_N`` (one magnitude per sample for both
platforms, along -Z through each centre o_j), and the hip-joint and thrust-bearing friction of
Eq. 16 the ``external`` friction of ``S0_upper`` and ``S0_lower`` driven by it; the S, U and
slider friction of Table 2 are the joints' Coulomb and viscous entries.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .params import HipModel

__all__ = ["hip_description"]


def _l(v: np.ndarray) -> list[float]:
    return [float(x) for x in np.asarray(v, dtype=float)]


def hip_description(model: HipModel) -> dict[str, Any]:
    """The description (a dict in the format of ``docs/mechanism_format.md``) of ``model``."""
    g, m, f = model.geometry, model.inertia, model.friction

    def friction(**keys: float) -> dict[str, Any]:
        """The joint's friction entry when any value is nonzero (Coulomb and viscous of Table 2;
        the lead screws are no bodies of the description: their friction and rotor inertia
        belong to the motors)."""
        vals = {k: float(v) for k, v in keys.items() if v}
        return {"friction": vals} if vals else {}

    bodies: list[dict[str, Any]] = []
    joints: list[dict[str, Any]] = []
    loads: list[dict[str, Any]] = []
    inertia_platform = _l(m.I_m) + [0.0, 0.0, 0.0]
    for j, pname in enumerate(("upper", "lower")):
        o = g.o[j]
        bodies.append({"name": pname, "mass_kg": float(m.m_m), "com_m": _l(o), "inertia_kgm2": inertia_platform})
        # the hip joint and thrust bearing at the platform centre, Eq. (16): friction torque
        # u(omega) (r_h mu_h |F| + r_t mu_t |F + m_m g|) driven by the hydraulic load F
        ext = [{"load": "hydraulic_N", "coefficient": float(mu), "radius_m": float(r), "offset_N": float(off)}
               for mu, r, off in ((f.mu_h, f.r_h, 0.0), (f.mu_t, f.r_t, m.m_m * m.g)) if mu and r]
        joints.append({"name": f"S0_{pname}", "type": "spherical", "parent": "ground", "child": pname,
                       "point_m": _l(o), **({"friction": {"external": ext}} if ext else {})})
        loads.append({"name": "hydraulic_N", "body": pname, "direction": [0.0, 0.0, -1.0], "point_m": _l(o)})
    dz_ref = []
    for i in range(3):
        a2 = g.o[1] + g.r_a[i]
        d = np.array([a2[0] - g.A[i, 0], a2[1] - g.A[i, 1], 0.0])
        d[2] = np.sqrt(g.l**2 - d[0] ** 2 - d[1] ** 2)
        dz_ref.append(d)
        b2 = a2 - d  # lower slider's U-joint centre at the zero pose
        L2 = float(b2[2])
        bodies.append({"name": f"slider_{i + 1}", "mass_kg": float(2.0 * m.m_L),
                       "com_m": _l(b2 + 0.5 * (g.h[0] - g.h[1]) * np.array([0.0, 0.0, 1.0])),
                       "inertia_kgm2": [1e-3, 1e-3, 1e-3, 0.0, 0.0, 0.0]})
        joints.append({"name": f"P_{i + 1}", "type": "prismatic", "parent": "ground", "child": f"slider_{i + 1}",
                       "point_m": _l(g.A[i]), "axis": [0.0, 0.0, 1.0], "actuated": True,
                       "position_at_reference_m": L2,
                       # one body for the module's two carriages: twice each carriage's friction
                       **friction(coulomb_force_N=2.0 * f.slider_coulomb, viscous_N_s_m=2.0 * f.slider_viscous)})
        e = d / g.l
        t = g.t[i]
        second = np.cross(t, e)
        second /= np.linalg.norm(second)
        Rl = np.column_stack([second, np.cross(e, second), e])  # lever frame (x, y, z)
        Il = Rl @ np.diag(m.I_l) @ Rl.T
        Il6 = [Il[0, 0], Il[1, 1], Il[2, 2], Il[0, 1], Il[0, 2], Il[1, 2]]
        for j, pname in enumerate(("upper", "lower")):
            a = g.o[j] + g.r_a[i]
            b = a - d
            lever = f"lever_{pname}_{i + 1}"
            bodies.append({"name": lever, "mass_kg": float(m.m_l), "com_m": _l(b + 0.5 * d),
                           "inertia_kgm2": [float(x) for x in Il6]})
            joints.append({"name": f"U_{pname}_{i + 1}", "type": "universal", "parent": f"slider_{i + 1}",
                           "child": lever, "point_m": _l(b), "axes": [_l(t), _l(second)],
                           **friction(coulomb_torque_Nm=f.universal_coulomb, viscous_Nm_s_rad=f.universal_viscous)})
            joints.append({"name": f"S_{pname}_{i + 1}", "type": "spherical", "parent": lever, "child": pname,
                           "point_m": _l(a), "axis": _l(e),
                           **friction(coulomb_torque_Nm=f.spherical_coulomb, viscous_Nm_s_rad=f.spherical_viscous)})
    # the lead screws: each module's motor turns a screw of lead p (one body per module for its
    # two carriages), its rotor inertia I_L and the screw friction on the motor side (Eq. 10, 16)
    actuators = [{"name": f"motor_{i + 1}", "joint": f"P_{i + 1}", "screw_lead_m": float(g.p),
                  "rotor_inertia_kgm2": float(m.I_L),
                  **({"coulomb_torque_Nm": float(f.screw_coulomb)} if f.screw_coulomb else {}),
                  **({"viscous_Nm_s_rad": float(f.screw_viscous)} if f.screw_viscous else {})} for i in range(3)]
    # the parts of Eq. (14): platforms, levers, sliders (the screws' rotors and every friction
    # are parts of the split of their own)
    groups = [{"name": "platform", "bodies": ["upper", "lower"]},
              {"name": "lever", "bodies": [f"lever_{p}_{i + 1}" for p in ("upper", "lower") for i in range(3)]},
              {"name": "slider", "bodies": [f"slider_{i + 1}" for i in range(3)]}]
    # the engine's own plausibility limits on the sliders' rates never bind before the parameter
    # file's [limits] (which the hip's jobs check, naming its keys)
    lim = model.limits
    limits = {"max_joint_speed_m_s": max(10.0, float(lim.max_slider_speed_m_s)),
              "max_joint_acceleration_m_s2": max(1000.0, float(lim.max_slider_acceleration_m_s2))}
    return {
        "mechanism": {"name": "hip", "source": "2(3PUS+S) hip simulator, Chen, Cheng & Pang (2022), Tables 1-2"
                      + (f"; parameters {model.source}" if getattr(model, "source", "") else ""),
                      "gravity_m_s2": [0.0, 0.0, -float(m.g)]},
        "bodies": bodies,
        "joints": joints,
        "loads": loads,
        "actuators": actuators,
        "groups": groups,
        "limits": limits,
        "task": {"body": "upper", "point_m": _l(g.o[0]), "euler_sequence": g.euler_sequence, "orientation": [1, 2, 3]},
        "default_motion": {"period_s": 1.0, "samples": 201,
                           "amplitude": {"euler1_rad": 0.3, "euler2_rad": 0.12, "euler3_rad": 0.1}},
    }

"""The hip simulator as a described mechanism: the generic engine against the hand-derived
closed form (Eq. 1-6) on the ISO 14242-1 cycle and on random variants of the machine."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.machines.hip_simulator import inverse_kinematics, load_params, model_from_dict, platform_kinematics
from pkmdyn.machines.hip_simulator.description import hip_description
from pkmdyn.machines.hip_simulator.params import default_params_dict
from pkmdyn.multibody import analyse_topology, load_mechanism, solve_kinematics
from pkmdyn.profiles.iso14242 import iso14242_motion


def _variant(seed):
    if seed is None:
        return load_params()
    rng = np.random.default_rng(seed)
    d = default_params_dict()
    g = d["geometry"]
    g["base_radius_m"] *= rng.uniform(0.95, 1.05)
    g["platform_radius_m"] *= rng.uniform(0.9, 1.1)
    g["lever_length_m"] *= rng.uniform(0.98, 1.1)
    g["platform_heights_m"] = [g["platform_heights_m"][0] * rng.uniform(0.95, 1.05), g["platform_heights_m"][1]]
    g["module_angles_deg"] = [a + rng.uniform(-5, 5) for a in g["module_angles_deg"]]
    g["platform_joint_angles_deg"] = [a + rng.uniform(-5, 5) for a in g["platform_joint_angles_deg"]]
    return model_from_dict(d, f"variant {seed}")


def _rel(a, b):
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-12))


def test_hip_topology():
    rep = analyse_topology(load_mechanism(hip_description(load_params())))
    assert (rep.bodies, rep.kutzbach, rep.mobility, rep.overconstraints, rep.idle, rep.dof) == (11, 3, 3, 0, 0, 3)


@pytest.mark.parametrize("seed", [None, 11, 12])
def test_generic_kinematics_match_the_closed_form(seed):
    hip = _variant(seed)
    m = load_mechanism(hip_description(hip))
    motion = iso14242_motion(cycles=1, samples_per_cycle=400)
    ref = inverse_kinematics(hip, motion)
    kin = solve_kinematics(m, motion.angles, motion.rates, motion.accels, motion.t)
    zero = platform_kinematics(hip, np.zeros(1), np.eye(3)[None], np.zeros((1, 3)), np.zeros((1, 3)))
    tol = 1e-9
    sliders = [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    assert _rel(kin.act_q[:, sliders], ref.L[:, 1]) < tol
    assert _rel(kin.act_qd[:, sliders], ref.Ld[:, 1]) < tol
    assert _rel(kin.act_qdd[:, sliders], ref.Ldd[:, 1]) < tol
    for name in ("upper", "lower"):
        b = m.body_names.index(name)
        assert _rel(kin.R[:, b], ref.R) < tol
        assert _rel(kin.w[:, b], ref.omega) < tol
        assert _rel(kin.wd[:, b], ref.omega_dot) < tol
    for j, name in enumerate(("upper", "lower")):
        for i in range(3):
            b = m.body_names.index(f"lever_{name}_{i + 1}")
            assert _rel(kin.p[:, b], ref.c_lever[:, j, i]) < tol
            assert _rel(kin.v[:, b], ref.v_lever[:, i]) < tol
            assert _rel(kin.a[:, b], ref.a_lever[:, i]) < tol
            assert _rel(kin.w[:, b], ref.omega_lever[:, i]) < tol
            assert _rel(kin.wd[:, b], ref.omega_lever_dot[:, i]) < tol
            # the lever frame turns with the body (its frame is the base frame at the zero pose)
            assert _rel(kin.R[:, b] @ zero.R_lever[0, i], ref.R_lever[:, i]) < tol

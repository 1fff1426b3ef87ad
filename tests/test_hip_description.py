"""The hip simulator as a described mechanism: the generic engine against the closed form of
Eq. 1-6 (``tests/oracles/hip.py``) on the ISO 14242-1 cycle and on random variants of the
machine."""

from __future__ import annotations

import numpy as np
import pytest

from hip_helpers import engine_kinematics, kinematics_against_oracle, rel, sliders
from oracles import hip as oracle
from pkmdyn.machines.hip_simulator import load_params, model_from_dict
from pkmdyn.machines.hip_simulator.description import hip_description
from pkmdyn.machines.hip_simulator.params import default_params_dict
from pkmdyn.multibody import analyse_topology, load_mechanism
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


def test_hip_topology():
    rep = analyse_topology(load_mechanism(hip_description(load_params())))
    assert (rep.bodies, rep.kutzbach, rep.mobility, rep.overconstraints, rep.idle, rep.dof) == (11, 3, 3, 0, 0, 3)


@pytest.mark.parametrize("seed", [None, 11, 12])
def test_generic_kinematics_match_the_closed_form(seed):
    hip = _variant(seed)
    motion = iso14242_motion(cycles=1, samples_per_cycle=400)
    kinematics_against_oracle(hip, motion.angles, motion.rates, motion.accels, motion.t)


def test_the_comparison_sees_a_wrong_machine():
    """The oracle of another lever length differs from the engine far beyond the tolerance."""
    hip = load_params()
    d = default_params_dict()
    d["geometry"]["lever_length_m"] *= 1.001
    motion = iso14242_motion(cycles=1, samples_per_cycle=50)
    m, kin = engine_kinematics(hip, motion.angles, motion.rates, motion.accels)
    other = oracle.kinematics(model_from_dict(d), motion.angles, motion.rates, motion.accels)
    assert rel(kin.act_q[:, sliders(m)], other.L[:, 1]) > 1e-4


def test_the_engines_rate_limits_never_bind_before_the_parameter_files():
    """A parameter file that raises the sliders' limits above the engine's defaults raises the
    description's too: a fast design is judged by the hip's own [limits] keys."""
    from pkmdyn.multibody.dynamics.actuators import effective_limits

    d = default_params_dict()
    d.setdefault("limits", {}).update(max_slider_speed_m_s=25.0, max_slider_acceleration_m_s2=4000.0)
    lim = effective_limits(load_mechanism(hip_description(model_from_dict(d, "fast"))))
    assert lim["max_joint_speed_m_s"] == 25.0 and lim["max_joint_acceleration_m_s2"] == 4000.0
    lim = effective_limits(load_mechanism(hip_description(load_params())))
    assert lim["max_joint_speed_m_s"] == 10.0 and lim["max_joint_acceleration_m_s2"] == 1000.0

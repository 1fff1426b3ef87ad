"""Sweeps of a machine that generates its mechanism description from a parameter file of its
own (the hip simulator): the registry's adapter, every design evaluated by the engine on the
generated description (the same numbers as the engine run from scratch on that description),
the machine's metrics under its own names, the engine's reactions (and, when asked for, its
least singularity measures) beside them."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from pkmdyn.machines.registry import sweep_adapter
from pkmdyn.multibody.analyses.designs import DescribedSweep, GeneratedSweep


def test_registry_gives_the_generic_adapter_of_generated_descriptions():
    ad = sweep_adapter("hip")
    assert isinstance(ad, GeneratedSweep) and ad.NAME == "hip"
    assert ad.module == "pkmdyn.machines.hip_simulator.described_sweep"
    import pickle

    assert pickle.loads(pickle.dumps(ad)).hooks is ad.hooks  # travels to workers by its module's name
    assert not isinstance(sweep_adapter("pdm"), (GeneratedSweep, DescribedSweep))  # the PDM's own
    assert isinstance(sweep_adapter("stewart"), DescribedSweep)


def test_metrics_keep_the_machine_names_then_the_engine_reactions_and_measures():
    ad = sweep_adapter("hip")
    names = [m.name for m in ad.metrics({}, None)]
    assert names[:3] == ["gci", "min_inverse_condition", "orientation_workspace_fraction"]
    assert "friction_energy_per_cycle_J" in names and "peak_drive_force_N" in names
    for extra in ("peak_force_S0_upper_N", "peak_moment_S_lower_3_Nm"):
        assert extra in names
    assert "peak_effort_N" not in names and len(names) == len(set(names))
    assert "orientation_workspace_fraction" not in [m.name for m in ad.metrics({"workspace_points": 0}, None)]
    # the engine's least singularity measures only when asked for (the status is 1/cond(J)'s)
    measures = ("min_inverse_measure", "min_direct_measure", "min_constraint_measure")
    assert not set(measures) & set(names)
    asked = [m.name for m in ad.metrics({"engine_measures": True}, None)]
    assert set(measures) <= set(asked) and set(asked) - set(measures) == set(names)


def test_the_engine_measures_when_asked_for_and_the_same_rows_without_them():
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import model_from_dict
    from pkmdyn.multibody import load_mechanism, solve_kinematics
    from pkmdyn.multibody.kinematics.singularity.measures import singularity_measures

    ad = sweep_adapter("hip")
    base = ad.base_description(None)
    options = {"samples_per_cycle": 60, "workspace_points": 16}
    d = _design(3)
    plain = ad.evaluate([d], ad.prepare(base, options, Path(".")))[0]
    asked = ad.evaluate([d], ad.prepare(base, {**options, "engine_measures": True}, Path(".")))[0]
    assert plain.status == asked.status == "ok"
    extra = {k: v for k, v in asked.metrics.items() if k not in plain.metrics}
    assert {k: asked.metrics[k] for k in plain.metrics} == plain.metrics
    model = load_mechanism(hip_description(model_from_dict(d)))
    mo = ad.prepare(base, options, Path(".")).engine.motion
    sm = singularity_measures(model, solve_kinematics(model, mo.x, mo.xd, mo.xdd, mo.t).q)
    assert extra == {"min_inverse_measure": sm.inverse.min(), "min_direct_measure": sm.direct.min(),
                     "min_constraint_measure": sm.constraint.min()}


def _design(seed: int) -> dict:
    rng = np.random.default_rng(seed)
    d = sweep_adapter("hip").base_description(None)
    d["geometry"]["base_radius_m"] *= rng.uniform(0.95, 1.05)
    d["geometry"]["lever_length_m"] *= rng.uniform(0.98, 1.08)
    d["friction"]["screw_coulomb_Nm"] = 0.02
    d["friction"]["slider_viscous_Ns_m"] = 20.0
    d["friction"]["spherical_coulomb_Nm"] = 0.1
    return d


@pytest.mark.parametrize("seed", [1, 2])
def test_a_design_is_the_engine_on_its_generated_description(seed):
    """The row's torques, energies and reactions: those of load_mechanism's model of the
    generated description, compiled from scratch, on the same motion, to the last bit."""
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.params import model_from_dict
    from pkmdyn.multibody import load_mechanism, solve_kinematics
    from pkmdyn.multibody.dynamics.actuators import motor_efforts
    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
    from pkmdyn.sweep_protocol import time_integral

    ad = sweep_adapter("hip")
    ctx = ad.prepare(ad.base_description(None), {"samples_per_cycle": 80, "workspace_points": 0}, Path("."))
    d = _design(seed)
    out = ad.evaluate([d], ctx)[0]
    assert out.status == "ok", out.reason
    m = out.metrics
    model = load_mechanism(hip_description(model_from_dict(d)))
    mo = ctx.engine.motion
    kin = solve_kinematics(model, mo.x, mo.xd, mo.xdd, mo.t)
    reac = joint_reactions(model, kin, named=mo.loads)
    me = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, reac.u)
    assert m["peak_torque_Nm"] == np.abs(me.effort).max()
    assert m["peak_slider_speed_m_s"] == np.abs(kin.act_qd).max()
    friction = time_integral(reac.dissipation + np.sum(me.friction * me.theta_dot, axis=1), mo.t)
    assert m["friction_energy_per_cycle_J"] == friction
    for j, name in enumerate(model.joint_names):
        assert m[f"peak_force_{name}_N"] == np.linalg.norm(reac.joint_force[:, j], axis=-1).max()
        assert m[f"peak_moment_{name}_Nm"] == np.linalg.norm(reac.joint_moment[:, j], axis=-1).max()
    assert m["friction_energy_per_cycle_J"] > 0.0 and math.isfinite(m["motor_energy_per_cycle_J"])


def test_invalid_unreachable_and_singular_designs_are_rows():
    ad = sweep_adapter("hip")
    ctx = ad.prepare(ad.base_description(None), {"samples_per_cycle": 60, "workspace_points": 16}, Path("."))
    short = ad.base_description(None)
    short["geometry"]["lever_length_m"] = 0.05  # cannot reach its platform: the schema's own check
    out = ad.evaluate([short], ctx)[0]
    assert out.status == "invalid" and "lever_length_m" in out.reason and not out.metrics
    strict = ad.prepare(ad.base_description(None), {"samples_per_cycle": 60, "workspace_points": 0,
                                                      "singularity_threshold": 0.5}, Path("."))
    out = ad.evaluate([ad.base_description(None)], strict)[0]
    assert out.status == "singular" and "1/cond(J)" in out.reason and out.metrics["min_inverse_condition"] < 0.5
    assert "peak_force_S0_upper_N" in out.metrics  # what was computed is kept


def test_a_motion_file_and_its_options(tmp_path):
    from pkmdyn.errors import MotionError
    from pkmdyn.profiles.iso14242 import iso14242_motion
    from pkmdyn.profiles.orientation import write_motion_csv

    write_motion_csv(tmp_path / "m.csv", iso14242_motion(1.0, 50))
    ad = sweep_adapter("hip")
    base = ad.base_description(None)
    ctx = ad.prepare(base, {"file": "m.csv", "workspace_points": 0}, tmp_path)
    assert ctx.data.cycles == 1.0 and len(ctx.engine.motion) == 51
    assert set(ctx.engine.motion.loads) == {"hydraulic_N"}
    assert ad.evaluate([base], ctx)[0].status == "ok"
    with pytest.raises(MotionError, match="samples_per_cycle"):
        ad.prepare(base, {"file": "m.csv", "samples_per_cycle": 10}, tmp_path)

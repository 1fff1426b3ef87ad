"""The PDM as a described mechanism: t = 9 and its nine named reactions from the rank, and
the generic kinematics of all 14 bodies against the hand-derived Eq. 2-48, on the Eq. 84
motion and random motions of random variants."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from pkmdyn.machines.pdm4 import BODY_NAMES, default_params_path, inverse_kinematics, load_params
from pkmdyn.machines.pdm4.description import pdm_description
from pkmdyn.multibody import analyse_topology, load_mechanism, solve_kinematics
from pkmdyn.profiles.pdm_motion import PdmMotion, cycloidal_motion


def _variant(seed, tmp_path):
    if seed is None:
        return load_params()
    rng = np.random.default_rng(seed)
    text = default_params_path().read_text(encoding="utf-8")
    raw = tomllib.loads(text)
    g = raw["geometry"]
    changes = {
        "crank_length_m": g["crank_length_m"] * rng.uniform(0.97, 1.03),
        "coupler_length_m": g["coupler_length_m"] * rng.uniform(0.97, 1.03),
        "platform_offset_m": g["platform_offset_m"] * rng.uniform(0.8, 1.2),
        "spu_home_elevation_deg": g["spu_home_elevation_deg"] + rng.uniform(-5, 5),
    }
    for k, v in changes.items():
        old = next(line for line in text.splitlines() if line.startswith(k + " "))
        text = text.replace(old, f"{k} = {v!r}")
    f = tmp_path / f"pdm_{seed}.toml"
    f.write_text(text, encoding="utf-8")
    return load_params(f)


def _rel(a, b):
    return float(np.abs(a - b).max() / max(float(np.abs(b).max()), 1e-12))


def test_pdm_overconstraints_are_the_papers_nine():
    rep = analyse_topology(load_mechanism(pdm_description(load_params())))
    assert (rep.bodies, rep.mobility, rep.overconstraints, rep.idle, rep.dof) == (14, 4, 9, 0, 4)
    assert rep.kutzbach == -5
    assert sorted(rep.overconstrained) == sorted((j, d) for j in ("R21'", "R22'", "R32")
                                                 for d in ("force_z", "couple_x", "couple_y"))


@pytest.mark.parametrize("seed", [None, 21, 22])
def test_generic_kinematics_match_the_hand_derived_ones(seed, tmp_path):
    pm = _variant(seed, tmp_path)
    m = load_mechanism(pdm_description(pm))
    tr = pm.trajectory
    if seed is None:
        motion = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    else:
        rng = np.random.default_rng(seed)
        strokes = np.array(tr.strokes) * rng.uniform(-1, 1, 4)
        motion = cycloidal_motion(tuple(strokes), tr.period_s * rng.uniform(0.5, 2.0), 300)
    ref = inverse_kinematics(pm, motion)
    kin = solve_kinematics(m, motion.q, motion.qd, motion.qdd, motion.t)
    for b, name in enumerate(BODY_NAMES):
        k = m.body_names.index(name)
        st = ref.bodies[b]
        for f in ("R", "p", "v", "a", "w", "wd"):
            assert _rel(getattr(kin, f)[:, k], getattr(st, f)) < 1e-9, (name, f)
    limbs = [m.actuator_names.index(n) for n in ("P11", "P12", "P23", "P24")]
    assert _rel(kin.act_q[:, limbs], ref.pos.l) < 1e-9
    assert _rel(kin.act_qd[:, limbs], ref.ld) < 1e-9
    assert _rel(kin.act_qdd[:, limbs], ref.ldd) < 1e-9


def test_reference_pose_other_than_home(tmp_path):
    pm = load_params()
    q_ref = np.array([0.01, -0.02, 0.05, 0.03])
    m = load_mechanism(pdm_description(pm, q_ref))
    motion = PdmMotion(np.zeros(1), q_ref[None], np.zeros((1, 4)), np.zeros((1, 4)))
    kin = solve_kinematics(m, motion.q, motion.qd, motion.qdd)
    ref = inverse_kinematics(pm, motion)
    assert _rel(kin.R[:, m.body_names.index("crank1")], ref.bodies[BODY_NAMES.index("crank1")].R) < 1e-12

"""Regressor of described mechanisms: efforts linear in the bodies' barycentric parameters and
the joints' Coulomb and viscous coefficients."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import fr_any, joint_reactions
from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics as _inverse_dynamics


def inverse_dynamics(m, kin):
    """Efforts with the joints' friction (the reactions route) or without any (Eq. 3)."""
    return joint_reactions(m, kin) if fr_any(m) else _inverse_dynamics(m, kin)
from pkmdyn.multibody.analyses.regressor import regressor


def _stewart_friction():
    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        for j in leg["joints"]:
            if j["type"] == "spherical":
                j["friction"] = {"coulomb_torque_Nm": 0.1, "viscous_Nm_s_rad": 0.05}
            if j["type"] == "prismatic":
                j["friction"] = {"coulomb_force_N": 5.0, "viscous_N_s_m": 20.0}
    d["loads"] = [{"body": "platform", "force_N": [10.0, 0.0, -50.0], "moment_Nm": [1.0, 0.0, 0.0],
                   "point_m": [0.05, 0.0, 1.0]}]
    return d


CASES = {"stewart_friction": _stewart_friction, "bennett": lambda: ex.builtin_dict("bennett"),
         "four_bar_cut_b": ex.four_bar_cut_b}


def _kin(m, n=40, seed=0):
    t = np.linspace(0.0, 1.0, n)
    amp = np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, seed)
    return solve_kinematics(m, x, xd, xdd, t)


@pytest.mark.parametrize("name", sorted(CASES))
def test_regressor_reproduces_the_efforts(name):
    m = load_mechanism(CASES[name]())
    kin = _kin(m)
    reg = regressor(m, kin)
    u = inverse_dynamics(m, kin).u
    assert np.abs(np.einsum("nap,p->na", reg.Y, reg.theta) + reg.u0 - u).max() <= 1e-10 * np.abs(u).max()


def test_regressor_columns_are_the_derivatives_by_finite_differences():
    """Change one body's mass and centre of mass in the description: the efforts change by the
    regressor times the parameter change (exact: the efforts are linear in the parameters)."""
    d = _stewart_friction()
    m = load_mechanism(d)
    kin = _kin(m)
    reg = regressor(m, kin)
    d2 = ex.deep(d)
    d2["bodies"][0]["mass_kg"] *= 1.3
    d2["bodies"][0]["com_m"] = [0.01, -0.02, 1.03]
    for leg in d2["legs"]:
        for j in leg["joints"]:
            if j["type"] == "prismatic":
                j["friction"]["viscous_N_s_m"] = 35.0
    m2 = load_mechanism(d2)
    reg2 = regressor(m2, solve_kinematics(m2, kin.x, kin.xd, kin.xdd, kin.t))
    du = inverse_dynamics(m2, solve_kinematics(m2, kin.x, kin.xd, kin.xdd, kin.t)).u - inverse_dynamics(
        m, kin).u
    assert np.abs(np.einsum("nap,p->na", reg.Y, reg2.theta - reg.theta) - du).max() <= 1e-9 * np.abs(du).max()


def test_least_squares_recovers_a_changed_model():
    """Efforts of a changed Stewart platform (masses), identified by least squares on the
    regressor of the nominal one: the fitted parameters predict the efforts of another motion."""
    d = _stewart_friction()
    m = load_mechanism(d)
    kin = _kin(m, n=200, seed=3)
    reg = regressor(m, kin)
    d2 = ex.deep(d)
    d2["bodies"][0]["mass_kg"] = 12.5
    for leg in d2["legs"]:
        for b in leg["bodies"]:
            b["mass_kg"] *= 1.2
    m2 = load_mechanism(d2)
    u2 = inverse_dynamics(m2, solve_kinematics(m2, kin.x, kin.xd, kin.xdd, kin.t)).u
    A = reg.Y.reshape(-1, reg.Y.shape[2])
    th, *_ = np.linalg.lstsq(A, (u2 - reg.u0).reshape(-1), rcond=None)
    assert np.abs(A @ th - (u2 - reg.u0).reshape(-1)).max() <= 1e-8 * np.abs(u2).max()
    # the fitted parameters (the base parameters' combinations; single masses need not be
    # identifiable) predict the changed machine's efforts on another motion
    kin_b = _kin(m, n=60, seed=9)
    reg_b = regressor(m, kin_b)
    u2_b = inverse_dynamics(m2, solve_kinematics(m2, kin_b.x, kin_b.xd, kin_b.xdd, kin_b.t)).u
    pred = np.einsum("nap,p->na", reg_b.Y, th) + reg_b.u0
    # (weakly excited directions of the fit amplify round-off: measured ~1e-7, allowed 1e-5)
    assert np.abs(pred - u2_b).max() <= 1e-5 * np.abs(u2_b).max()
    # and the nominal parameters do not (the change is seen)
    nominal = np.einsum("nap,p->na", reg_b.Y, reg.theta) + reg_b.u0
    assert np.abs(nominal - u2_b).max() > 1e-2 * np.abs(u2_b).max()

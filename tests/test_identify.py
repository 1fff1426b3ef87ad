"""Identification of the hip simulator on the engine: the engine's regressor of the hip's
description named in the hip's parameters, base parameters, constrained fit, excitation. The
synthetic torques are the engine's inverse dynamics (joint reactions), not the regressor."""

from dataclasses import replace

import numpy as np
import pytest

from hip_helpers import SmoothMotion, random_model
from pkmdyn.errors import MotionError, ParameterError
from pkmdyn.identify import base_parameters, bounded_fourier
from pkmdyn.identify._report import identification_report
from pkmdyn.machines.hip_simulator.identify_view import (
    ALL_NAMES,
    consistency_transform,
    engine_torques,
    engine_values,
    hip_regressor,
    identify_hip,
    parameter_names,
    parameter_vector,
    regressor_mechanism,
    savgol_derivatives,
    with_parameters,
)
from pkmdyn.machines.hip_simulator.params import default_params_dict, model_from_dict
from pkmdyn.profiles.iso14242 import iso14242_motion


def _tau(model, motion):
    return engine_torques(model, motion)


def _machine(rng, platform_mass=3.0):
    """The paper's machine (physically consistent inertia) with random non-default friction."""
    d = default_params_dict()
    d["inertia"]["platform_mass_kg"] = platform_mass
    d["friction"].update(
        hip_coefficient=rng.uniform(0.05, 0.2),
        thrust_coefficient=rng.uniform(0.01, 0.05),
        slider_coulomb_N=rng.uniform(1, 10),
        slider_viscous_Ns_m=rng.uniform(5, 50),
        screw_coulomb_Nm=rng.uniform(0.002, 0.02),
        screw_viscous_Nms_rad=rng.uniform(1e-5, 1e-4),
        spherical_coulomb_Nm=rng.uniform(0.05, 0.3),
        spherical_viscous_Nms_rad=rng.uniform(0.005, 0.05),
        universal_coulomb_Nm=rng.uniform(0.05, 0.3),
        universal_viscous_Nms_rad=rng.uniform(0.005, 0.05),
    )
    return model_from_dict(d, "test machine")


@pytest.mark.parametrize("which", ["friction", "inertia", "all"])
def test_regressor_times_parameters_is_the_engines_inverse_dynamics(which):
    rng = np.random.default_rng(3)
    model = random_model(rng, friction=True)
    motion = SmoothMotion(rng).motion(np.linspace(0.0, 2.0, 80))
    names = parameter_names(which)
    reg = hip_regressor(model, motion, names)
    tau = _tau(model, motion)
    assert reg.Y.shape == (80, 3, len(names))
    assert np.max(np.abs(reg.efforts(parameter_vector(model, names)) - tau)) <= 1e-10 * np.max(np.abs(tau))
    # other values give other torques: the regressor is not the file's torques in disguise
    scale = {n: rng.uniform(0.5, 1.5) for n in names}
    for body in ("lever", "platform"):  # a principal-inertia triple scaled as one, keeping it physical
        for x in "yz":
            if f"{body}_I{x}_kgm2" in scale:
                scale[f"{body}_I{x}_kgm2"] = scale[f"{body}_Ix_kgm2"]
    theta = parameter_vector(model, names) * np.array([scale[n] for n in names])
    other = with_parameters(model, names, theta)
    assert np.max(np.abs(reg.efforts(theta) - _tau(other, motion))) <= 1e-10 * np.max(np.abs(tau))
    # a model rebuilt from its own parameter vector gives the same torques
    again = with_parameters(model, names, parameter_vector(model, names))
    assert np.allclose(_tau(again, motion), tau, rtol=0, atol=1e-12 * np.max(np.abs(tau)))


def test_the_hip_parameters_map_onto_the_engines_of_the_real_description():
    """The engine's parameters that the hip's values give equal those of the hip's own
    description, wherever that description has the parameter (the load-driven friction written
    as the two unit-radius terms: S - C / F_REF and C / F_REF)."""
    from pkmdyn.machines.hip_simulator.description import hip_description
    from pkmdyn.machines.hip_simulator.identify_view import F_REF
    from pkmdyn.multibody import load_mechanism
    from pkmdyn.multibody.analyses.regressor import regressor
    from pkmdyn.multibody.kinematics.inverse import solve_kinematics

    rng = np.random.default_rng(8)
    model = random_model(rng, friction=True)
    motion = SmoothMotion(rng).motion(np.linspace(0.0, 1.0, 5))
    real = load_mechanism(hip_description(model))
    reg_real = regressor(real, solve_kinematics(real, motion.angles), {"hydraulic_N": motion.load})
    mech = regressor_mechanism(model)
    reg = regressor(mech, solve_kinematics(mech, motion.angles), {"hydraulic_N": motion.load})
    mapped = dict(zip(reg.names, engine_values(model, mech, reg.names,
                                               dict(zip(ALL_NAMES, parameter_vector(model, ALL_NAMES))))))
    compared = 0
    for name, value in zip(reg_real.names, reg_real.theta):
        if "_external" in name:
            continue
        assert mapped[name] == pytest.approx(value, rel=1e-12, abs=1e-15), name
        compared += 1
    assert compared > 150
    S, C = parameter_vector(model, ("bearing_load_coeff_m", "bearing_weight_friction_Nm"))
    assert mapped["S0_upper_external2_hydraulic_N_coefficient"] == pytest.approx(C / F_REF, rel=1e-12)
    assert mapped["S0_lower_external1_hydraulic_N_coefficient"] == pytest.approx(S - C / F_REF, rel=1e-12)


def test_base_parameters_of_a_known_dependence():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(50, 3))
    W = np.column_stack([X[:, 0], X[:, 1], 2.5 * X[:, 0] - X[:, 1], np.zeros(50), X[:, 2]])
    b = base_parameters(W, ("a", "b", "c", "d", "e"))
    assert b.rank == 3 and b.unexcited == (3,)
    theta = rng.normal(size=5)
    # the base parameters reproduce W theta through the independent columns
    assert np.allclose(W[:, list(b.independent)] @ b.values(theta), W @ theta)
    assert set(b.separable()) == {4}
    text = " ".join(b.describe(i) for i in range(b.rank))
    assert "c" in text and "a" in text and "b" in text


@pytest.mark.parametrize("which", ["friction", "all"])
def test_noise_free_recovery_of_identifiable_combinations(which):
    rng = np.random.default_rng(7)
    truth = _machine(rng)
    prior = model_from_dict(default_params_dict())
    motion = SmoothMotion(rng, amplitude_deg=12).motion(np.linspace(0.0, 3.0, 300))
    res = identify_hip(prior, motion, _tau(truth, motion), which)
    true_b = res.base.values(parameter_vector(truth, res.names))
    assert res.base.rank >= len(res.names) - 2
    assert np.all(np.abs(res.estimate.base_values - true_b) <= 1e-6 * np.abs(true_b) + 1e-12)
    assert np.max(res.residual_rms) < 1e-9
    # the bearing products S and C, and every separable parameter, recovered on their own
    est = dict(zip(res.names, res.estimate.theta))
    true = dict(zip(res.names, parameter_vector(truth, res.names)))
    for name in ("bearing_load_coeff_m", "bearing_weight_friction_Nm"):
        assert est[name] == pytest.approx(true[name], rel=1e-6)
    for k in res.base.separable():
        assert est[res.names[k]] == pytest.approx(true[res.names[k]], rel=1e-5), res.names[k]
    # the identified file's split reproduces S and C
    f, m = res.model.friction, res.model.inertia
    assert f.r_h * f.mu_h + f.r_t * f.mu_t == pytest.approx(true["bearing_load_coeff_m"], rel=1e-6)
    assert f.r_t * f.mu_t * m.m_m * m.g == pytest.approx(true["bearing_weight_friction_Nm"], rel=1e-6)


def test_unseparable_coefficients_are_reported_only_as_combinations():
    rng = np.random.default_rng(11)
    truth = _machine(rng, platform_mass=0.0)
    prior = replace(truth, inertia=replace(truth.inertia, m_m=0.0))
    motion = SmoothMotion(rng).motion(np.linspace(0.0, 3.0, 200))
    res = identify_hip(prior, motion, _tau(truth, motion), "friction")
    T = consistency_transform(res.names)[0]
    tau_rms = np.sqrt(np.mean(res.tau_measured**2, axis=0))
    report = identification_report(res.base, res.estimate, res.prior, ("a", "b", "c"), tau_rms, res.residual_rms, T)
    # viscous friction of slider and screw act alike (screw speed = slider speed / gear)
    for name in ("slider_viscous_Ns_m", "screw_viscous_Nms_rad"):
        assert name not in report["separable"] and name in report["not_separable"]
    combo = next(c for c in report["combinations"] if "slider_viscous_Ns_m" in c["terms"])
    assert "screw_viscous_Nms_rad" in combo["terms"]
    # the hip-joint and thrust-bearing coefficients enter only through S and C: no number of their own
    text = str(report)
    assert "hip_coefficient" not in text and "thrust_coefficient" not in text
    assert report["separable"]["bearing_weight_friction_Nm"]["estimate"] == pytest.approx(0.0, abs=1e-9)


def test_constraints_hold_where_the_data_would_break_them():
    rng = np.random.default_rng(5)
    truth = _machine(rng)
    # an unphysical machine: negative S-joint friction and lever inertias breaking the triangle inequality
    bad = replace(
        truth,
        friction=replace(truth.friction, spherical_coulomb=-0.3),
        inertia=replace(truth.inertia, I_l=np.array([0.03, 0.01, 0.005])),
    )
    motion = SmoothMotion(rng, amplitude_deg=12).motion(np.linspace(0.0, 3.0, 300))
    # no description holds such a machine (the engine refuses it): its torques by the regressor
    names = parameter_names("all")
    res = identify_hip(truth, motion, hip_regressor(truth, motion, names).efforts(parameter_vector(bad, names)), "all")
    est = dict(zip(res.names, res.estimate.theta))
    assert all(est[n] >= 0.0 for n in parameter_names("friction"))
    assert est["spherical_coulomb_Nm"] == pytest.approx(0.0, abs=1e-9)
    I = np.array([est[f"lever_I{x}_kgm2"] for x in "xyz"])
    assert np.all(I.sum() - 2 * I >= -1e-12 * I.sum())  # I_a + I_b >= I_c for every axis
    # the broken one is active: its second moment of mass (I.sum() / 2 - I.max()) sits on the
    # solver's lower bound (consistency_transform), up to rounding of the inertia's size
    _, lower, _ = consistency_transform(res.names)
    floor = lower[res.names.index("lever_Ix_kgm2")]
    assert I.sum() - 2 * I.max() == pytest.approx(2 * floor, abs=1e-12 * I.sum())
    assert all(est[n] > 0 for n in ("slider_mass_kg", "lever_mass_kg", "screw_inertia_kgm2"))


def test_noisy_identification_predicts_a_held_out_motion():
    rng = np.random.default_rng(2)
    truth = _machine(rng)
    prior = model_from_dict(default_params_dict())
    motion = SmoothMotion(rng, amplitude_deg=12).motion(np.linspace(0.0, 4.0, 600))
    tau = _tau(truth, motion)
    noisy = tau + rng.normal(size=tau.shape) * 0.02 * np.sqrt(np.mean(tau**2, axis=0))
    res = identify_hip(prior, motion, noisy, "friction")
    held = iso14242_motion(1.0, 300)
    tau_held = _tau(truth, held)
    err = np.sqrt(np.mean((_tau(res.model, held) - tau_held) ** 2, axis=0)) / np.sqrt(np.mean(tau_held**2, axis=0))
    assert np.all(err < 0.03)
    prior_err = np.sqrt(np.mean((_tau(prior, held) - tau_held) ** 2, axis=0)) / np.sqrt(np.mean(tau_held**2, axis=0))
    assert np.all(prior_err > 3 * err)  # the identification did something


def test_bad_inputs_raise_motion_errors():
    prior = model_from_dict(default_params_dict())
    rng = np.random.default_rng(1)
    motion = SmoothMotion(rng).motion(np.linspace(0.0, 1.0, 40))
    tau = _tau(prior, motion)
    with pytest.raises(MotionError, match="too few"):
        identify_hip(prior, SmoothMotion(rng).motion(np.linspace(0.0, 1.0, 5)), tau[:5], "all")
    bad = tau.copy()
    bad[3, 1] = np.nan
    with pytest.raises(MotionError, match="row 4.*tau2_Nm"):
        identify_hip(prior, motion, bad, "friction")
    still = type(motion)(motion.t, np.zeros((40, 3)), np.zeros((40, 3)), np.zeros((40, 3)), np.zeros(40))
    with pytest.raises(MotionError, match="rank 0"):
        identify_hip(prior, still, _tau(prior, still), "friction")


def test_bounded_fourier_derivatives_and_range():
    rng = np.random.default_rng(4)
    c = rng.normal(0, 1.5, 7)
    t = np.linspace(0, 2, 2001)
    x, xd, xdd = bounded_fourier(t, 2.0, c, -0.3, 0.5)
    assert np.all((x > -0.3) & (x < 0.5))
    h = 1e-5
    xp, xdp, _ = bounded_fourier(t + h, 2.0, c, -0.3, 0.5)
    xm, xdm, _ = bounded_fourier(t - h, 2.0, c, -0.3, 0.5)
    assert np.allclose((xp - xm) / (2 * h), xd, atol=1e-6 * np.max(np.abs(xd)))
    assert np.allclose((xdp - xdm) / (2 * h), xdd, atol=1e-6 * np.max(np.abs(xdd)))
    x1 = bounded_fourier(t + 2.0, 2.0, c, -0.3, 0.5)[0]
    assert np.allclose(x1, x)  # periodic


def test_savgol_differentiator_on_a_smooth_signal():
    t = np.linspace(0, 1, 501)
    x = np.sin(2 * np.pi * t)[:, None]
    d1, d2 = savgol_derivatives(t, x, 15, 5, "test")
    assert np.allclose(d1[:, 0], 2 * np.pi * np.cos(2 * np.pi * t), atol=1e-4)
    assert np.allclose(d2[:, 0], -((2 * np.pi) ** 2) * np.sin(2 * np.pi * t), atol=5e-2)
    with pytest.raises(MotionError, match="uniform"):
        savgol_derivatives(t ** 1.1, x, 15, 5, "test")


def test_paper_fit_preset_is_closer_to_the_paper_than_the_default():
    from pkmdyn.machines.hip_simulator import load_params
    from pkmdyn.profiles.iso14242 import IsoCycle
    from pkmdyn.machines.hip_simulator.paper import PAPER_SLIDER_MAXIMA, iso_cycle_preset
    from pkmdyn.machines.hip_simulator.paper import slider_maxima

    model = load_params()
    fit = slider_maxima(model, iso_cycle_preset("paper-fit")) / PAPER_SLIDER_MAXIMA - 1.0
    default = slider_maxima(model, iso_cycle_preset("default")) / PAPER_SLIDER_MAXIMA - 1.0
    assert iso_cycle_preset("default") == IsoCycle()
    assert np.sum(fit**2) < 0.1 * np.sum(default**2)
    with pytest.raises(ParameterError, match="motion model"):
        iso_cycle_preset("nope")


def test_excitation_respects_its_limits_and_is_better_conditioned_than_its_start():
    from pkmdyn.machines.hip_simulator.identify_excite import (ExcitationLimits, design_excitation,
                                                               excitation_motion, slider_rates)
    from pkmdyn.machines.hip_simulator.identify_view import engine_kinematics

    prior = model_from_dict(default_params_dict())
    limits = ExcitationLimits(slider_speed_m_s=0.2, slider_accel_m_s2=2.0)
    ex = design_excitation(prior, "friction", limits, harmonics=2, samples=48, iterations=2, starts=1, seed=3)
    t = np.linspace(0.0, ex.period_s, 400)
    motion = excitation_motion(ex.coeffs, ex.period_s, limits, t)
    mech = regressor_mechanism(prior)
    Ld, Ldd, cond = slider_rates(mech, engine_kinematics(mech, motion), prior.geometry.euler_sequence)
    assert np.max(np.abs(Ld)) <= 0.2 * (1 + 1e-6) and np.max(np.abs(Ldd)) <= 2.0 * (1 + 1e-6)
    assert np.all((motion.load > 300) & (motion.load < 3000)) and ex.period_s >= 2.0
    assert 1.0 <= np.max(cond) <= limits.cond_J
    # the designed motion's regressor has the rank the design claims, at its condition number
    W = hip_regressor(prior, motion, parameter_names("friction")).stacked()
    names = parameter_names("friction")
    A = W[:, [names.index(n) for n in ex.parameters]]
    s = np.linalg.svd(A / np.linalg.norm(A, axis=0), compute_uv=False)
    assert s[0] / s[-1] < 1e4


def test_cond_j_is_that_of_the_slider_speeds_per_angular_velocity():
    """J maps the platform's angular velocity to the slider speeds: J omega = Ld along a motion."""
    from pkmdyn.machines.hip_simulator.identify_excite import slider_rates
    from pkmdyn.machines.hip_simulator.identify_view import engine_kinematics
    from pkmdyn.spatial import euler_kinematics

    rng = np.random.default_rng(6)
    model = random_model(rng)
    motion = SmoothMotion(rng).motion(np.linspace(0.0, 1.0, 30))
    mech = regressor_mechanism(model)
    kin = engine_kinematics(mech, motion)
    Ld, _, cond = slider_rates(mech, kin, model.geometry.euler_sequence)
    _, omega, _ = euler_kinematics(model.geometry.euler_sequence, motion.angles, motion.rates, motion.accels)
    zero = np.zeros_like(motion.angles)
    E = np.stack([euler_kinematics(model.geometry.euler_sequence, motion.angles,
                                   np.broadcast_to(np.eye(3)[k], zero.shape), zero)[1] for k in range(3)], axis=-1)
    J = kin.J_ax @ np.linalg.inv(E)
    assert np.allclose(np.einsum("nij,nj->ni", J, omega), Ld, rtol=0, atol=1e-12 * np.max(np.abs(Ld)))
    assert np.allclose(cond, np.linalg.cond(J), rtol=1e-12) and np.all(cond >= 1.0)


def test_the_generic_layer_identifies_another_machine():
    """The same regressor, base parameters and solver on a second machine (the two-link toy arm)."""
    from dataclasses import replace as rep

    import toy_machine
    from pkmdyn.identify._identify import identify_efforts

    names = ("I1_kgm2", "I2_kgm2", "m1_kg", "mu0_Nm", "mu_load_Nm_N", "viscous_Nms_rad")
    fields = ("I1", "I2", "m1", "mu0", "mu_load", "viscous")
    truth = toy_machine.ToyModel(I1=0.05, I2=0.015, m1=2.6, mu0=0.8, mu_load=2e-3, viscous=0.12)
    prior = toy_machine.ToyModel()
    q, qd, qdd, load = toy_machine.motion(np.linspace(0.0, 2.0, 200))
    machine = toy_machine.verbs()
    u = machine.inverse_dynamics(truth, q, qd, qdd, load)

    def model_with(theta):
        return rep(prior, **dict(zip(fields, theta)))

    p = len(names)
    res = identify_efforts(machine, model_with, names, np.array([getattr(prior, f) for f in fields]),
                           (np.eye(p), np.zeros(p), np.full(p, np.inf)), q, qd, qdd, load, u)
    assert res.base.rank == p and res.base.separable() == tuple(range(p))
    assert np.allclose(res.estimate.theta, [getattr(truth, f) for f in fields], rtol=1e-6, atol=0)
    # a load that never changes makes the load-dependent friction inseparable from mu0
    res2 = identify_efforts(machine, model_with, names, np.zeros(p), (np.eye(p), np.zeros(p), np.full(p, np.inf)),
                            q, qd, qdd, np.full(200, 1000.0), machine.inverse_dynamics(truth, q, qd, qdd, np.full(200, 1000.0)))
    assert res2.base.rank == p - 1
    combo = [res2.base.terms(i) for i in range(res2.base.rank) if len(res2.base.terms(i)) > 1]
    assert len(combo) == 1 and set(combo[0]) == {"mu0_Nm", "mu_load_Nm_N"}
    k = [i for i in range(res2.base.rank) if len(res2.base.terms(i)) > 1][0]
    assert res2.estimate.base_values[k] == pytest.approx(res2.base.values(np.array([getattr(truth, f) for f in fields]))[k], rel=1e-6)


def test_paper_fit_zxy_preset_meets_the_nine_maxima_with_that_sequence():
    from pkmdyn.machines.hip_simulator.paper import PAPER_SLIDER_MAXIMA, iso_cycle_preset
    from pkmdyn.machines.hip_simulator.paper import slider_maxima

    d = default_params_dict()
    d["geometry"]["euler_sequence"] = "ZXY"
    rel = slider_maxima(model_from_dict(d), iso_cycle_preset("paper-fit-zxy")) / PAPER_SLIDER_MAXIMA - 1.0
    assert np.max(np.abs(rel)) < 0.02


@pytest.mark.parametrize("m_m, S, C", [(0.0, 4e-3, 0.0), (0.0, 4e-3, 0.09), (4.0, 4e-3, 0.09), (4.0, 4e-3, 5.0),
                                       (4.0, 4e-3, 0.0), (2.0, 0.0, 0.0)])
def test_bearing_split_reproduces_both_products(m_m, S, C):
    from pkmdyn.machines.hip_simulator.identify_view import bearing_split

    d = default_params_dict()
    d["inertia"]["platform_mass_kg"] = m_m
    model = model_from_dict(d)
    f, g = model.friction, model.inertia.g
    mu_h, mu_t, mass = bearing_split(model, S, C)
    assert mu_h >= 0 and mu_t >= 0 and mass >= 0
    assert f.r_h * mu_h + f.r_t * mu_t == pytest.approx(S, rel=1e-12, abs=1e-18)
    assert f.r_t * mu_t * mass * g == pytest.approx(C, rel=1e-12, abs=1e-18)
    keepable = C == 0.0 or (m_m > 0 and C / (m_m * g) <= S)
    if keepable:
        assert mass == m_m  # the file's platform mass is kept whenever it can be

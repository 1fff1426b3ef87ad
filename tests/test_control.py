"""Controllers (pkmdyn.control) in closed loop: open-loop replay of the feedforward on an exact
plant, augmented PD against PD under the default model mismatch, the laws on the toy machine,
gain and settings checks."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import toy_machine as toy
from pkmdyn.jobs.control import builtin_closed_loop, machine_setup
from pkmdyn.control import Gains, effort, gains, load_settings, loop_settings, make_controller, sample_reference
from pkmdyn.errors import ParameterError
from pkmdyn.simulate import DivergenceError, LoopSettings, track



def _toy_settings(**kw) -> LoopSettings:
    base = LoopSettings(cycle_s=1e-3, step_s=5e-4, effort_limit=np.full(2, 50.0), divergence_limit=np.full(2, 0.5),
                        encoder_resolution=1e-6, velocity_cutoff_Hz=200.0, acceleration_cutoff_Hz=50.0,
                        pose_noise=np.zeros(2), pose_delay_cycles=0, seed=3)
    return replace(base, **kw)


# ----------------------------------------------------------------------------- open-loop replay
def test_hip_feedforward_replay_on_exact_plant():
    """Feedforward, plant = controller model, one ISO cycle, at the DEFAULT settings (1 ms
    cycle, one integration step per cycle; the feedforward reads no sensor): within 1e-3 deg,
    at every cycle instant and at the end."""
    tr = builtin_closed_loop("hip", 1.0, "feedforward", exact_plant=True)
    r = tr.result
    K = r.t.shape[0]
    err = np.rad2deg(np.abs(tr.reference.q[:K] - r.q))
    assert err.max() < 1e-3
    assert np.rad2deg(np.abs(tr.reference.q[-1] - r.q_end)).max() < 1e-3


def test_hip_replay_error_is_the_hold_not_the_integrator():
    """At the default settings the replay error is that of the zero-order hold: a ten times
    finer integration step changes it by less than a tenth of the 1e-3 deg bound, and ROS2
    alone (second order) at the default step is several times further off."""
    from pkmdyn.simulate import track

    s = load_settings("hip")
    ls = loop_settings(s)
    base = builtin_closed_loop("hip", 1.0, "feedforward", exact_plant=True)
    fine = builtin_closed_loop("hip", 1.0, "feedforward", integration_step_s=1e-4, exact_plant=True)
    assert np.rad2deg(np.abs(base.result.q - fine.result.q)).max() < 1e-4
    su = machine_setup("hip", None, None, None, 1.0, s)
    ros2 = track(su.verbs, su.model, su.model, su.motion, 1.0, "feedforward", gains(s, "feedforward", 3),
                 replace(ls, method="ros2"), True)
    K = base.result.t.shape[0]
    e_base = np.abs(base.reference.q[:K] - base.result.q).max()
    e_ros2 = np.abs(ros2.reference.q[:K] - ros2.result.q).max()
    assert e_ros2 > 5 * e_base


def test_held_effort_on_the_sampled_double_integrator():
    """The held-effort analysis of ``pkmdyn.control._reference`` on ``qdd = u`` sampled exactly
    (``q += T v + T^2/2 u_k``, ``v += T u_k``) with ``u*(t) = sin(w t)``: the position error at
    ``t`` matches ``T^2 [(c - 1/24)(u*(t) - u*(0) - u*'(0) t) + (u*(t) - u*(0))/12]`` for the
    interval mean (``c = 1/24``) and the middle value (``c = 0``), and ``held_efforts`` (``c =
    -1/24`` and the start corrected) is a hundred times closer than either over three periods."""
    from pkmdyn.control import held_efforts

    T, w, K = 1e-3, 2 * np.pi, 3000
    t = np.arange(K + 1) * T
    mid = np.sin(w * (t[:-1] + T / 2))
    mean = (np.cos(w * t[:-1]) - np.cos(w * t[1:])) / (w * T)
    q_ref = -np.sin(w * t) / w**2 + t / w  # q(0) = 0, v(0) = 0, qdd = sin(w t)

    def replay(u):
        q, v, out = 0.0, 0.0, np.empty(K)
        for k in range(K):
            q += T * v + T * T / 2 * u[k]
            v += T * u[k]
            out[k] = q - q_ref[k + 1]
        return out

    e = {"mean": replay(mean), "mid": replay(mid), "held": replay(held_efforts(mid[:, None])[:, 0])}
    k = 799  # t = 0.8 s
    tt = t[k + 1]
    for name, c in (("mean", 1 / 24), ("mid", 0.0)):
        pred = T**2 * ((c - 1 / 24) * (np.sin(w * tt) - w * tt) + np.sin(w * tt) / 12)
        assert e[name][k] == pytest.approx(pred, rel=0.02)
    assert np.abs(e["held"]).max() < min(np.abs(e["mean"]).max(), np.abs(e["mid"]).max()) / 100


def test_pdm_feedforward_replay_on_exact_plant():
    """Feedforward on the exact PDM plant: platform position and limb displacements within
    1e-3 mm over the first 0.3 s of the cycle. In force control the PDM is open-loop unstable
    (gravity tips the platform about R4; errors e-fold in about 65 ms), so a replay error of
    any origin grows without bound over the 2 s cycle (docs/control.md); over 0.3 s the bound
    tests the feedforward and the hold, and the error falls faster than the cycle (as its
    cube with the held effort of ``held_efforts``)."""
    s = load_settings("pdm")
    su = machine_setup("pdm", None, None, None, 1.0, s)
    errs = []
    for T in (2e-3, 1e-3):
        ls = replace(loop_settings(s), cycle_s=T, step_s=T / 2, encoder_resolution=0.0)
        tr = track(su.verbs, su.model, su.model, su.motion, 0.3, "feedforward", gains(s, "feedforward", 4), ls, False,
                   joint_accelerations=False)
        r = tr.result
        K = r.t.shape[0]
        assert np.abs(tr.reference.q[:K, :2] - r.q[:, :2]).max() < 1e-6  # m
        assert np.abs(tr.joint.s[:K] - r.s).max() < 1e-6  # m
        errs.append(np.abs(tr.reference.q[:K] - r.q).max())
    assert errs[0] > 3 * errs[1]


# ----------------------------------------------------------------------------- mismatch
def test_augmented_pd_beats_pd_under_default_mismatch():
    """Default plant (masses x 1.10, friction x 1.25), default gains and sensors, the first
    0.3 s of the ISO cycle (stance, loads up to 3000 N): augmented PD's posture errors are
    smaller than PD's, RMS and maximum, for every angle."""
    res = {}
    for kind in ("pd", "augmented-pd"):
        tr = builtin_closed_loop("hip", 0.3, kind)
        K = tr.result.t.shape[0]
        e = tr.reference.q[:K] - tr.result.q
        res[kind] = (np.sqrt(np.mean(e**2, axis=0)), np.max(np.abs(e), axis=0))
    assert np.all(res["augmented-pd"][0] < res["pd"][0])
    assert np.all(res["augmented-pd"][1] < res["pd"][1])


# ----------------------------------------------------------------------------- toy machine
TOY_GAINS = {
    "pd": Gains(np.full(2, 400.0), np.full(2, 20.0), np.zeros(2)),
    "augmented-pd": Gains(np.full(2, 400.0), np.full(2, 20.0), np.zeros(2)),
    "computed-torque": Gains(np.full(2, 900.0), np.full(2, 42.0), np.zeros(2)),
    "pid": Gains(np.full(2, 400.0), np.full(2, 20.0), np.full(2, 2000.0)),
}


def test_laws_track_the_toy_machine():
    """Every law keeps the toy arm (reference with reversals, Coulomb friction under a varying
    load) within 0.05 rad, exact or mismatched plant; on the exact plant the model-based laws
    (augmented PD, computed torque) are at least ten times closer than PD with the same
    feedback, and under mismatch augmented PD stays closer than PD."""
    err = {}
    for kind, g in TOY_GAINS.items():
        for tag, plant in (("exact", toy.ToyModel()), ("mismatch", toy.mismatched(toy.ToyModel(), 0.1, 0.25))):
            tr = track(toy.verbs(True), toy.ToyModel(), plant, toy.motion, 0.5, kind, g, _toy_settings(), True,
                       joint_accelerations=False)
            K = tr.result.t.shape[0]
            err[kind, tag] = np.abs(tr.reference.q[:K] - tr.result.q).max()
    assert max(err.values()) < 0.05
    assert err["augmented-pd", "exact"] < err["pd", "exact"] / 10
    assert err["computed-torque", "exact"] < err["pd", "exact"] / 10
    assert err["augmented-pd", "mismatch"] < err["pd", "mismatch"]


def test_pd_law_is_eq15_reading():
    """u = B(q_ref)^-1 (K_p e + K_d e_dot) at one cycle, by hand."""
    v, m = toy.verbs(), toy.ToyModel()
    ref = sample_reference(toy.motion, 0.01, 1e-3)
    g = Gains(np.array([100.0, 200.0]), np.array([3.0, 4.0]), np.zeros(2))
    ctrl = make_controller("pd", g, v, m, ref)
    from pkmdyn.control import Sensed

    y = Sensed(ref.q[4] + [0.01, -0.02], ref.qd[4] + [0.1, 0.2], np.zeros(2), np.zeros(2), np.zeros(2))
    u = effort(ctrl, ref, 4, y, np.zeros(2))
    w = g.kp * (ref.q[4] - y.q) + g.kd * (ref.qd[4] - y.qd)
    np.testing.assert_allclose(np.asarray(m.B) @ u, w, rtol=1e-12)


def test_divergence_is_reported_with_its_time():
    g = Gains(np.full(2, 1e7), np.full(2, 0.0), np.zeros(2))
    with pytest.raises(DivergenceError, match=r"diverged at t = \d"):
        track(toy.verbs(True), toy.ToyModel(), toy.ToyModel(), toy.motion, 0.5, "pd", g,
              _toy_settings(pose_delay_cycles=3), True)


# ----------------------------------------------------------------------------- checks
@pytest.mark.parametrize("bad", [-1.0, np.inf, np.nan])
def test_bad_gains_rejected(bad):
    ref = sample_reference(toy.motion, 0.01, 1e-3)
    g = Gains(np.array([1.0, bad]), np.ones(2), np.zeros(2))
    with pytest.raises(ParameterError, match=r"kp\[1\]"):
        make_controller("pd", g, toy.verbs(), toy.ToyModel(), ref)


def test_unknown_controller_rejected():
    ref = sample_reference(toy.motion, 0.01, 1e-3)
    with pytest.raises(ParameterError, match="unknown"):
        make_controller("bang-bang", Gains(np.ones(2), np.ones(2), np.ones(2)), toy.verbs(), toy.ToyModel(), ref)


@pytest.mark.parametrize("text, match", [
    ("[pd]\nkp_Nm_rad = [1.0, -2.0, 3.0]\n", r"kp_Nm_rad\[1\].*>= 0"),
    ("[pd]\nkp_Nm_rad = [1.0, nan, 3.0]\n", "not finite"),
    ("[pd]\nkp_Nm_rad = [1.0, 2.0]\n", "list of 3"),
    ("[pd]\nkq_Nm_rad = [1.0, 2.0, 3.0]\n", "unknown key"),
    ("[pid]\nkp_N_m = [1.0, 2.0, 3.0, 4.0]\n", "unknown table"),
    ("[timing]\ncontrol_cycle_s = 0.0\n", "must be > 0"),
    ("[sensors]\npose_delay_cycles = 1.5\n", "whole number"),
])
def test_bad_settings_rejected(tmp_path, text, match):
    p = tmp_path / "g.toml"
    p.write_text(text)
    with pytest.raises(ParameterError, match=match):
        load_settings("hip", p)


def test_settings_override_and_units(tmp_path):
    p = tmp_path / "g.toml"
    p.write_text("[sensors]\npose_noise_deg = [0.0, 0.1, 0.0]\n[pd]\nkd_Nms_rad = [1.0, 2.0, 3.0]\n")
    s = load_settings("hip", p)
    ls = loop_settings(s)
    np.testing.assert_allclose(ls.pose_noise, np.deg2rad([0.0, 0.1, 0.0]))
    g = gains(s, "pd", 3)
    np.testing.assert_allclose(g.kd, [1.0, 2.0, 3.0])
    np.testing.assert_allclose(g.kp, load_settings("hip")["pd"]["kp_Nm_rad"])
    assert g.ki.shape == (3,) and not g.ki.any()


def test_mismatch_scales_masses_and_friction():
    from pkmdyn.control import scale_description
    from pkmdyn.machines.hip_simulator.params import default_params_dict

    d = default_params_dict()
    s = scale_description(d, 1.1, 1.25)
    assert s["inertia"]["slider_mass_kg"] == pytest.approx(1.1 * d["inertia"]["slider_mass_kg"])
    assert s["inertia"]["platform_inertia_kgm2"][2] == pytest.approx(1.1 * d["inertia"]["platform_inertia_kgm2"][2])
    assert s["friction"]["hip_coefficient"] == pytest.approx(1.25 * d["friction"]["hip_coefficient"])
    assert s["friction"]["hip_radius_m"] == d["friction"]["hip_radius_m"]
    assert s["geometry"] == d["geometry"]


def test_joint_reference_integrates_the_actuator_rates():
    """With a constant actuator map (toy machine), s = B^T (q - q0) exactly; rates B^T qd and
    accelerations B^T qdd."""
    from pkmdyn.control import joint_reference

    m = toy.ToyModel()
    ref = sample_reference(toy.motion, 0.5, 1e-3)
    j = joint_reference(toy.verbs(), m, ref, toy.motion)
    Bt = np.asarray(m.B).T
    np.testing.assert_allclose(j.s, (ref.q - ref.q[0]) @ Bt.T, atol=1e-9)
    np.testing.assert_allclose(j.sd, ref.qd @ Bt.T, atol=1e-12)
    np.testing.assert_allclose(j.sdd, ref.qdd @ Bt.T, rtol=1e-5, atol=1e-5)


def test_hermite_motion_reproduces_a_quintic_and_its_samples():
    """The quintic Hermite interpolant through samples of one quintic polynomial per coordinate
    is that polynomial (value, rate and acceleration between the samples, to rounding); times
    beyond the samples are refused."""
    from pkmdyn.control import hermite_motion
    from pkmdyn.errors import MotionError

    rng = np.random.default_rng(7)
    coef = rng.normal(size=(6, 3))  # six powers, three coordinates
    t = np.sort(np.concatenate([[0.0, 1.5], rng.uniform(0.0, 1.5, 9)]))

    def poly(tt, d):
        out = np.zeros((tt.size, 3))
        for k in range(d, 6):
            f = np.prod(np.arange(k - d + 1, k + 1)) if d else 1.0
            out += f * np.outer(tt ** (k - d), coef[k])
        return out

    fn = hermite_motion(t, poly(t, 0), poly(t, 1), poly(t, 2), np.linspace(0.0, 3.0, t.size))
    tt = rng.uniform(0.0, 1.5, 200)
    q, qd, qdd, load = fn(tt)
    for d, got in enumerate((q, qd, qdd)):
        want = poly(tt, d)
        assert np.max(np.abs(got - want)) <= 1e-10 * np.max(np.abs(want))
    assert np.allclose(load, np.interp(tt, t, np.linspace(0.0, 3.0, t.size)), rtol=0, atol=1e-14)
    q, qd, qdd, _ = fn(t - t[0])
    for d, got in enumerate((q, qd, qdd)):
        assert np.max(np.abs(got - poly(t, d))) <= 1e-11 * np.max(np.abs(poly(t, d)))
    with pytest.raises(MotionError, match="beyond"):
        fn(np.array([1.6]))


def test_hermite_motion_keeps_the_rates_of_a_small_motion_about_a_large_offset():
    """A coordinate of 1 m moving by 1 mm, sampled every millisecond: the interpolant's rates and
    accelerations between the samples are those of the Bernstein form (scipy's BPoly, one per
    coordinate) to 1e-12 and 1e-10 of their peaks; converted to the power basis as it is, the
    offset's rounding would cost them some 1e-9 and 1e-7."""
    from scipy.interpolate import BPoly

    from pkmdyn.control import hermite_motion

    t = np.arange(201) * 1e-3
    w = 2 * np.pi * 5.0
    q, qd, qdd = 1.0 + 1e-3 * np.sin(w * t), 1e-3 * w * np.cos(w * t), -1e-3 * w * w * np.sin(w * t)
    fn = hermite_motion(t, q[:, None], qd[:, None], qdd[:, None], None)
    ref = BPoly.from_derivatives(t, np.stack([q, qd, qdd], axis=-1))
    tt = np.random.default_rng(5).uniform(0.0, t[-1], 300)
    _, rate, acc, _ = fn(tt)
    assert np.max(np.abs(rate[:, 0] - ref(tt, 1))) <= 1e-12 * np.max(np.abs(qd))
    assert np.max(np.abs(acc[:, 0] - ref(tt, 2))) <= 1e-10 * np.max(np.abs(qdd))

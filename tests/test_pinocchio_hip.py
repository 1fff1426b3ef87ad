"""The hip simulator's motor torques by the generic engine (its description) against an
independent Pinocchio reference.

The reference (``tests/oracles/hip_pinocchio.py``) solves the machine as a spanning tree with
loop-closure multipliers; it shares no formula with the engine's cut-joint reactions. Cases: the
built-in parameters and random variants (geometry, inertia, friction, load) driven by smooth
analytic Euler-angle motions. (The closed-form oracle's agreement with the same reference is
checked in ``tests/oracles/test_hip_oracle.py``.)
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

from hip_helpers import engine_torques, random_model  # noqa: E402
from pkmdyn.machines.hip_simulator.params import HipModel, default_params_dict, model_from_dict  # noqa: E402
from pkmdyn.spatial import euler_kinematics  # noqa: E402
from oracles.hip_pinocchio import (  # noqa: E402
    build_tree,
    closure_residual,
    reference_torques,
    spanning_tree_rnea_inputs,
)

RTOL = 1e-6
N_SAMPLES = 40
#: a lever's principal moments far from axisymmetric that a rigid body can have [kg m^2]
ASYMMETRIC = [0.048, 0.025, 0.024]


# --------------------------------------------------------------------------- cases


def perturbed_model(seed: int, spread: float = 0.15, friction: bool = True, **inertia_override) -> HipModel:
    """The built-in machine with lengths, masses and inertias scaled by up to +-spread."""
    return random_model(np.random.default_rng(seed), spread, friction, inertia=inertia_override)


def motion_on(seed: int, t: np.ndarray, amplitude_deg: float = 18.0):
    """Euler angles as sums of three sinusoids per angle, with exact rates and accelerations.

    The motion is fixed by ``seed`` and evaluated on the time grid ``t (n,)`` [s]. Returns ``t``,
    ``angles, rates, accels (n, 3)`` [rad, rad/s, rad/s^2] and a positive load ``(n,)`` [N]. The
    summed amplitude per angle stays below ``amplitude_deg``.
    """
    rng = np.random.default_rng(1000 + seed)
    harm = np.arange(1, 4)[:, None]
    amp = np.deg2rad(amplitude_deg) * rng.dirichlet(np.ones(4), size=3).T[:3] * rng.uniform(0.6, 1.0)  # (harmonic, angle)
    w = 2.0 * np.pi * rng.uniform(0.6, 1.2) * harm  # (3, 1) [rad/s]
    ph = rng.uniform(0.0, 2.0 * np.pi, (3, 3))
    arg = w[None] * t[:, None, None] + ph[None]  # (n, harmonic, angle)
    angles = np.sum(amp * np.sin(arg), axis=1)
    rates = np.sum(amp * w * np.cos(arg), axis=1)
    accels = -np.sum(amp * w**2 * np.sin(arg), axis=1)
    load = 800.0 + 600.0 * np.sin(2.0 * np.pi * rng.uniform(0.5, 1.5) * t + rng.uniform(0.0, 6.0)) ** 2
    return t, angles, rates, accels, load


def smooth_motion(seed: int, n: int = N_SAMPLES):
    """:func:`motion_on` over 1.2 s, ``n`` samples."""
    return motion_on(seed, np.linspace(0.0, 1.2, n))


def both(model: HipModel, seed: int, n: int = N_SAMPLES):
    t, ang, rat, acc, load = smooth_motion(seed, n)
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, ang, rat, acc)
    ours = engine_torques(model, ang, rat, acc, load, t)
    ref = reference_torques(model, t, R, w, wd, load)
    return ours, ref, (t, R, w, wd, load)


def rel_diff(a: np.ndarray, b: np.ndarray, scale: float) -> float:
    return float(np.max(np.abs(a - b)) / scale)


CASES = {
    "builtin": lambda: model_from_dict(default_params_dict(), "built-in"),
    "builtin_all_friction": lambda: perturbed_model(0, spread=0.0, friction=True),
    "random_1": lambda: perturbed_model(1, spread=0.15),
    "random_2": lambda: perturbed_model(2, spread=0.20),
    "random_3_hip_friction_only": lambda: perturbed_model(3, spread=0.20, friction=False),
    # non-axisymmetric lever (a rigid body's moments): the lever frame's orientation about its axis matters
    "asymmetric_lever": lambda: perturbed_model(4, spread=0.10, lever_inertia_kgm2=ASYMMETRIC),
}


# --------------------------------------------------------------------------- tests


@pytest.mark.parametrize("case", list(CASES))
def test_engine_matches_pinocchio_reference(case: str) -> None:
    model = CASES[case]()
    assert model.geometry.lever_spin == "u_joint"
    ours, ref, _ = both(model, seed=10 + list(CASES).index(case))
    scale = float(np.max(np.abs(ref["tau"])))
    assert scale > 0.0
    diffs = {
        part: rel_diff(getattr(ours, part), ref[part], scale)
        for part in ("tau", "platform", "lever", "slider", "screw", "friction", "hip_friction")
    }
    assert diffs["tau"] < RTOL, diffs
    for part, value in diffs.items():
        assert value < RTOL, f"{part}: {value:.3g} (all: {diffs})"
    # the parts add up in the reference too
    total = ref["platform"] + ref["lever"] + ref["slider"] + ref["screw"] + ref["friction"]
    assert rel_diff(total, ref["tau"], scale) < 1e-10


FRICTION_FAMILIES = {
    "slider": ("slider_coulomb", "slider_viscous"),
    "screw": ("screw_coulomb", "screw_viscous"),
    "spherical": ("spherical_coulomb", "spherical_viscous"),
    "universal": ("universal_coulomb", "universal_viscous"),
    "hip_and_thrust": ("mu_h", "mu_t"),
}


@pytest.mark.parametrize("family", list(FRICTION_FAMILIES))
def test_each_friction_term_is_exercised(family: str) -> None:
    """In the full-friction case every friction family moves the torque far beyond RTOL, and
    the two models still agree with that family switched off."""
    model = perturbed_model(0, spread=0.0, friction=True)
    f = model.friction
    assert all(getattr(f, key) > 0.0 for keys in FRICTION_FAMILIES.values() for key in keys)
    t, ang, rat, acc, load = smooth_motion(5, 25)
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, ang, rat, acc)
    full = reference_torques(model, t, R, w, wd, load)["tau"]
    scale = float(np.max(np.abs(full)))
    off = dataclasses.replace(model, friction=dataclasses.replace(f, **{k: 0.0 for k in FRICTION_FAMILIES[family]}))
    ref_off = reference_torques(off, t, R, w, wd, load)["tau"]
    ours_off = engine_torques(off, ang, rat, acc, load, t).tau
    assert rel_diff(full, ref_off, scale) > 1e-3
    assert rel_diff(ours_off, ref_off, scale) < RTOL
    assert rel_diff(engine_torques(model, ang, rat, acc, load, t).tau, full, scale) < RTOL


def test_lever_frame_orientation_is_discriminated() -> None:
    """Swapping the lever's I_xx and I_yy must move the reference torque well beyond RTOL."""
    model = perturbed_model(4, spread=0.10, lever_inertia_kgm2=ASYMMETRIC)
    swapped = perturbed_model(4, spread=0.10, lever_inertia_kgm2=[ASYMMETRIC[1], ASYMMETRIC[0], ASYMMETRIC[2]])
    t, ang, rat, acc, load = smooth_motion(6, 15)
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, ang, rat, acc)
    ours = engine_torques(model, ang, rat, acc, load, t).tau
    ref_swapped = reference_torques(swapped, t, R, w, wd, load)["tau"]
    assert rel_diff(ours, ref_swapped, float(np.max(np.abs(ours)))) > 1e3 * RTOL


def test_loop_closure_of_reconstructed_configuration() -> None:
    model = perturbed_model(7, spread=0.15)
    t, ang, rat, acc, load = smooth_motion(7, 25)
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, ang, rat, acc)
    ref = reference_torques(model, t, R, w, wd, load)
    assert np.max(ref["closure_residual"]) < 1e-10
    pm, info = build_tree(model)
    data = pm.createData()
    dh = model.geometry.h[0] - model.geometry.h[1]
    for k in range(t.shape[0]):
        q, v, a = ref["q"][k], ref["v"][k], ref["a"][k]
        assert np.max(np.abs(closure_residual(pm, data, info, q))) < 1e-10
        for j in range(2):  # both platforms at the prescribed orientation
            np.testing.assert_allclose(data.oMi[info.platform_joint[j]].rotation, R[k], atol=1e-12)
        for j, i in np.ndindex(2, 3):  # each slider below its S joint, on its screw
            b = data.oMi[int(info.u_joint[j, i, 0])].translation
            np.testing.assert_allclose(b[:2], model.geometry.A[i, :2], atol=1e-12)
            assert abs(b[2] - (q[info.module_q[i]] + (dh if j == 0 else 0.0))) < 1e-12
            assert data.oMf[int(info.tip_frame[j, i])].translation[2] > b[2]
        # velocity and acceleration closures: the platform points' world motion matches too
        pin.forwardKinematics(pm, data, q, v, a)
        pin.updateFramePlacements(pm, data)
        for j, i in np.ndindex(2, 3):
            vt = pin.getFrameVelocity(pm, data, int(info.tip_frame[j, i]), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED).linear
            r = R[k] @ model.geometry.r_a[i]
            np.testing.assert_allclose(vt, np.cross(w[k], r), atol=1e-12)
            at = pin.getFrameClassicalAcceleration(
                pm, data, int(info.tip_frame[j, i]), pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            ).linear
            np.testing.assert_allclose(at, np.cross(wd[k], r) + np.cross(w[k], np.cross(w[k], r)), atol=1e-10)


def test_reference_power_balance() -> None:
    """Without friction the motor power equals the rate of change of the machine's energy.

    ``sum_i tau_i theta_dot_i = d/dt (T + V)``, with ``T + V`` from Pinocchio (tree) plus the
    screw rotors, differentiated by central differences along the motion. This checks the
    reference's velocity and acceleration reconstruction independently of the engine.
    """
    model = perturbed_model(8, spread=0.15, friction=False)
    t = np.linspace(0.0, 1.2, 12)
    h = 1e-4
    seq = model.geometry.euler_sequence

    def reference_at(tt: np.ndarray) -> dict:
        tt, ang_, rat_, acc_, load_ = motion_on(8, tt)
        return reference_torques(model, tt, *euler_kinematics(seq, ang_, rat_, acc_), load_)

    ref0 = reference_at(t)
    energy = {k: reference_at(t + k * h)["energy"] for k in (-2, -1, 1, 2)}
    theta_dot = 2.0 * np.pi * ref0["Ld"] / model.geometry.p
    power = np.sum(ref0["no_friction"] * theta_dot, axis=1)
    # fourth-order central difference (truncation ~ h^4, about 1e-11 relative here)
    dEdt = (energy[-2] - 8.0 * energy[-1] + 8.0 * energy[1] - energy[2]) / (12.0 * h)
    assert np.max(np.abs(power)) > 1.0
    assert np.max(np.abs(power - dEdt)) < 1e-8 * np.max(np.abs(power))


def test_spanning_tree_rnea_inputs() -> None:
    model = model_from_dict(default_params_dict(), "built-in")
    pm, data, q, v, a = spanning_tree_rnea_inputs(model)
    assert (pm.nq, pm.nv) == (23, 21)
    assert q.shape == (23,) and v.shape == (21,) and a.shape == (21,)
    assert np.any(v != 0.0) and np.any(a != 0.0)
    tau = pin.rnea(pm, data, q, v, a)
    assert tau.shape == (21,) and np.all(np.isfinite(tau))
    _, info = build_tree(model)
    assert np.max(np.abs(closure_residual(pm, pm.createData(), info, q))) < 1e-10

"""Self-tests of the drive oracles (five-bar, biglide), each against an independent route:
central differences of positions for the rates and accelerations, loop closure, Lagrange's
equations from the kinetic and potential energies alone, the power balance of the motors,
and hand-worked special cases. Deliberately wrong inputs must fail the same checks."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from oracles import biglide, five_bar

MECHS = {"five_bar": five_bar, "biglide": biglide}


def assert_close(actual, expected, rtol, what=""):
    actual, expected = np.asarray(actual), np.asarray(expected)
    scale = max(np.max(np.abs(expected)), 1e-12)
    err = np.max(np.abs(actual - expected))
    assert err <= rtol * scale, f"{what}: max err {err:.3e} > {rtol:.1e} * {scale:.3e}"


def rel_err(actual, expected):
    return np.max(np.abs(np.asarray(actual) - expected)) / max(np.max(np.abs(expected)), 1e-300)


def drives(name, seed, signs=(1.0, 1.0)):
    r = np.random.default_rng(seed)
    out = dict(
        rotor_inertia=r.uniform(2e-5, 8e-5, 2), coulomb=r.uniform(0.02, 0.08, 2),
        viscous=r.uniform(1e-4, 5e-4, 2), joint_sign=np.asarray(signs, float),
    )
    if name == "five_bar":
        out["gear_ratio"] = r.uniform(8.0, 30.0, 2)
    else:
        out["gear_ratio"] = r.uniform(1.0, 3.0, 2)
        out["screw_lead"] = r.uniform(0.005, 0.02, 2)
    return out


def make(name, seed=1, signs=(1.0, 1.0)):
    mod = MECHS[name]
    par = (five_bar.default_five_bar if name == "five_bar" else biglide.default_biglide)(
        **drives(name, seed, signs))
    return mod, par, mod.DEFAULT_POSE


def motion_fn(pose, amp=(0.03, -0.025), omega=(2.1, 3.3), phase=(0.4, -0.7)):
    def f(t):
        return five_bar.sine_motion(np.atleast_1d(t), pose, amp, omega, phase)
    return f


def fd1(f, t, h):
    return (f(t + h) - f(t - h)) / (2 * h)


def fd1_4(f, t, h):
    """Fourth-order central difference."""
    return (-f(t + 2 * h) + 8 * f(t + h) - 8 * f(t - h) + f(t - 2 * h)) / (12 * h)


def _unwrap_diff(a, b):
    return np.angle(np.exp(1j * (a - b)))


TS = np.array([0.0, 0.31, 0.77, 1.4, 2.2])
NAMES = list(MECHS)


# ----------------------------------------------------------------------------------------
# kinematics
# ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_rates_and_accelerations_vs_central_differences(name):
    mod, par, pose = make(name)
    mo = motion_fn(pose)
    h = 1e-5

    def ik(t):
        return mod.inverse_kinematics(par, *mo(t))

    out = ik(TS)
    pos_keys = ("phi", "psi") if name == "five_bar" else ("s", "psi")
    for key in pos_keys:
        d1 = _unwrap_diff(ik(TS + h)[key], ik(TS - h)[key]) / (2 * h)
        assert_close(out[key + "d"], d1, 1e-8, what=f"{key} rate")
        assert_close(out[key + "dd"], fd1(lambda t: ik(t)[key + "d"], TS, h), 1e-8,
                     what=f"{key} acceleration")
    assert_close(out["qd"], fd1(lambda t: ik(t)["q"], TS, h), 1e-8, what="q rate")
    assert_close(out["qdd"], fd1(lambda t: ik(t)["qd"], TS, h), 1e-8, what="q acceleration")
    # rates are K Pd
    P, Pd, _ = mo(TS)
    rate = out["phid"] if name == "five_bar" else out["sd"]
    assert_close(np.einsum("nij,nj->ni", out["K"], Pd), rate, 1e-13, what="K Pd")

    # every body's centre of mass and angle
    def bm(t):
        return mod.body_motion(par, *mo(t))

    b = bm(TS)
    assert_close(b["v"], fd1(lambda t: bm(t)["c"], TS, h), 1e-8, what="com velocity")
    assert_close(b["a"], fd1(lambda t: bm(t)["v"], TS, h), 1e-8, what="com acceleration")
    w = _unwrap_diff(bm(TS + h)["angle"], bm(TS - h)["angle"]) / (2 * h)
    assert_close(b["w"], w, 1e-8, what="angular velocity")
    assert_close(b["alpha"], fd1(lambda t: bm(t)["w"], TS, h), 1e-8, what="angular acc")


def test_a_wrong_acceleration_formula_fails_the_difference_check():
    """The check above can fail: drop the centripetal term of the five-bar's accelerations."""
    mod, par, pose = make("five_bar")
    mo = motion_fn(pose)
    h = 1e-5
    P, Pd, Pdd = mo(TS)
    out = mod.inverse_kinematics(par, P, Pd, Pdd)
    # a plausible mistake: phidd = Pdd.e(psi) / (l1 sin(psi - phi)) (velocity terms left out)
    wrong = np.sum(Pdd[:, None, :] * five_bar._e(out["psi"]), -1) / (par.l1 * out["leg_sine"])
    ref = fd1(lambda t: mod.inverse_kinematics(par, *mo(t))["phid"], TS, h)
    assert rel_err(out["phidd"], ref) < 1e-8
    assert rel_err(wrong, ref) > 1e-2


def test_five_bar_loop_closure_and_branch():
    _, par, pose = make("five_bar")
    P = motion_fn(pose)(TS)[0]
    out = five_bar.inverse_kinematics(par, P)
    A = par.base[None]
    assert_close(np.linalg.norm(out["B"] - A, axis=-1), np.broadcast_to(par.l1, (len(TS), 2)),
                 1e-14, what="proximal length")
    for i in range(2):
        recon = out["B"][:, i] + par.l2[i] * five_bar._e(out["psi"][:, i])
        assert_close(recon, P, 1e-14, what=f"loop closure leg {i}")
        side = five_bar._cross(P - A[:, i], out["B"][:, i] - A[:, i])
        assert np.all(np.sign(side) == par.sigma[i])
    # away from both kinds of singularity along the motion
    assert np.min(np.abs(out["leg_sine"])) > 0.3 and np.min(np.abs(out["distal_sine"])) > 0.3


def test_biglide_loop_closure_and_branch():
    _, par, pose = make("biglide")
    P = motion_fn(pose)(TS)[0]
    out = biglide.inverse_kinematics(par, P)
    d = biglide._e(np.asarray(par.rail_angle))
    nd = biglide._n(np.asarray(par.rail_angle))
    for i in range(2):
        S = out["S"][:, i]
        # on the rail
        assert np.max(np.abs(np.sum((S - par.rail_origin[i]) * nd, -1))) < 1e-15  # on the rail
        assert_close(np.linalg.norm(P - S, axis=-1), np.full(len(TS), par.length[i]), 1e-14,
                     what="link length")
        recon = S + par.length[i] * biglide._e(out["psi"][:, i])
        assert_close(recon, P, 1e-14, what=f"loop closure leg {i}")
        beyond = np.sum((S - P) * d, -1)
        assert np.all(np.sign(beyond) == par.sigma[i])
    assert np.min(np.abs(out["leg_cosine"])) > 0.3 and np.min(np.abs(out["link_sine"])) > 0.3


# ----------------------------------------------------------------------------------------
# dynamics
# ----------------------------------------------------------------------------------------

def _lagrange_generalised_force(mod, par, mo, ts, h_t=1e-4, h_x=1e-6):
    """``d/dt dT/dPd - dT/dP + dV/dP`` from the energies alone (positions and rates only):
    central differences in P at fixed Pd, in Pd (T is quadratic in Pd), and in time."""

    def dT_dPd(P, Pd):
        cols = []
        for k in range(2):
            dv = np.zeros_like(Pd)
            dv[:, k] = 1.0
            Tp = mod.energies(par, P, Pd + dv)["T"]
            Tm = mod.energies(par, P, Pd - dv)["T"]
            cols.append((Tp - Tm) / 2.0)            # exact for a quadratic form
        return np.stack(cols, -1)

    def along(t):
        P, Pd, _ = mo(t)
        return dT_dPd(P, Pd)

    P, Pd, _ = mo(ts)
    ddt = fd1_4(along, ts, h_t)
    grad = []
    for k in range(2):
        dx = np.zeros_like(P)
        dx[:, k] = h_x
        ep, em = mod.energies(par, P + dx, Pd), mod.energies(par, P - dx, Pd)
        grad.append(((ep["V"] - ep["T"]) - (em["V"] - em["T"])) / (2 * h_x))
    return ddt + np.stack(grad, -1)


def _dq_dP(mod, par, P, h=1e-6):
    cols = []
    for k in range(2):
        dx = np.zeros_like(P)
        dx[:, k] = h
        cols.append((mod.inverse_kinematics(par, P + dx)["q"]
                     - mod.inverse_kinematics(par, P - dx)["q"]) / (2 * h))
    return np.stack(cols, -1)          # (n, joint, task)


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("signs", [(1.0, 1.0), (-1.0, 1.0)])
def test_efforts_satisfy_lagranges_equations(name, signs):
    mod, par, pose = make(name, seed=3, signs=signs)
    mo = motion_fn(pose, amp=(0.04, 0.03), omega=(4.0, 5.5))
    P, Pd, Pdd = mo(TS)
    u = mod.joint_efforts(par, P, Pd, Pdd)
    Q = _lagrange_generalised_force(mod, par, mo, TS)
    H = _dq_dP(mod, par, P)
    assert_close(np.einsum("nik,ni->nk", H, u), Q, 1e-7, what="Lagrange")


@pytest.mark.parametrize("name", NAMES)
def test_a_wrong_inertia_fails_lagranges_equations(name):
    mod, par, pose = make(name, seed=3)
    mo = motion_fn(pose, amp=(0.04, 0.03), omega=(4.0, 5.5))
    P, Pd, Pdd = mo(TS)
    Q = _lagrange_generalised_force(mod, par, mo, TS)
    H = _dq_dP(mod, par, P)
    key = "inertia_distal" if name == "five_bar" else "inertia_link"
    wrong = dataclasses.replace(par, **{key: getattr(par, key) * 1.2})
    u = mod.joint_efforts(wrong, P, Pd, Pdd)
    assert rel_err(np.einsum("nik,ni->nk", H, u), Q) > 1e-4


def _power_residual(mod, par_torque, par_energy, mo, ts, h=1e-4):
    """``sum tau theta_d - d/dt(T + V + T_rotor) - loss``, relative to the motor power scale."""
    P, Pd, Pdd = mo(ts)
    tq = mod.motor_torques(par_torque, P, Pd, Pdd)
    ref = mod.motor_torques(par_energy, P, Pd, Pdd)
    power = np.sum(tq["torque"] * ref["theta_d"], -1)

    def total(t):
        e = mod.energies(par_energy, *mo(t)[:2])
        return e["T"] + e["V"] + e["T_rotor"]

    loss = mod.energies(par_energy, P, Pd)["loss"]
    rhs = fd1_4(total, ts, h) + loss
    scale = np.max(np.abs(tq["torque"] * ref["theta_d"]))
    return np.max(np.abs(power - rhs)) / scale


@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("signs", [(1.0, 1.0), (1.0, -1.0)])
def test_power_balance_of_the_motors(name, signs):
    mod, par, pose = make(name, seed=5, signs=signs)
    mo = motion_fn(pose, amp=(0.04, -0.03), omega=(3.0, 4.4), phase=(1.0, 0.2))
    ts = np.linspace(0.0, 2.0, 9)
    assert _power_residual(mod, par, par, mo, ts) < 1e-8
    # each part is present: rotor and friction are not negligible here
    P, Pd, Pdd = mo(ts)
    tq = mod.motor_torques(par, P, Pd, Pdd)
    big = np.max(np.abs(tq["torque"]))
    assert np.max(np.abs(tq["rotor"])) > 1e-2 * big
    assert np.max(np.abs(tq["friction"])) > 1e-2 * big


@pytest.mark.parametrize("name", NAMES)
def test_wrong_drive_inputs_fail_the_power_balance(name):
    mod, par, pose = make(name, seed=5)
    mo = motion_fn(pose, amp=(0.04, -0.03), omega=(3.0, 4.4), phase=(1.0, 0.2))
    ts = np.linspace(0.0, 2.0, 9)
    assert _power_residual(mod, par, par, mo, ts) < 1e-8
    wrong_ratio = dataclasses.replace(par, gear_ratio=par.gear_ratio * np.array([1.02, 1.0]))
    assert _power_residual(mod, wrong_ratio, par, mo, ts) > 1e-4
    no_rotor = dataclasses.replace(par, rotor_inertia=np.zeros(2))
    assert _power_residual(mod, no_rotor, par, mo, ts) > 1e-4
    no_viscous = dataclasses.replace(par, viscous=np.zeros(2))
    assert _power_residual(mod, no_viscous, par, mo, ts) > 1e-5
    if name == "biglide":
        wrong_lead = dataclasses.replace(par, screw_lead=par.screw_lead * np.array([1.0, 1.02]))
        assert _power_residual(mod, wrong_lead, par, mo, ts) > 1e-4


def test_five_bar_with_massless_distal_links_is_two_pendulums():
    """Massless distal links carry no force (two non-parallel two-force members meeting at a
    free point), so each base joint carries its own proximal link as a compound pendulum:
    ``u = sign (I_A phidd - m cross(r, g))``, ``I_A = I_c + m |r|^2``."""
    par = five_bar.default_five_bar(joint_sign=[1.0, -1.0])
    par = dataclasses.replace(par, mass_distal=np.zeros(2), inertia_distal=np.zeros(2))
    mo = motion_fn(five_bar.DEFAULT_POSE)
    P, Pd, Pdd = mo(TS)
    u = five_bar.joint_efforts(par, P, Pd, Pdd)
    ik = five_bar.inverse_kinematics(par, P, Pd, Pdd)
    ca, cp = par.com_proximal[:, 0], par.com_proximal[:, 1]
    r = ca[None, :, None] * five_bar._e(ik["phi"]) + cp[None, :, None] * five_bar._n(ik["phi"])
    IA = par.inertia_proximal + par.mass_proximal * (ca**2 + cp**2)
    grav = five_bar._cross(r, np.broadcast_to(par.gravity, r.shape))
    expected = par.joint_sign[None] * (IA[None] * ik["phidd"] - par.mass_proximal[None] * grav)
    assert_close(u, expected, 1e-12, what="two pendulums")


def test_biglide_with_massless_links_carries_its_sliders():
    """Massless links carry no force: each screw drives its own slider,
    ``u = sign m (sdd - g.d)``; and the motor torque is ``u p / (2 pi N) + I_r theta_dd +
    friction``, the ball-screw relation."""
    par = biglide.default_biglide(**drives("biglide", 7, signs=(-1.0, 1.0)))
    par = dataclasses.replace(par, mass_link=np.zeros(2), inertia_link=np.zeros(2))
    mo = motion_fn(biglide.DEFAULT_POSE)
    P, Pd, Pdd = mo(TS)
    tq = biglide.motor_torques(par, P, Pd, Pdd)
    ik = biglide.inverse_kinematics(par, P, Pd, Pdd)
    d = biglide._e(np.asarray(par.rail_angle))
    expected = par.joint_sign[None] * par.mass_slider[None] * (ik["sdd"] - par.gravity @ d)
    assert_close(tq["effort"], expected, 1e-12, what="sliders")
    thd = 2 * np.pi * par.gear_ratio / par.screw_lead * ik["qd"]
    thdd = 2 * np.pi * par.gear_ratio / par.screw_lead * ik["qdd"]
    tau = (expected * par.screw_lead / (2 * np.pi * par.gear_ratio) + par.rotor_inertia * thdd
           + par.coulomb * thd / np.sqrt(thd**2 + 1e-6) + par.viscous * thd)
    assert_close(tq["torque"], tau, 1e-12, what="screw torque")


@pytest.mark.parametrize("name", NAMES)
def test_static_efforts_are_the_gradient_of_the_potential(name):
    """At rest, ``u = dV/dq``: with ``H = dq/dP``, ``H^T u = dV/dP``."""
    mod, par, pose = make(name, seed=9, signs=(-1.0, -1.0))
    P = motion_fn(pose)(TS)[0]
    zero = np.zeros_like(P)
    u = mod.joint_efforts(par, P, zero, zero)
    h = 1e-6
    grad = np.stack([(mod.energies(par, P + h * np.eye(2)[k], zero)["V"]
                      - mod.energies(par, P - h * np.eye(2)[k], zero)["V"]) / (2 * h)
                     for k in range(2)], -1)
    assert_close(np.einsum("nik,ni->nk", _dq_dP(mod, par, P), u), grad, 1e-8, what="statics")


@pytest.mark.parametrize("name", NAMES)
def test_effort_shares_are_the_efforts_of_each_body_alone(name):
    """A body's share is the effort with every other body massless (linearity), and the
    shares sum to the efforts."""
    mod, par, pose = make(name, seed=4, signs=(1.0, -1.0))
    P, Pd, Pdd = motion_fn(pose)(TS)
    shares = mod.effort_shares(par, P, Pd, Pdd)
    u = mod.joint_efforts(par, P, Pd, Pdd)
    assert_close(shares.sum(axis=1), u, 1e-13, what="sum of shares")
    if name == "five_bar":
        keys = ("mass_proximal", "inertia_proximal", "mass_distal", "inertia_distal")
    else:
        keys = ("mass_slider", None, "mass_link", "inertia_link")
    for b in range(4):
        leg, kind = b % 2, b // 2
        kept = {}
        for j, key in enumerate(keys):
            if key is None:
                continue
            keep = np.zeros(2)
            if j // 2 == kind:
                keep[leg] = 1.0
            kept[key] = getattr(par, key) * keep
        alone = mod.joint_efforts(dataclasses.replace(par, **kept), P, Pd, Pdd)
        assert_close(shares[:, b], alone, 1e-12, what=f"share of body {b}")

"""Self-tests of the closed-form oracles (each against an independent route)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

from oracles import bennett, delta, five_bar, mobility, rpr3, rrr3, stewart

RNG_SEED = 20261130


def rng():
    return np.random.default_rng(RNG_SEED)


def assert_close(actual, expected, rtol, atol_scale=1.0, what=""):
    actual = np.asarray(actual)
    expected = np.asarray(expected)
    scale = max(np.max(np.abs(expected)), 1e-12) * atol_scale
    err = np.max(np.abs(actual - expected))
    assert err <= rtol * scale, f"{what}: max err {err:.3e} > {rtol:.1e} * {scale:.3e}"


class Traj:
    """Smooth sinusoidal trajectory q(t) = q0 + amp sin(w t + ph), componentwise."""

    def __init__(self, q0, amp, w, ph):
        self.q0, self.amp, self.w, self.ph = map(np.asarray, (q0, amp, w, ph))

    def q(self, t):
        return self.q0 + self.amp * np.sin(self.w * t + self.ph)

    def qd(self, t):
        return self.amp * self.w * np.cos(self.w * t + self.ph)

    def qdd(self, t):
        return -self.amp * self.w**2 * np.sin(self.w * t + self.ph)


def fd1(f, t, h):
    return (f(t + h) - f(t - h)) / (2 * h)


def fd2(f, t, h):
    return (f(t + h) - 2 * f(t) + f(t - h)) / h**2


def _wrapd(x):
    return np.angle(np.exp(1j * x))


def fd1_angle(f, t, h):
    """Central difference of an angle that may be wrapped to (-pi, pi]."""
    return _wrapd(f(t + h) - f(t - h)) / (2 * h)


def fd2_angle(f, t, h):
    f0 = f(t)
    return (_wrapd(f(t + h) - f0) - _wrapd(f0 - f(t - h))) / h**2


# --------------------------------------------------------------------------
# Stewart
# --------------------------------------------------------------------------

def _stewart_samples(n=5):
    r = rng()
    a, b, home = stewart.default_geometry()
    p = home + r.uniform(-0.15, 0.15, (n, 3))
    ang = r.uniform(-0.3, 0.3, (n, 3))
    return a, b, p, ang


@pytest.mark.parametrize("seq", ["XYZ", "ZYX", "ZXZ", "xyz", "zyx"])
def test_euler_matrix_matches_scipy(seq):
    ang = rng().uniform(-1.2, 1.2, (6, 3))
    R = stewart.euler_kinematics(ang, seq)["R"]
    assert_close(R, Rotation.from_euler(seq, ang).as_matrix(), 1e-12, what=seq)


def test_euler_xyz_is_rx_ry_rz():
    ang = np.array([[0.3, -0.7, 1.1]])
    R = stewart.euler_kinematics(ang, "XYZ")["R"][0]
    ca, sa = np.cos(0.3), np.sin(0.3)
    cb, sb = np.cos(-0.7), np.sin(-0.7)
    cc, sc = np.cos(1.1), np.sin(1.1)
    Rx = np.array([[1, 0, 0], [0, ca, -sa], [0, sa, ca]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rz = np.array([[cc, -sc, 0], [sc, cc, 0], [0, 0, 1]])
    assert_close(R, Rx @ Ry @ Rz, 1e-14)
    # and ZYX is Rz(a) Ry(b) Rx(c)
    R2 = stewart.euler_kinematics(np.array([[1.1, -0.7, 0.3]]), "ZYX")["R"][0]
    assert_close(R2, Rz @ Ry @ Rx, 1e-14)


@pytest.mark.parametrize("seq", ["XYZ", "ZYX", "xyz"])
def test_euler_rates_vs_fd(seq):
    tr = Traj([0.2, -0.4, 0.6], [0.5, 0.3, 0.4], [1.3, 0.7, 2.1], [0.1, 0.5, -0.3])
    ts = np.array([0.0, 0.4, 1.1])
    h = 1e-5
    Rf = lambda t: stewart.euler_kinematics(tr.q(t[:, None]), seq)["R"]
    out = stewart.euler_kinematics(tr.q(ts[:, None]), seq, tr.qd(ts[:, None]), tr.qdd(ts[:, None]))
    Rd = fd1(Rf, ts, h)
    W = Rd @ np.swapaxes(out["R"], 1, 2)  # skew(omega), space frame
    w_fd = np.stack([W[:, 2, 1], W[:, 0, 2], W[:, 1, 0]], -1)
    assert_close(out["omega"], w_fd, 1e-7, what="omega")
    wf = lambda t: stewart.euler_kinematics(tr.q(t[:, None]), seq, tr.qd(t[:, None]))["omega"]
    assert_close(out["omega_dot"], fd1(wf, ts, h), 1e-7, what="omega_dot")


def test_stewart_ik_reconstructs_platform_points():
    a, b, p, ang = _stewart_samples()
    out = stewart.inverse_kinematics(a, b, p, ang, "XYZ")
    recon = a[None] + out["L"][..., None] * out["u"]
    R = Rotation.from_euler("XYZ", ang).as_matrix()
    direct = p[:, None, :] + np.einsum("nij,kj->nki", R, b)
    assert_close(recon, direct, 1e-13)
    assert_close(np.linalg.norm(out["u"], axis=-1), np.ones((len(p), 6)), 1e-14)
    assert np.all(out["L"] > 0.5) and np.all(out["L"] < 2.0)


@pytest.mark.parametrize("seq", ["XYZ", "ZYX"])
def test_stewart_rates_and_accels_vs_fd(seq):
    a, b, home = stewart.default_geometry()
    trp = Traj(home, [0.1, -0.08, 0.12], [1.1, 1.7, 0.9], [0.3, -0.2, 0.8])
    tra = Traj([0.05, -0.1, 0.2], [0.2, 0.15, 0.25], [1.4, 0.6, 1.9], [0.0, 0.7, -0.4])
    ts = np.array([0.0, 0.37, 1.3])
    h = 1e-4

    def run(t):
        T = t[:, None]
        return stewart.inverse_kinematics(a, b, trp.q(T), tra.q(T), seq, trp.qd(T), tra.qd(T),
                                          trp.qdd(T), tra.qdd(T))

    out = run(ts)
    Lf = lambda t: run(t)["L"]
    assert_close(out["Ld"], fd1(Lf, ts, h), 1e-7, what="Ld")
    assert_close(out["Ldd"], fd2(Lf, ts, h), 1e-5, what="Ldd (2nd difference)")
    assert_close(out["Ldd"], fd1(lambda t: run(t)["Ld"], ts, h), 1e-7, what="Ldd")
    # Jacobian maps the twist (v, omega) to leg rates
    tw = np.concatenate([trp.qd(ts[:, None]), out["omega"]], -1)
    assert_close(np.einsum("nij,nj->ni", out["J"], tw), out["Ld"], 1e-13, what="J twist")
    # leg direction rates and leg angular velocity / acceleration
    uf = lambda t: run(t)["u"]
    ud_fd = fd1(uf, ts, h)
    assert_close(out["ud"], ud_fd, 1e-7, what="ud")
    assert_close(out["udd"], fd2(uf, ts, h), 1e-5, what="udd")
    assert_close(out["leg_omega"], np.cross(out["u"], ud_fd), 1e-7, what="leg omega")
    assert_close(np.einsum("nki,nki->nk", out["leg_omega"], out["u"]), np.zeros((3, 6)),
                 1e-12, atol_scale=1e12 * np.max(np.abs(out["leg_omega"])) + 1)
    assert_close(out["leg_omega_dot"], fd1(lambda t: run(t)["leg_omega"], ts, h), 1e-7,
                 what="leg omega dot")
    # the leg angular velocity carries u_i with the rate ud_i: ud = w_leg x u
    assert_close(np.cross(out["leg_omega"], out["u"]), out["ud"], 1e-12, what="w x u")


def test_ups_leg_angular_velocity_from_explicit_u_joint_angles():
    """Second route: parametrise the leg direction by the two U-joint angles."""
    a, b, home = stewart.default_geometry()
    trp = Traj(home, [0.1, -0.08, 0.12], [1.1, 1.7, 0.9], [0.3, -0.2, 0.8])
    tra = Traj([0.05, -0.1, 0.2], [0.2, 0.15, 0.25], [1.4, 0.6, 1.9], [0.0, 0.7, -0.4])
    ts = np.array([0.0, 0.37, 1.3])
    h = 1e-4
    # first U axis of each leg: horizontal, tangent to the base circle
    n1 = np.cross([0.0, 0.0, 1.0], a / np.linalg.norm(a, axis=1, keepdims=True))
    run = lambda t: stewart.inverse_kinematics(
        a, b, trp.q(t[:, None]), tra.q(t[:, None]), "XYZ", trp.qd(t[:, None]),
        tra.qd(t[:, None]), trp.qdd(t[:, None]), tra.qdd(t[:, None]))

    def cyl_rot(t):
        """Cylinder rotation Q = Rot(n1, q1) Rot(m, q2) E, from u alone.

        Reference leg frame E: columns (n1, m, k) with k the vertical, m = k x n1.
        u = Rot(n1, q1) Rot(m, q2) k fixes q1, q2 (second axis Rot(n1,q1) m is
        body-fixed and normal to n1 and u).
        """
        u = run(t)["u"]
        k = np.array([0.0, 0.0, 1.0])
        out = np.empty(u.shape + (3,))
        for i in range(6):
            m = np.cross(k, n1[i])
            # u components in (n1, m, k): u = (sin q2, -sin q1 cos q2, cos q1 cos q2)
            un, um, uk = u[:, i] @ n1[i], u[:, i] @ m, u[:, i] @ k
            q2 = np.arcsin(un)
            q1 = np.arctan2(-um, uk)
            E = np.stack([n1[i], m, k], -1)
            R1 = Rotation.from_rotvec(q1[:, None] * n1[i]).as_matrix()
            R2 = Rotation.from_rotvec(q2[:, None] * m).as_matrix()
            out[:, i] = R1 @ R2 @ E
        return out

    out = run(ts)
    w, wd, spin = stewart.ups_leg_angular_velocity(out["u"], out["ud"], out["udd"], n1[None])
    Q = cyl_rot(ts)
    # the cylinder's z axis is the leg direction
    assert_close(Q[..., :, 2], out["u"], 1e-12, what="U-joint parametrisation")
    W = fd1(cyl_rot, ts, h) @ np.swapaxes(Q, -1, -2)
    w_fd = np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], -1)
    assert_close(w, w_fd, 1e-7, what="U-joint leg omega")
    assert np.max(np.abs(spin)) > 1e-3  # a real spin component exists here
    wf = lambda t: stewart.ups_leg_angular_velocity(run(t)["u"], run(t)["ud"], run(t)["udd"], n1[None])[0]
    assert_close(wd, fd1(wf, ts, h), 1e-7, what="U-joint leg omega dot")


def test_stewart_ldd_centripetal_term_is_detected():
    """A formula missing the (|ld|^2 - Ld^2)/L term must fail the FD check."""
    a, b, home = stewart.default_geometry()
    trp = Traj(home, [0.1, -0.08, 0.12], [1.1, 1.7, 0.9], [0.3, -0.2, 0.8])
    tra = Traj([0.05, -0.1, 0.2], [0.2, 0.15, 0.25], [1.4, 0.6, 1.9], [0.0, 0.7, -0.4])
    ts = np.array([0.0, 0.37, 1.3])
    h = 1e-4
    run = lambda t: stewart.inverse_kinematics(
        a, b, trp.q(t[:, None]), tra.q(t[:, None]), "XYZ", trp.qd(t[:, None]),
        tra.qd(t[:, None]), trp.qdd(t[:, None]), tra.qdd(t[:, None]))
    out = run(ts)
    r = out["r"]
    W = out["omega"][:, None, :].repeat(6, 1)
    ldd = trp.qdd(ts[:, None])[:, None, :] + np.cross(out["omega_dot"][:, None, :].repeat(6, 1), r) \
        + np.cross(W, np.cross(W, r))
    wrong = np.einsum("nki,nki->nk", out["u"], ldd)
    with pytest.raises(AssertionError):
        assert_close(wrong, fd2(lambda t: run(t)["L"], ts, h), 1e-5)


def test_stewart_jacobian_vs_small_displacements():
    a, b, p, ang = _stewart_samples(3)
    R = Rotation.from_euler("XYZ", ang).as_matrix()
    J, u = stewart.inverse_jacobian(a, b, p, R)
    eps = 1e-6

    def lengths(pp, RR):
        return np.linalg.norm(pp[:, None, :] + np.einsum("nij,kj->nki", RR, b) - a[None], axis=-1)

    Jfd = np.zeros_like(J)
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = eps
        Jfd[:, :, k] = (lengths(p + dp, R) - lengths(p - dp, R)) / (2 * eps)
        rv = np.zeros(3)
        rv[k] = eps
        Rp = Rotation.from_rotvec(rv).as_matrix()
        Jfd[:, :, 3 + k] = (lengths(p, Rp @ R) - lengths(p, Rp.T @ R)) / (2 * eps)
    assert_close(J, Jfd, 1e-8)


def test_semi_regular_hexagon_geometry():
    gb, gp = np.radians(12.0), np.radians(8.0)
    a, b = stewart.semi_regular_hexagon(1.2, 0.6, gb, gp)
    assert_close(np.linalg.norm(a, axis=1), np.full(6, 1.2), 1e-14)
    assert_close(np.linalg.norm(b, axis=1), np.full(6, 0.6), 1e-14)
    assert np.all(a[:, 2] == 0) and np.all(b[:, 2] == 0)
    ang_a = np.degrees(np.arctan2(a[:, 1], a[:, 0])) % 360
    ang_b = np.degrees(np.arctan2(b[:, 1], b[:, 0])) % 360
    assert_close(np.sort(ang_a), np.sort([348, 12, 108, 132, 228, 252]), 1e-12)
    assert_close(np.sort(ang_b), np.sort([308, 52, 68, 172, 188, 292]), 1e-12)
    # 3-fold symmetry: equal legs at a centred, level pose
    L = stewart.inverse_kinematics(a, b, [[0, 0, 1.0]], [[0, 0, 0]])["L"][0]
    assert_close(L, np.full(6, L[0]), 1e-13)
    # each leg goes to the adjacent platform pair (angular gap 60 - gb - gp)
    gap = np.degrees(np.abs(np.angle(np.exp(1j * (np.radians(ang_b) - np.radians(ang_a))))))
    assert_close(gap, np.full(6, 60 - 12 - 8), 1e-11)


# --------------------------------------------------------------------------
# Delta
# --------------------------------------------------------------------------

GEOM = delta.williams_irb360_geometry()


def _delta_points(n=6):
    r = rng()
    return np.column_stack([r.uniform(-0.3, 0.3, n), r.uniform(-0.3, 0.3, n), r.uniform(-1.25, -0.85, n)])


def test_delta_fk_of_ik_is_identity():
    p = _delta_points()
    g = GEOM
    th = delta.inverse_kinematics(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    assert np.all(np.isfinite(th))
    assert_close(delta.forward_kinematics(th, g["R_b"], g["R_p"], g["L_A"], g["L_B"]), p, 1e-12)


def test_delta_ik_two_closed_forms_and_constraint():
    p = _delta_points()
    g = GEOM
    th = delta.inverse_kinematics(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    th2 = delta.inverse_kinematics_atan2(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    assert_close(th, th2, 1e-12)
    C = delta.elbow_points(th, g["R_b"], g["L_A"])
    P = p[:, None, :] + g["R_p"] * delta.leg_directions()[None]
    assert_close(np.linalg.norm(P - C, axis=-1), np.full((len(p), 3), g["L_B"]), 1e-13)
    # upper-arm length and elbow-out branch (B_ii > 0)
    A = g["R_b"] * delta.leg_directions()[None]
    assert_close(np.linalg.norm(C - A, axis=-1), np.full((len(p), 3), g["L_A"]), 1e-13)
    _, B, _ = delta.jacobian(p, th, g["R_b"], g["R_p"], g["L_A"])
    assert np.all(np.diagonal(B, axis1=1, axis2=2) > 0)


def test_delta_ik_branch_over_wide_box():
    """Both algebraic forms of the tangent-half-angle root are exercised."""
    g = GEOM
    args = (g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    r = rng()
    p = np.column_stack([r.uniform(-1.5, 1.5, 4000), r.uniform(-1.5, 1.5, 4000), r.uniform(-1.8, 1.2, 4000)])
    th = delta.inverse_kinematics(p, *args)
    ok = np.all(np.isfinite(th), axis=1)
    p, th = p[ok], th[ok]
    assert len(p) > 500
    assert_close(_wrapd(th - delta.inverse_kinematics_atan2(p, *args)), np.zeros_like(th), 1e-10, atol_scale=1e10)
    C = delta.elbow_points(th, g["R_b"], g["L_A"])
    P = p[:, None, :] + g["R_p"] * delta.leg_directions()[None]
    assert_close(np.linalg.norm(P - C, axis=-1), np.full(th.shape, g["L_B"]), 1e-12)
    _, B, _ = delta.jacobian(p, th, g["R_b"], g["R_p"], g["L_A"])
    assert np.all(np.diagonal(B, axis1=1, axis2=2) > 0)


def test_delta_ik_on_axis_vs_planar_root_finding():
    """On the vertical axis each leg is a planar circle problem: solve by bracketing."""
    g = GEOM
    for z in (-0.9, -1.1, -1.3):
        th = delta.inverse_kinematics([[0.0, 0.0, z]], g["R_b"], g["R_p"], g["L_A"], g["L_B"])[0]

        def f(t):  # elbow (R_b + L_A cos t, -L_A sin t) to platform joint (R_p, z)
            return np.hypot(g["R_b"] + g["L_A"] * np.cos(t) - g["R_p"], -g["L_A"] * np.sin(t) - z) - g["L_B"]

        # elbow-out root: arm below horizontal, elbow outside the joint
        root = brentq(f, -np.pi / 2, np.pi / 2)
        assert_close(th, np.full(3, root), 1e-10, what=f"z={z}")


def test_delta_rates_vs_fd_and_jacobian():
    g = GEOM
    args = (g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    tr = Traj([0.05, -0.03, -1.05], [0.15, 0.12, 0.1], [1.3, 2.1, 0.8], [0.2, -0.5, 0.9])
    ts = np.array([0.0, 0.6, 1.7])
    h = 1e-4
    run = lambda t: delta.kinematics(tr.q(t[:, None]), *args, pd=tr.qd(t[:, None]), pdd=tr.qdd(t[:, None]))
    out = run(ts)
    thf = lambda t: run(t)["theta"]
    assert_close(out["thetad"], fd1(thf, ts, h), 1e-7, what="thetad")
    assert_close(out["thetadd"], fd1(lambda t: run(t)["thetad"], ts, h), 1e-7, what="thetadd")
    assert_close(out["thetadd"], fd2(thf, ts, h), 1e-5, what="thetadd 2nd diff")
    pd = tr.qd(ts[:, None])
    assert_close(np.einsum("nij,nj->ni", out["A"], pd),
                 np.einsum("nij,nj->ni", out["B"], out["thetad"]), 1e-12, what="A pd = B thd")
    # inverse Jacobian by finite differences of the IK
    p0 = tr.q(ts[:, None])
    eps = 1e-6
    Jfd = np.zeros((3, 3, 3))
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = eps
        Jfd[:, :, k] = (delta.inverse_kinematics(p0 + dp, *args) - delta.inverse_kinematics(p0 - dp, *args)) / (2 * eps)
    assert_close(out["J"], Jfd, 1e-7, what="J")


def test_delta_fk_discriminates_wrong_angles():
    g = GEOM
    p = _delta_points(3)
    th = delta.inverse_kinematics(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    p2 = delta.forward_kinematics(th + np.array([1e-3, 0, 0]), g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    with pytest.raises(AssertionError):
        assert_close(p2, p, 1e-8)


# --------------------------------------------------------------------------
# 3-RRR
# --------------------------------------------------------------------------

G3 = rrr3.symmetric_geometry()


def _rrr_poses(n=5):
    r = rng()
    return np.column_stack([r.uniform(-0.05, 0.05, n), r.uniform(-0.05, 0.05, n), r.uniform(-0.3, 0.3, n)])


@pytest.mark.parametrize("sigma", [(1, 1, 1), (-1, -1, -1), (1, -1, 1), (-1, 1, 1)])
def test_rrr_loop_closure(sigma):
    g = G3
    pose = _rrr_poses()
    out = rrr3.inverse_kinematics(pose, g["A"], g["c"], g["l1"], g["l2"], sigma)
    assert np.all(np.isfinite(out["theta"]))
    th, psi = out["theta"], out["psi"]
    # rebuild each leg as a serial chain from its base pivot
    B = g["A"][None] + g["l1"] * np.stack([np.cos(th), np.sin(th)], -1)
    C = B + g["l2"] * np.stack([np.cos(th + out["beta"]), np.sin(th + out["beta"])], -1)
    ph = pose[:, 2]
    Rm = np.stack([np.stack([np.cos(ph), -np.sin(ph)], -1), np.stack([np.sin(ph), np.cos(ph)], -1)], -2)
    Cdirect = pose[:, None, :2] + np.einsum("nij,kj->nki", Rm, g["c"])
    assert_close(C, Cdirect, 1e-13, what="loop closure")
    # platform orientation from the chain: theta + beta + gamma = phi (mod 2 pi)
    tot = np.angle(np.exp(1j * (th + out["beta"] + out["gamma"] - ph[:, None])))
    assert_close(tot, np.zeros_like(tot), 1e-12, atol_scale=1e12)
    assert_close(np.angle(np.exp(1j * (psi - th - out["beta"]))), np.zeros_like(th), 1e-12, atol_scale=1e12)
    # branch side
    side = np.sign((Cdirect[..., 0] - g["A"][None, :, 0]) * (B[..., 1] - g["A"][None, :, 1])
                   - (Cdirect[..., 1] - g["A"][None, :, 1]) * (B[..., 0] - g["A"][None, :, 0]))
    assert np.all(side == np.asarray(sigma)[None])


@pytest.mark.parametrize("sigma", [(1, 1, 1), (-1, 1, -1)])
def test_rrr_rates_vs_fd(sigma):
    g = G3
    tr = Traj([0.01, -0.02, 0.1], [0.04, 0.03, 0.2], [1.2, 0.8, 1.7], [0.4, -0.1, 0.3])
    ts = np.array([0.0, 0.5, 1.4])
    h = 1e-4
    run = lambda t: rrr3.inverse_kinematics(tr.q(t[:, None]), g["A"], g["c"], g["l1"], g["l2"], sigma,
                                             tr.qd(t[:, None]), tr.qdd(t[:, None]))
    out = run(ts)
    for key, dkey in (("theta", "thetad"), ("psi", "psid")):
        assert_close(out[dkey], fd1_angle(lambda t, key=key: run(t)[key], ts, h), 1e-7, what=dkey)
    assert_close(out["thetadd"], fd1(lambda t: run(t)["thetad"], ts, h), 1e-7, what="thetadd")
    assert_close(out["thetadd"], fd2_angle(lambda t: run(t)["theta"], ts, h), 1e-5, what="thetadd 2nd")
    assert_close(out["psidd"], fd1(lambda t: run(t)["psid"], ts, h), 1e-7, what="psidd")
    pd = tr.qd(ts[:, None])
    assert_close(np.einsum("nij,nj->ni", out["J"], pd), out["thetad"], 1e-12, what="J")
    # Jacobian columns by finite differences of the IK
    p0 = tr.q(ts[:, None])
    eps = 1e-6
    for k in range(3):
        dp = np.zeros(3)
        dp[k] = eps
        th_p = rrr3.inverse_kinematics(p0 + dp, g["A"], g["c"], g["l1"], g["l2"], sigma)["theta"]
        th_m = rrr3.inverse_kinematics(p0 - dp, g["A"], g["c"], g["l1"], g["l2"], sigma)["theta"]
        assert_close(out["J"][:, :, k], (th_p - th_m) / (2 * eps), 1e-6, what=f"J col {k}")


# --------------------------------------------------------------------------
# Bennett
# --------------------------------------------------------------------------

TWISTS = [(np.radians(40), np.radians(70)), (np.radians(75), np.radians(30)),
          (np.radians(120), np.radians(50)), (np.radians(35), np.radians(150))]


@pytest.mark.parametrize("alpha,beta", TWISTS)
def test_bennett_loop_closes(alpha, beta):
    a = 0.8
    b = bennett.bennett_b(a, alpha, beta)
    th1 = np.linspace(-3.0, 3.0, 13)
    io = bennett.input_output(th1, alpha, beta)
    th = np.column_stack([th1, io["theta2"], io["theta3"], io["theta4"]])
    T = bennett.loop_transform(th, a, alpha, b, beta)
    err = np.max(np.abs(T - np.eye(4)[None]))
    assert err < 1e-10, err
    # joint frames: consecutive joint axes are separated by a, b, a, b
    F = bennett.joint_frames(th, a, alpha, b, beta)
    for k, length in enumerate([a, b, a]):
        d = F[:, k + 1, :3, 3] - F[:, k, :3, 3]
        assert_close(np.linalg.norm(d, axis=-1), np.full(len(th1), length), 1e-12)


def test_bennett_loop_detects_errors():
    alpha, beta = TWISTS[0]
    a = 0.8
    b = bennett.bennett_b(a, alpha, beta)
    th1 = np.array([0.4, 1.2])
    io = bennett.input_output(th1, alpha, beta)
    bad = np.column_stack([th1, io["theta2"] + 1e-4, io["theta3"], io["theta4"]])
    assert np.max(np.abs(bennett.loop_transform(bad, a, alpha, b, beta) - np.eye(4))) > 1e-6
    # violating the Bennett condition breaks closure too
    good = np.column_stack([th1, io["theta2"], io["theta3"], io["theta4"]])
    assert np.max(np.abs(bennett.loop_transform(good, a, alpha, 1.01 * b, beta) - np.eye(4))) > 1e-4


@pytest.mark.parametrize("alpha,beta", TWISTS[:3])
def test_bennett_derivatives_vs_fd(alpha, beta):
    tr = Traj([0.3], [1.0], [1.3], [0.2])
    ts = np.array([0.0, 0.7, 1.9])
    h = 1e-4
    out = bennett.input_output(tr.q(ts[:, None])[:, 0], alpha, beta, tr.qd(ts[:, None])[:, 0],
                               tr.qdd(ts[:, None])[:, 0])

    def th2_at(t):  # evaluate each sample separately so unwrapping is per-sample
        return np.array([np.unwrap(bennett.input_output(tr.q(np.array([[ti - h], [ti], [ti + h]]))[:, 0],
                                                        alpha, beta)["theta2"]) for ti in t])

    def fd_first(t):
        v = th2_at(t)
        return (v[:, 2] - v[:, 0]) / (2 * h)

    def fd_second(t):
        v = th2_at(t)
        return (v[:, 2] - 2 * v[:, 1] + v[:, 0]) / h**2

    assert_close(out["theta2_d"], fd_first(ts), 1e-7, what="theta2_d")
    assert_close(out["theta2_dd"], fd_second(ts), 1e-5, what="theta2_dd")
    # g1, g2 against derivative of theta2(theta1)
    x = np.array([-2.0, -0.5, 0.4, 1.5])
    f = lambda x: np.unwrap(bennett.input_output(x, alpha, beta)["theta2"])
    vals = np.array([f(np.array([xi - h, xi, xi + h])) for xi in x])
    assert_close(bennett.input_output(x, alpha, beta)["g1"], (vals[:, 2] - vals[:, 0]) / (2 * h), 1e-7)
    assert_close(bennett.input_output(x, alpha, beta)["g2"], (vals[:, 2] - 2 * vals[:, 1] + vals[:, 0]) / h**2,
                 1e-5)


# --------------------------------------------------------------------------
# Mobility
# --------------------------------------------------------------------------

@pytest.mark.parametrize("name", sorted(mobility.CLASSIC))
def test_mobility_table_consistent(name):
    m = mobility.CLASSIC[name]
    k = mobility.kutzbach(m["n_bodies"], m["joints"], "spatial")
    assert k == m["kutzbach_spatial"]
    if m["grubler_planar"] is not None:
        assert mobility.kutzbach(m["n_bodies"], m["joints"], "planar") == m["grubler_planar"]
        assert m["grubler_planar"] == m["mobility"]
    assert m["mobility"] == k - m["idle"] + m["overconstraints"]


def test_kutzbach_basic_counts():
    assert mobility.kutzbach(7, "RRRRRR") == 6            # serial 6R arm (tree)
    assert mobility.kutzbach(4, "RRRR", "planar") == 1    # planar four-bar
    assert mobility.kutzbach(4, "RRRR") == -2             # same, spatial count
    assert mobility.kutzbach(4, "RRRP", "planar") == 1    # slider-crank
    assert mobility.kutzbach(7, "RRRRRRR") == 1           # general 7R loop
    assert mobility.kutzbach(2, [3]) == 3                 # single ball joint
    assert mobility.kutzbach(4, "RSSR") == 2             # RSSR: 1 + idle coupler spin
    assert mobility.kutzbach(4, "RCCC") == 1             # RCCC spatial four-bar
    assert mobility.kutzbach(4, ["R", "U", "S", "P"]) == 1  # 1+2+3+1 = 7 - 6
    assert mobility.kutzbach(2, "H") == 1 and mobility.kutzbach(2, "E") == 3
    assert mobility.loops(14, 18) == 5                    # Stewart: 5 independent loops
    assert mobility.loops(8, 9) == 2


# --------------------------------------------------------------------------
# Five-bar direct kinematics
# --------------------------------------------------------------------------

def _cross2(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


@pytest.mark.parametrize("sigma", [(1, -1), (1, 1), (-1, -1), (-1, 1)])
def test_five_bar_fk_of_ik_both_solutions(sigma):
    par = dataclasses.replace(five_bar.default_five_bar(), sigma=np.asarray(sigma, float),
                              joint_sign=np.array([-1.0, 1.0]))
    P = five_bar.DEFAULT_POSE + rng().uniform(-0.05, 0.05, (8, 2))
    ik = five_bar.inverse_kinematics(par, P)
    assert np.all(np.isfinite(ik["phi"]))
    phi = par.joint_sign * ik["q"]          # the joint coordinates back to absolute angles
    fk = five_bar.forward_kinematics(par, phi)
    assert fk["P"].shape == (8, 2, 2) and fk["B"].shape == (8, 2, 2)
    assert_close(fk["B"], ik["B"], 1e-13, what="elbows")
    # P is the solution on its own side of B_0 -> B_1: 0 left, 1 right
    B0, B1 = ik["B"][:, 0], ik["B"][:, 1]
    side = _cross2(B1 - B0, P - B0)
    assert np.all(np.abs(side) > 1e-4)     # regular: the two solutions are distinct
    k = np.where(side > 0, 0, 1)
    idx = np.arange(len(P))
    assert_close(fk["P"][idx, k], P, 1e-12, what="fk(ik(P))")
    # the other solution closes both distal links too, and lies on the other side
    other = fk["P"][idx, 1 - k]
    assert np.all(np.linalg.norm(other - P, axis=-1) > 1e-3)
    for i in range(2):
        assert_close(np.linalg.norm(other - ik["B"][:, i], axis=-1), np.full(len(P), par.l2[i]), 1e-12,
                     what=f"other solution, distal {i}")
    assert np.all(_cross2(B1 - B0, fk["P"][:, 0] - B0) > 0) and np.all(_cross2(B1 - B0, fk["P"][:, 1] - B0) < 0)


def test_five_bar_fk_unreachable_is_nan_and_wrong_formula_fails():
    par = five_bar.default_five_bar()
    # elbows pointing away from each other: |B_1 - B_0| = 0.67 m > l2_0 + l2_1 = 0.54 m
    out = five_bar.forward_kinematics(par, [[np.pi, 0.0], [0.3, 2.0]])
    assert np.all(np.isnan(out["P"][0])) and np.all(np.isfinite(out["P"][1]))
    # one sample of shape (2,) is promoted to (1, 2)
    assert five_bar.forward_kinematics(par, [1.2, 1.9])["P"].shape == (1, 2, 2)
    # swapped distal lengths must not reproduce the pose
    P = five_bar.DEFAULT_POSE + rng().uniform(-0.03, 0.03, (4, 2))
    phi = five_bar.inverse_kinematics(par, P)["phi"]
    bad = dataclasses.replace(par, l2=par.l2[::-1].copy())
    fk = five_bar.forward_kinematics(bad, phi)["P"]
    err = np.min(np.linalg.norm(fk - P[:, None, :], axis=-1), axis=1)
    assert np.all(err > 1e-4)


# --------------------------------------------------------------------------
# 3-RPR
# --------------------------------------------------------------------------

# a constructed geometry with six real assembly modes (found by a search with this oracle and
# confirmed by the independent coupler-curve scan below)
RPR_SIX = rpr3.RPR3(A=[[0.0, 0.0], [0.7, 0.05], [0.2, 0.55]], b=[[-0.25, -0.12], [0.2, -0.1], [0.05, 0.25]])
RPR_SIX_RHO = np.array([0.55, 0.288, 0.611])
# four real modes of the default geometry
RPR_DEFAULT_FOUR_RHO = np.array([0.758, 0.214, 0.775])


def _triangle(d01, d12, d20):
    """Platform points b_0 = 0, b_1 on +x, b_2 above, from the side lengths."""
    x = (d01**2 + d20**2 - d12**2) / (2 * d01)
    return np.array([[0.0, 0.0], [d01, 0.0], [x, np.sqrt(d20**2 - x**2)]])


# Recalled from the 3-RPR of Innocenti & Parenti-Castelli (1992), as used by Zein, Wenger &
# Chablat, Mech. Mach. Theory 43(4) (2008) 480-490: A_1 = (0, 0), A_2 = (15.91, 0),
# A_3 = (0, 10), platform sides d_1 = B_1B_2 = 17.04, d_2 = B_2B_3 = 16.54,
# d_3 = B_3B_1 = 20.84, and rho = (14.98, 15.38, 12.0) with six assembly modes.
# Quoted from memory, NOT confirmed against the papers here; the six modes are confirmed by
# the coupler-curve scan.
RPR_RECALLED = rpr3.RPR3(A=[[0.0, 0.0], [15.91, 0.0], [0.0, 10.0]], b=_triangle(17.04, 16.54, 20.84))
RPR_RECALLED_RHO = np.array([14.98, 15.38, 12.0])

# the points A_i - b_i are collinear (on y = 0) at phi = 0: the linear system M p = r of the
# elimination is singular at that root (the fallback path)
RPR_COLLINEAR = rpr3.RPR3(A=[[0.0, 0.0], [0.8, 0.05], [0.3, 0.7]], b=[[0.0, 0.0], [0.3, 0.05], [0.1, 0.7]])


def _rpr_cases():
    par = rpr3.default_rpr3()
    home_rho = rpr3.inverse_kinematics(par, rpr3.DEFAULT_POSE)["rho"][0]
    return {
        "default_home": (par, home_rho, 2),
        "default_four": (par, RPR_DEFAULT_FOUR_RHO, 4),
        "six": (RPR_SIX, RPR_SIX_RHO, 6),
        "recalled": (RPR_RECALLED, RPR_RECALLED_RHO, 6),
    }


def _wrap(a):
    return np.angle(np.exp(1j * np.asarray(a)))


def _pose_distance(a, b, size):
    """Largest of the position difference (relative to size) and the wrapped angle difference."""
    return max(np.max(np.abs(a[:2] - b[:2])) / size, abs(_wrap(a[2] - b[2])))


def _coupler_scan(par, rho, n=40000):
    """Every assembly mode by a second, geometric route (Merlet 2006, ch. 4): cut leg k;
    legs i, j and the platform side b_i b_j form a four-bar. For the angle t of leg i
    (the crank), C_i = A_i + rho_i e(t) and C_j is one of the two intersections (branch s) of
    the circles |C_j - A_j| = rho_j and |C_j - C_i| = |b_j - b_i|; that fixes phi and C_k.
    The modes are the roots of g(t) = |C_k - A_k| - rho_k on each branch, bracketed on a dense
    grid and refined by brentq. A root where the crank turns back (the coupler in line with
    leg j, where the two branches meet) can be missed, so the scan is repeated with legs i and
    j swapped and the union is returned."""
    A, b = np.asarray(par.A), np.asarray(par.b)
    size = max(np.max(rho), np.max(np.abs(A)), np.max(np.abs(b)))
    found = []
    for i, j, k in ((0, 1, 2), (1, 0, 2)):
        L = np.linalg.norm(b[j] - b[i])
        beta = np.arctan2(b[j, 1] - b[i, 1], b[j, 0] - b[i, 0])

        def pose_of(t, s):
            t = np.atleast_1d(t)
            Ci = A[i] + rho[i] * np.stack([np.cos(t), np.sin(t)], -1)
            g = A[j] - Ci
            G = np.linalg.norm(g, axis=-1)
            a = (G**2 + L**2 - rho[j] ** 2) / (2 * G)
            with np.errstate(invalid="ignore"):
                h = np.sqrt(L**2 - a**2)
            u = g / G[:, None]
            Cj = Ci + a[:, None] * u + s * h[:, None] * np.stack([-u[:, 1], u[:, 0]], -1)
            phi = np.arctan2(Cj[:, 1] - Ci[:, 1], Cj[:, 0] - Ci[:, 0]) - beta
            c, sn = np.cos(phi), np.sin(phi)
            rot = lambda v: np.stack([c * v[0] - sn * v[1], sn * v[0] + c * v[1]], -1)
            p = Ci - rot(b[i])
            Ck = p + rot(b[k])
            return np.column_stack([p, _wrap(phi)]), np.linalg.norm(Ck - A[k], axis=-1) - rho[k]

        t = np.linspace(-np.pi, np.pi, n + 1)
        for s in (1.0, -1.0):
            _, g = pose_of(t, s)
            ok = np.isfinite(g[:-1]) & np.isfinite(g[1:]) & (np.sign(g[:-1]) != np.sign(g[1:]))
            for m in np.nonzero(ok)[0]:
                root = brentq(lambda x: pose_of(x, s)[1][0], t[m], t[m + 1], xtol=1e-15, rtol=1e-15)
                found.append(pose_of(root, s)[0][0])
    out = []
    for p in found:   # t = +-pi is one point; both scans find most modes
        if not any(_pose_distance(p, q, size) < 1e-7 for q in out):
            out.append(p)
    return np.array(out).reshape(-1, 3)


def test_rpr3_inverse_kinematics_and_jacobian():
    par = rpr3.default_rpr3()
    r = rng()
    pose = rpr3.DEFAULT_POSE + np.column_stack([r.uniform(-0.05, 0.05, (4, 2)), r.uniform(-0.3, 0.3, 4)])
    out = rpr3.inverse_kinematics(par, pose)
    ph = pose[:, 2]
    for i in range(3):   # rebuild C_i by hand
        C = pose[:, :2] + np.column_stack([np.cos(ph) * par.b[i, 0] - np.sin(ph) * par.b[i, 1],
                                           np.sin(ph) * par.b[i, 0] + np.cos(ph) * par.b[i, 1]])
        assert_close(out["C"][:, i], C, 1e-14)
        assert_close(out["rho"][:, i], np.linalg.norm(C - par.A[i], axis=-1), 1e-14)
    eps = 1e-6
    for k in range(3):
        d = np.zeros(3)
        d[k] = eps
        rho_of = lambda q: rpr3.inverse_kinematics(par, q)["rho"]
        col = (rho_of(pose + d) - rho_of(pose - d)) / (2 * eps)
        assert_close(out["J"][:, :, k], col, 1e-8, what=f"J col {k}")


@pytest.mark.parametrize("case", ["default_home", "default_four", "six", "recalled"])
def test_rpr3_every_mode_reproduces_rho_and_matches_coupler_scan(case):
    par, rho, count = _rpr_cases()[case]
    sols = rpr3.forward_kinematics(par, rho)
    assert sols.shape == (count, 3), sols
    assert np.all(sols[:, 2] > -np.pi) and np.all(sols[:, 2] <= np.pi)
    assert_close(rpr3.inverse_kinematics(par, sols)["rho"], np.broadcast_to(rho, (count, 3)), 1e-10, what=case)
    # all of them, and no others: the independent geometric route finds the same set
    scan = _coupler_scan(par, rho)
    size = max(np.max(rho), np.max(np.abs(par.A)), np.max(np.abs(par.b)))
    assert len(scan) == count, scan
    for p in scan:
        assert min(_pose_distance(p, q, size) for q in sols) < 1e-9, (p, sols)


def test_rpr3_mode_count_stable_under_tiny_perturbation():
    r = rng()
    for par, rho, count in [(RPR_SIX, RPR_SIX_RHO, 6), (RPR_RECALLED, RPR_RECALLED_RHO, 6),
                            (rpr3.default_rpr3(), RPR_DEFAULT_FOUR_RHO, 4)]:
        base = rpr3.forward_kinematics(par, rho)
        size = np.max(rho)
        for _ in range(4):
            rho2 = rho * (1 + r.uniform(-1e-7, 1e-7, 3))
            sols = rpr3.forward_kinematics(par, rho2)
            assert len(sols) == count
            # each mode moves continuously (well away from a singularity)
            for p in sols:
                assert min(_pose_distance(p, q, size) for q in base) < 1e-5


def test_rpr3_fk_of_ik_contains_the_pose():
    par = rpr3.default_rpr3()
    r = rng()
    n = 30
    pose = np.column_stack([r.uniform(0.15, 0.55, n), r.uniform(0.1, 0.45, n), r.uniform(-np.pi, np.pi, n)])
    pose[:3, 2] = [np.pi, -np.pi + 1e-9, 3.1]   # near and at phi = pi (t = tan(phi/2) = infinity)
    rho = rpr3.inverse_kinematics(par, pose)["rho"]
    counts = []
    for p, rh in zip(pose, rho):
        sols = rpr3.forward_kinematics(par, rh)
        counts.append(len(sols))
        assert len(sols) % 2 == 0 and 2 <= len(sols) <= 6
        assert np.all(sols[:, 2] > -np.pi) and np.all(sols[:, 2] <= np.pi)
        assert min(_pose_distance(p, q, 1.0) for q in sols) < 1e-9, (p, sols)
        assert_close(rpr3.inverse_kinematics(par, sols)["rho"], np.broadcast_to(rh, sols.shape), 1e-10)
    assert max(counts) >= 4   # more than the two obvious modes occur in this box


def test_rpr3_singular_linear_system_fallback():
    """At phi = 0 the points A_i - R b_i are collinear: p comes from the line-circle fallback."""
    par = RPR_COLLINEAR
    for p in ([0.35, 0.3, 0.0], [0.5, 0.1, 0.0]):
        rho = rpr3.inverse_kinematics(par, p)["rho"][0]
        sols = rpr3.forward_kinematics(par, rho)
        # the pose and its mirror image in y = 0 share phi = 0 (a double root of F)
        for q in (np.asarray(p), np.asarray(p) * [1.0, -1.0, 1.0]):
            assert min(_pose_distance(q, s, 1.0) for s in sols) < 1e-9, (q, sols)
        assert_close(rpr3.inverse_kinematics(par, sols)["rho"], np.broadcast_to(rho, sols.shape), 1e-10)
        scan = _coupler_scan(par, rho)
        assert len(scan) == len(sols)


def test_rpr3_eliminant_is_a_sextic():
    """The 4th harmonic of F(phi) cancels (at most 6 real modes), and F vanishes at every mode."""
    r = rng()
    for _ in range(5):
        par = rpr3.RPR3(A=r.uniform(-1, 1, (3, 2)), b=r.uniform(-0.4, 0.4, (3, 2)))
        rho = r.uniform(0.2, 1.5, 3)
        f = rpr3.eliminant_harmonics(par, rho)
        k = (len(f) - 1) // 2
        big = np.max(np.abs(f))
        assert np.all(np.abs(f[: k - 3]) <= 1e-13 * big) and np.all(np.abs(f[k + 4:]) <= 1e-13 * big)
        assert np.max(np.abs(f[[k - 3, k + 3]])) > 1e-6 * big   # degree 3 in general
        assert_close(f[::-1], np.conj(f), 1e-14, what="real F")


def test_rpr3_unreachable_gives_no_mode():
    par = rpr3.default_rpr3()
    assert rpr3.forward_kinematics(par, [0.01, 0.01, 2.0]).shape == (0, 3)   # leg 2 far too long
    assert rpr3.forward_kinematics(par, [0.01, 0.01, 0.01]).shape == (0, 3)  # platform larger than legs allow
    with pytest.raises(ValueError):
        rpr3.forward_kinematics(par, [-0.3, 0.3, 0.3])


def test_rpr3_wrong_formulas_fail():
    par = rpr3.default_rpr3()
    p = rpr3.DEFAULT_POSE
    rho = rpr3.inverse_kinematics(par, p)["rho"][0]
    sols = rpr3.forward_kinematics(par, rho)

    def wrong_ik(pose):   # platform rotated the wrong way: R(-phi)
        return rpr3.inverse_kinematics(par, pose * np.array([1.0, 1.0, -1.0]))["rho"]

    with pytest.raises(AssertionError):
        assert_close(wrong_ik(sols), np.broadcast_to(rho, sols.shape), 1e-10)
    # a leg length 1e-6 m off does not reproduce the pose to 1e-9
    moved = rpr3.forward_kinematics(par, rho + np.array([1e-6, 0.0, 0.0]))
    assert min(_pose_distance(p, q, 1.0) for q in moved) > 1e-9
    # a wrong platform point misses the pose altogether
    bad = rpr3.RPR3(A=par.A, b=par.b * np.array([1.0, -1.0]))
    assert all(_pose_distance(p, q, 1.0) > 1e-3 for q in rpr3.forward_kinematics(bad, rho))

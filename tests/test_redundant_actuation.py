"""Redundant actuation (more actuated joints than freedoms, ``[actuation]``): the built-in 4-RRR's
efforts by each distribution against routes written apart from the engine's.

- **Minimum norm**: the same mechanism with its fourth drive passive is square; its three
  efforts give the generalised force ``w = A_3 u_3`` through LU, and the redundant efforts must
  be ``pinv(A) w`` (``A = J_ax^T``).
- **Minimax**: the least peak ``max |u_i|`` with ``A u = w`` by scipy's linear program (HiGHS),
  against the engine's second-order-cone solver.
- **Weighted**: the least ``sum c_i u_i^2`` satisfies ``N^T C u = 0`` (``N`` the null space of
  ``A``).
- **Preload**: the task motion and the platform's net wrench (the legs' reactions summed) do
  not change; every drive keeps the preload's sign and margin.
- Every distribution keeps the power balance ``sum u qd_a = d(T + V)/dt`` and every body's
  equations (the reactions' residual)."""

from __future__ import annotations

import copy

import multibody_examples as ex
import numpy as np
import pytest
from scipy.optimize import linprog

from pkmdyn.cli import main
from pkmdyn.errors import LimitError, ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.distribution import internal_directions
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions


def _rrr4(**actuation):
    return _builtin("rrr4", **actuation)


def _builtin(name, **actuation):
    d = copy.deepcopy(ex.builtin_dict(name))
    d["actuation"] = {"distribution": "minimum_norm", **actuation}
    return d


def _square(name="rrr4"):
    """The built-in with its last leg's drive passive: as many actuated joints as freedoms."""
    return ex.passive_last_drive(_builtin(name))


def _motion(m, n=25, seed=1):
    amp = np.where(m.task_kind == 1, 0.15, 0.03)
    t = np.linspace(0.0, 1.0, n)
    return (t, *ex.smooth_motion(reference_task(m), amp, t, seed))


def _solve(d, motion):
    m = load_mechanism(d)
    t, x, xd, xdd = motion
    kin = solve_kinematics(m, x, xd, xdd, t)
    return m, kin, joint_reactions(m, kin, split=True)


MOTION = _motion(load_mechanism(_rrr4()))


@pytest.mark.parametrize("name", ["rrr4", "stewart7"])
def test_minimum_norm_efforts_are_the_pseudo_inverse_of_the_square_mechanisms_force(name):
    motion = MOTION if name == "rrr4" else _motion(load_mechanism(_builtin(name)), seed=2)
    m4, kin4, r4 = _solve(_builtin(name), motion)
    m3, kin3, r3 = _solve(_square(name), motion)
    assert m4.na == m4.nt + 1 and m3.na == m3.nt == m4.nt
    assert m3.actuator_names == m4.actuator_names[:-1]
    A = np.swapaxes(kin4.J_ax, 1, 2)  # (n, nt, nt + 1)
    A3 = np.swapaxes(kin3.J_ax, 1, 2)
    assert np.abs(A[:, :, :-1] - A3).max() <= 1e-12 * np.abs(A3).max()
    w = np.einsum("nta,na->nt", A3, r3.u)
    expected = np.einsum("nat,nt->na", np.linalg.pinv(A), w)
    assert np.abs(r4.u - expected).max() <= 1e-10 * np.abs(expected).max()
    # the minimum norm has no internal part
    assert np.abs(r4.shares.internal).max() <= 1e-10 * np.abs(r4.u).max()


def _power_balance(m, kin, u):
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, m.inertia, kin.R)
    dT = np.einsum("b,nbi,nbi->n", m.mass, kin.v, kin.a) + np.einsum("nbi,nbij,nbj->n", kin.w, Iw, kin.wd)
    dV = -np.einsum("b,i,nbi->n", m.mass, m.gravity, kin.v)
    P = np.einsum("na,na->n", u, kin.act_qd)
    return np.abs(P - dT - dV).max() / max(np.abs(P).max(), 1e-3)


@pytest.mark.parametrize("actuation", [{}, {"distribution": "minimax"},
                                       {"distribution": "weighted", "weights": {"RA_1": 4.0, "RA_3": 0.25}},
                                       {"preload_min_effort_SI": 2.0}])
def test_every_distribution_keeps_the_balances(actuation):
    m, kin, r = _solve(_rrr4(**actuation), MOTION)
    A = np.swapaxes(kin.J_ax, 1, 2)
    _, _, base = _solve(_rrr4(), MOTION)
    w = np.einsum("nta,na->nt", A, base.u)
    assert np.abs(np.einsum("nta,na->nt", A, r.u) - w).max() <= 1e-9 * np.abs(w).max()
    assert _power_balance(m, kin, r.u) <= 1e-9
    assert np.abs(r.residual).max() <= 1e-9 * max(np.abs(r.joint_force).max(), 1.0)
    parts = r.shares.groups.sum(axis=2) + r.shares.friction.sum(axis=2) + r.shares.internal
    assert np.abs(parts - r.u).max() <= 1e-9 * np.abs(r.u).max()


def test_minimax_efforts_reach_the_least_peak_of_an_independent_linear_program():
    _, kin, r = _solve(_rrr4(distribution="minimax"), MOTION)
    _, _, base = _solve(_rrr4(), MOTION)
    A = np.swapaxes(kin.J_ax, 1, 2)
    for i in range(len(kin.t)):
        w = A[i] @ base.u[i]
        na = A.shape[2]
        # variables (u, t): least t with A u = w and -t <= u_j <= t
        G = np.block([[np.eye(na), -np.ones((na, 1))], [-np.eye(na), -np.ones((na, 1))]])
        lp = linprog(np.r_[np.zeros(na), 1.0], A_ub=G, b_ub=np.zeros(2 * na), A_eq=np.hstack([A[i], np.zeros((3, 1))]),
                     b_eq=w, bounds=[(None, None)] * na + [(0, None)], method="highs")
        assert lp.status == 0
        peak = float(np.abs(r.u[i]).max())
        assert peak == pytest.approx(lp.x[-1], rel=1e-8)
        assert peak <= np.abs(base.u[i]).max() * (1 + 1e-12)


def test_weighted_efforts_are_the_least_weighted_norm():
    c = {"RA_1": 4.0, "RA_2": 1.0, "RA_3": 0.25, "RA_4": 2.0}
    _, kin, r = _solve(_rrr4(distribution="weighted", weights=c), MOTION)
    N = internal_directions(np.swapaxes(kin.J_ax, 1, 2))
    Cu = r.u * np.array(list(c.values()))
    assert np.abs(np.einsum("nar,na->nr", N, Cu)).max() <= 1e-10 * np.abs(Cu).max()


def test_a_preload_keeps_the_motion_and_the_platforms_net_wrench_and_every_drive_from_zero():
    margin = 2.0
    m, kin, r = _solve(_rrr4(preload_min_effort_SI=margin), MOTION)
    _, kin0, r0 = _solve(_rrr4(), MOTION)
    assert np.array_equal(kin.q, kin0.q)
    N = internal_directions(np.swapaxes(kin.J_ax, 1, 2))[:, :, 0]
    assert np.all(np.sign(N) * r.u >= margin * (1 - 1e-9))
    assert np.abs(r.u - r0.u).max() > margin  # the preload acted
    plat = [j for j, nm in enumerate(m.joint_names) if nm.startswith("RC_")]
    c = kin.x[:, None, :2]

    def net(reac):
        f = reac.joint_force[:, plat]
        arm = reac.joint_point[:, plat] - np.concatenate([c, np.zeros_like(c[..., :1])], axis=2)
        return f.sum(axis=1), (reac.joint_moment[:, plat] + np.cross(arm, f)).sum(axis=1)

    (f1, n1), (f0, n0) = net(r), net(r0)
    scale = np.abs(r.joint_force[:, plat]).max()
    assert np.abs(f1 - f0).max() <= 1e-10 * scale and np.abs(n1 - n0).max() <= 1e-10 * scale


def test_bounds_that_no_distribution_meets_are_refused_naming_the_sample_and_drive():
    _, _, base = _solve(_rrr4(), MOTION)
    low = 0.3 * float(np.abs(base.u).max())
    with pytest.raises(LimitError, match=r"sample \d+.*RA_\d"):
        _solve(_rrr4(distribution="minimax", max_effort_SI={k: low for k in ("RA_1", "RA_2", "RA_3", "RA_4")}),
               MOTION)
    with pytest.raises(LimitError, match=r"sample \d+.*preload"):
        _solve(_rrr4(preload_min_effort_SI=50.0, max_effort_SI={"RA_2": 1.0}), MOTION)


@pytest.mark.parametrize("section, key", [({"weights": {"RA_1": 2.0}}, "weights"),
                                          ({"weights": {"RB_1": 2.0}, "distribution": "weighted"}, "weights"),
                                          ({"max_effort_SI": {"RA_1": -1.0}}, "max_effort_SI"),
                                          ({"preload_sign": {"RA_1": 1}}, "preload_sign")])
def test_bad_actuation_sections_are_refused_naming_the_key(section, key):
    with pytest.raises(ParameterError, match=rf"\[actuation\] {key}"):
        load_mechanism(_rrr4(**section))


def test_an_actuation_section_on_a_mechanism_without_redundancy_is_refused():
    d = copy.deepcopy(ex.builtin_dict("rrr3"))
    d["actuation"] = {"distribution": "minimax"}
    with pytest.raises(ParameterError, match=r"\[actuation\].*nothing to distribute"):
        load_mechanism(d)


def test_describe_and_run_say_the_redundancy(tmp_path, capsys):
    assert main(["describe", "--machine", "rrr4"]) == 0
    out = capsys.readouterr().out
    assert "degree of redundancy 1" in out and "internal-force directions" in out
    assert main(["run", "--machine", "rrr4", "--out", str(tmp_path / "r")]) == 0
    header = (tmp_path / "r" / "results.csv").read_text().splitlines()[0].split(",")
    assert sum(c.endswith("_internal_Nm") for c in header) == 4


def test_identification_from_preloaded_efforts_leaves_the_internal_force_out():
    """Efforts with a preload carry an internal force no parameter determines: the fit of the
    description's own efforts explains them (their least-norm part) to rounding, with the
    description's parameters, and the internal force is gone from the efforts it compares."""
    import pkmdyn

    m, kin, r = _solve(_rrr4(preload_min_effort_SI=2.0), _motion(load_mechanism(_rrr4()), n=120, seed=4))
    fit = pkmdyn.identification(m, kin, r.u)
    u_ln = r.u - r.shares.internal
    assert np.abs(fit.u_identified - u_ln).max() <= 1e-8 * np.abs(u_ln).max()
    assert np.abs(r.shares.internal).max() > 1.0  # the preload was there to remove


@pytest.mark.parametrize("controller", ["computed-torque", "augmented-pd"])
def test_control_of_a_redundantly_actuated_machine_tracks_as_a_square_one(tmp_path, controller):
    """The controller's task effort is shared by the machine's distribution (a preload too) and
    its pose read from the square subset's encoders: it tracks the default motion as the 3-RRR
    does (about 0.02 mm with the exact model; 2 mm when the pose came from a non-square solve)."""
    import json

    d = ex.builtin_dict("rrr4", parametric=True)
    d["actuation"] = {"distribution": "minimax", "preload_min_effort_SI": 0.5}
    from pkmdyn.io import dumps_toml

    f = tmp_path / "rrr4p.toml"
    f.write_text(dumps_toml(d), encoding="utf-8")
    assert main(["control", "--machine", str(f), "--controller", controller, "--out", str(tmp_path / "c")]) == 0
    doc = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert doc["coordinates"]["x"]["max_abs_err_mm"] < 0.1 and doc["coordinates"]["y"]["max_abs_err_mm"] < 0.1
    assert all(v["peak_abs_Nm"] >= 0.5 for v in doc["actuators"].values())


def test_the_internal_forces_stiffness_is_the_actuated_coordinates_hessians_weighted_by_it(tmp_path):
    """K_u = -sum_a u_a d^2 q_a/dx^2 (Eq. S-U of docs/stiffness.md): against second differences of
    the actuated coordinates alone (positions, no actuator map), at a pose off the reference."""
    from pkmdyn.multibody.analyses.stiffness import internal_force_stiffness

    m = load_mechanism(_rrr4())
    x0 = reference_task(m) + np.array([0.02, -0.01, 0.05])
    u = np.array([0.7, -0.4, 0.9, -0.2])
    K = internal_force_stiffness(m, x0[None], u[None])[0]
    h = 2.5e-4  # truncation about h^2 times the fourth derivative; round-off about 1e-12 / h^2
    nt = m.nt

    def q(dx):
        return solve_kinematics(m, (x0 + dx)[None], np.zeros((1, nt)), np.zeros((1, nt))).act_q[0]

    H = np.empty((nt, nt, m.na))
    for i in range(nt):
        for j in range(nt):
            ei, ej = np.eye(nt)[i] * h, np.eye(nt)[j] * h
            H[i, j] = (q(ei + ej) - q(ei - ej) - q(ej - ei) + q(-ei - ej)) / (4 * h * h)
    expected = -np.einsum("ija,a->ij", H, u)
    assert np.abs(K - expected).max() <= 1e-5 * np.abs(expected).max()
    assert np.abs(K - K.T).max() <= 1e-6 * np.abs(K).max()
    # the command writes it for each pose of a preloaded machine
    from pkmdyn.io import dumps_toml

    d = ex.builtin_dict("rrr4", parametric=True)
    d["actuation"] = {"preload_min_effort_SI": 0.5}
    f = tmp_path / "rrr4p.toml"
    f.write_text(dumps_toml(d), encoding="utf-8")
    assert main(["stiffness", "--machine", str(f), "--out", str(tmp_path / "s")]) == 0
    import json

    pose = json.loads((tmp_path / "s" / "stiffness.json").read_text())["poses"][0]
    assert min(abs(v) for v in pose["internal_force"].values()) >= 0.5 * (1 - 1e-9)
    mp = load_mechanism(d)
    xp = np.array([pose["task"][f"{n}_{u}"] for n, u in zip(mp.task_names, mp.task_units)])
    up = np.array([pose["internal_force"][a] for a in mp.actuator_names])
    Kp = internal_force_stiffness(mp, xp[None], up[None])[0]
    assert np.abs(Kp).max() > 1.0  # a 0.5 N m preload on 0.3 m links: about 10 N m/m
    assert np.abs(np.array(pose["K_internal"]) - Kp).max() <= 1e-9 * np.abs(Kp).max()


def test_retiming_refuses_a_distribution_that_is_not_linear():
    from pkmdyn.multibody.analyses.retime import retime, task_path

    m = load_mechanism(_rrr4(preload_min_effort_SI=2.0))
    with pytest.raises(ParameterError, match=r"\[actuation\]: retiming"):
        retime(m, task_path(m, MOTION[1][::5]), 50)


def test_the_pd_laws_share_the_task_effort_by_the_machines_weighted_rule():
    """The PD laws' map from a task effort to the motor efforts of a redundantly actuated machine
    is its distribution's (weighted) least norm over the joint efforts (Eq. R2), divided by the
    drives' ratio: against the weighted least norm solved here as the minimum-norm solution of
    ``(A C^-1/2) v = F``, ``u = C^-1/2 v`` (numpy's lstsq), ``A = J_ax^T``."""
    from pkmdyn.control._laws import Gains, make_controller
    from pkmdyn.control._reference import Reference
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    c = {"RA_1": 1.0, "RA_2": 4.0, "RA_3": 0.5, "RA_4": 2.0}
    d = _rrr4(distribution="weighted", weights=c)
    for leg in d["legs"]:
        leg["actuators"] = [{"joint": "RA", "name": "M", "gear_ratio": 8.0}]
    m = load_mechanism(d)
    t, x, xd, xdd = _motion(m, n=7, seed=5)
    ref = Reference(float(t[1] - t[0]), t, x, xd, xdd, None, x[:-1], xd[:-1], xdd[:-1], None)
    ctrl = make_controller("pd", Gains(*(np.ones(m.nt),) * 3), machine_verbs(m), m, ref)
    kin = solve_kinematics(m, x, xd, xdd, t)
    w = np.array([c[n] for n in m.actuator_names])
    rng = np.random.default_rng(3)
    for s in range(len(t)):
        F = rng.normal(size=m.nt)
        A = kin.J_ax[s].T  # (nt, na): J_ax^T u = F, u the joint efforts
        v = np.linalg.lstsq(A / np.sqrt(w), F, rcond=None)[0]
        tau = v / np.sqrt(w) / 8.0  # the motor torques
        assert np.abs(ctrl.B_inv[s] @ F - tau).max() <= 1e-10 * np.abs(tau).max()
    # (the unweighted pseudo-inverse of B differs: the weights are what the map holds)
    B = np.swapaxes(kin.J_ax, 1, 2) * 8.0
    assert np.abs(np.linalg.pinv(B[0]) - ctrl.B_inv[0]).max() > 1e-3 * np.abs(ctrl.B_inv[0]).max()


@pytest.mark.parametrize("name", ["rrr4", "stewart7"])
def test_the_direct_kinematics_is_the_least_squares_pose_of_every_actuated_joint(name):
    """Exact readings give back the task motion; readings off it by a third of the agreement give
    the pose where the weighted residual's gradient vanishes (central differences of the inverse
    kinematics' actuated coordinates, no actuator map), with a smaller residual than the pose of
    the square subset alone; a reading off by ten times the agreement is refused, naming the
    sample and a joint."""
    from pkmdyn.errors import UnreachablePoseError
    from pkmdyn.multibody.kinematics.direct import REDUNDANT_TOLERANCE, direct_kinematics, square_subset

    m = load_mechanism(_builtin(name))
    t, x, xd, xdd = _motion(m, n=9, seed=6)
    kin = solve_kinematics(m, x, xd, xdd, t)
    dk = direct_kinematics(m, kin.act_q, kin.act_qd, kin.act_qdd, t)
    for got, want in ((dk.x, x), (dk.xd, xd), (dk.xdd, xdd)):
        assert np.abs(got - want).max() <= 1e-9 * max(np.abs(want).max(), 1.0)
    a = np.where(np.array(m.actuator_units) == "m", m.length_scale, 1.0) * REDUNDANT_TOLERANCE
    rng = np.random.default_rng(7)
    s = kin.act_q + a / 3.0 * rng.choice([-1.0, 1.0], size=kin.act_q.shape)
    dk = direct_kinematics(m, s, kin.act_qd, kin.act_qdd, t)

    def f(xx):  # the actuated coordinates at the poses xx
        return solve_kinematics(m, xx, np.zeros_like(xx), np.zeros_like(xx), t).act_q

    noise = np.linalg.norm((s - kin.act_q) / a, axis=1)

    def stationarity(xx):  # |J^T W r| / (|J^T W| |noise|) with W = diag(1/a^2), r = s - q_a(x)
        h = 1e-4  # truncation about h^2 (1e-8), the inverse kinematics' rounding about 1e-12 / h
        J = np.stack([(f(xx + h * e) - f(xx - h * e)) / (2 * h) for e in np.eye(m.nt)], axis=2) / a[None, :, None]
        r = (s - f(xx)) / a
        return r, np.linalg.norm(np.einsum("nat,na->nt", J, r), axis=1) / (np.linalg.norm(J, axis=(1, 2)) * noise)

    r, g = stationarity(dk.x)
    assert np.all(g <= 1e-5)
    sub, keep = square_subset(m)
    x_sub = direct_kinematics(sub, s[:, keep], kin.act_qd[:, keep], kin.act_qdd[:, keep], t).x
    r_sub, g_sub = stationarity(x_sub)
    assert g_sub.max() > 1e-2  # (the square subset's pose is not the least-squares one)
    assert np.all(np.linalg.norm(r, axis=1) <= np.linalg.norm(r_sub, axis=1) * (1 + 1e-9))
    assert np.any(np.linalg.norm(r, axis=1) < 0.9 * np.linalg.norm(r_sub, axis=1))
    s[4, 2] += 10.0 * a[2]
    # (the least squares may move the disagreement onto another joint: the message names the one it sees)
    with pytest.raises(UnreachablePoseError, match=r"sample 4\b.*actuated joint \w+ is at"):
        direct_kinematics(m, s, kin.act_qd, kin.act_qdd, t)
    s[4, 2] -= 10.0 * a[2]
    s[6, 1] += 0.05  # far off (rad or m): refused by name, whether or not the least squares leaves the workspace
    with pytest.raises(UnreachablePoseError, match=r"sample 6\b.*actuated joint \w+ is at"):
        direct_kinematics(m, s, kin.act_qd, kin.act_qdd, t)

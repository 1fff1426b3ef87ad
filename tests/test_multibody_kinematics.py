"""Every derivative of the generic kinematics against central finite differences, loop
closure, batch independence and the Jacobians, on the built-in and textbook mechanisms."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import MotionError, SingularityError, UnreachablePoseError
from pkmdyn.multibody import (
    load_mechanism,
    loop_residuals,
    reference_task,
    singularity_measures,
    solve_kinematics,
)

AMP = {"stewart": [0.05, 0.05, 0.05, 0.1, 0.1, 0.1], "delta": [0.15, 0.15, 0.1], "rrr3": [0.04, 0.04, 0.2],
       "bennett": [0.5], "four_bar": [0.6], "slider_crank": [1.0], "rssr": [0.1], "stewart_sps": [0.05] * 6,
       "stewart_tool": [0.05, 0.05, 0.05, 0.1, 0.1, 0.1], "rrr3_planar": [0.04, 0.04, 0.2],
       "rrr3_planar_cut": [0.04, 0.04, 0.2], "slider_crank_c": [1.0], "four_bar_cut_b": [0.6],
       "stewart_flipped": [0.05, 0.05, 0.05, 0.1, 0.1, 0.1], "sarrus": [0.01], "serial_arm": [0.05, 0.05]}


def _models():
    out = {name: ex.MACHINES / name / f"{name}.toml" for name in ex.BUILTIN}
    out.update(four_bar=ex.four_bar(), slider_crank=ex.slider_crank(), rssr=ex.rssr(), stewart_sps=ex.stewart_sps(),
               stewart_tool=ex.stewart_with_tool(), rrr3_planar=ex.rrr3_planar_platform(),
               rrr3_planar_cut=ex.rrr3_planar_platform(cut_legs=True), slider_crank_c=ex.slider_crank("cylindrical"),
               four_bar_cut_b=ex.four_bar_cut_b(), stewart_flipped=ex.stewart_flipped_spheres(),
               sarrus=ex.sarrus(), serial_arm=ex.serial_arm())
    return out


MODELS = _models()


@pytest.fixture(scope="module", params=sorted(MODELS))
def case(request):
    name = request.param
    return name, load_mechanism(MODELS[name])


def _vee(S):
    return np.stack([S[..., 2, 1], S[..., 0, 2], S[..., 1, 0]], axis=-1)


def _motion(model, name, times, seed=0):
    x0 = reference_task(model)
    return ex.smooth_motion(x0, np.array(AMP[name]), times, seed)


def test_every_derivative_against_finite_differences(case):
    name, m = case
    h = 1e-4
    centres = np.array([0.13, 0.41, 0.77])
    # a fine grid (Newton follows the motion from the reference pose) with (t - h, t, t + h) inserted
    grid = np.linspace(0.0, 0.8, 161)
    grid = grid[np.min(np.abs(grid[:, None] - centres[None]), axis=1) > 3 * h]
    tt = np.sort(np.concatenate([grid, (centres[:, None] + np.array([-h, 0.0, h])).ravel()]))
    x, xd, xdd = _motion(m, name, tt)
    kin = solve_kinematics(m, x, xd, xdd, tt)
    k = np.array([int(np.argmin(np.abs(tt - (c - h)))) for c in centres])  # index of t - h
    mid = k + 1

    def fd(a):
        return (a[k + 2] - a[k]) / (2 * h)

    def check(analytic, numeric, what):
        scale = max(float(np.abs(analytic).max()), 1e-3)
        err = float(np.abs(analytic - numeric).max())
        assert err <= 2e-6 * scale, f"{name}: {what} differs from finite differences by {err:.3g} (scale {scale:.3g})"

    check(kin.qd[mid], fd(kin.q), "qd")
    check(kin.qdd[mid], fd(kin.qd), "qdd")
    check(kin.origin_v[mid], fd(kin.origin), "origin velocity")
    check(kin.origin_a[mid], fd(kin.origin_v), "origin acceleration")
    check(kin.v[mid], fd(kin.p), "centre-of-mass velocity")
    check(kin.a[mid], fd(kin.v), "centre-of-mass acceleration")
    Rd = fd(kin.R)
    check(kin.w[mid], _vee(np.einsum("nbij,nbkj->nbik", Rd, kin.R[mid])), "angular velocity")
    check(kin.wd[mid], fd(kin.w), "angular acceleration")
    check(kin.joint_point_v[mid], fd(kin.joint_point), "joint point velocity")
    check(kin.joint_point_a[mid], fd(kin.joint_point_v), "joint point acceleration")
    check(kin.act_qd[mid], fd(kin.act_q), "actuator rates")
    check(kin.act_qdd[mid], fd(kin.act_qd), "actuator accelerations")
    # the task rates are reproduced by the solved motion (task rows of J qd)
    check(kin.xd[mid], fd(kin.x), "task rates (motion)")


def test_actuator_jacobian_against_finite_differences(case):
    name, m = case
    x0 = reference_task(m)
    x1 = x0 + 0.3 * np.array(AMP[name])
    d = 1e-6
    rows = [x1]
    for i in range(m.nt):
        for s in (1, -1):
            xx = x1.copy()
            xx[i] += s * d
            rows.append(xx)
    kin = solve_kinematics(m, np.array(rows))
    for i in range(m.nt):
        num = (kin.act_q[1 + 2 * i] - kin.act_q[2 + 2 * i]) / (2 * d)
        assert np.allclose(kin.J_ax[0][:, i], num, rtol=1e-6, atol=1e-7), f"{name}: dq_a/dx_{i}"
        num_q = (kin.q[1 + 2 * i] - kin.q[2 + 2 * i]) / (2 * d)
        assert np.allclose(kin.G[0][:, i], num_q, rtol=1e-6, atol=1e-7), f"{name}: dq/dx_{i}"


def test_loops_close_and_task_is_met(case):
    name, m = case
    t = np.linspace(0.0, 1.5, 120)
    x, xd, xdd = _motion(m, name, t, seed=3)
    kin = solve_kinematics(m, x, xd, xdd, t)
    res = loop_residuals(m, kin.q)
    assert np.abs(res).max(initial=0.0) <= 1e-11 * m.length_scale
    assert kin.residual.max() <= 1e-12
    assert np.all(np.isfinite(kin.R)) and np.all(np.isfinite(kin.joint_point_a))
    # rotations stay orthonormal
    RtR = np.einsum("nbji,nbjk->nbik", kin.R, kin.R)
    assert np.abs(RtR - np.eye(3)).max() < 1e-12


def test_batch_of_one_equals_batch_of_many(case):
    name, m = case
    t = np.linspace(0.0, 1.0, 60)
    x, xd, xdd = _motion(m, name, t, seed=5)
    kin = solve_kinematics(m, x, xd, xdd, t)
    for s in (0, 17, 59):
        one = solve_kinematics(m, x[s:s + 1], xd[s:s + 1], xdd[s:s + 1])
        for field in ("q", "qd", "qdd", "R", "origin", "w", "wd", "a", "joint_point_a", "act_q", "J_ax"):
            a, b = getattr(one, field)[0], getattr(kin, field)[s]
            assert np.allclose(a, b, rtol=1e-9, atol=1e-10 * max(1.0, float(np.abs(b).max()))), f"{name}: {field}"


def test_a_pose_at_rest_has_the_moving_poses_maps_and_no_motion(case):
    """A pose solved at rest (xd = xdd = 0: a grid's, a pose of its own) has the positions and the
    maps G and J_ax of the same pose in motion, and every rate, velocity and acceleration zero
    (the solver leaves their passes out at rest); the moving pose's rates are G xd."""
    name, m = case
    t = np.linspace(0.0, 1.0, 30)
    x, xd, xdd = _motion(m, name, t, seed=3)
    moving = solve_kinematics(m, x, xd, xdd, t)
    for s in (0, 11, 29):
        rest = solve_kinematics(m, x[s:s + 1], q_start=moving.q[s])
        for field in ("q", "G", "J_ax", "R", "origin", "joint_point"):
            a, b = getattr(rest, field)[0], getattr(moving, field)[s]
            assert np.allclose(a, b, rtol=1e-9, atol=1e-10 * max(1.0, float(np.abs(b).max()))), f"{name}: {field}"
        for field in ("qd", "qdd", "origin_v", "origin_a", "w", "wd", "v", "a", "joint_point_v", "joint_point_a",
                      "act_qd", "act_qdd"):
            assert np.all(getattr(rest, field) == 0.0), f"{name}: {field}"
        np.testing.assert_allclose(moving.qd[s], moving.G[s] @ xd[s], rtol=1e-9,
                                   atol=1e-12 * max(1.0, float(np.abs(moving.qd[s]).max())))
    # at rest within a moving motion: after moving samples (whose velocities and accelerations
    # fill the solver's buffers) and before others
    xd2, xdd2 = xd.copy(), xdd.copy()
    xd2[11:13] = xdd2[11:13] = 0.0
    mixed = solve_kinematics(m, x, xd2, xdd2, t)
    for field in ("qd", "qdd", "origin_v", "origin_a", "w", "wd", "v", "a", "joint_point_v", "joint_point_a"):
        assert np.all(getattr(mixed, field)[11:13] == 0.0), f"{name}: {field}"
        a, b = getattr(mixed, field)[13:], getattr(moving, field)[13:]
        assert np.allclose(a, b, rtol=1e-9, atol=1e-9 * max(1.0, float(np.abs(b).max()))), f"{name}: {field}"
    for field in ("q", "G"):
        a, b = getattr(mixed, field), getattr(moving, field)
        assert np.allclose(a, b, rtol=1e-9, atol=1e-10 * max(1.0, float(np.abs(b).max()))), f"{name}: {field}"


def test_singularity_measures_are_in_range(case):
    name, m = case
    t = np.linspace(0.0, 1.0, 20)
    x, xd, xdd = _motion(m, name, t, seed=6)
    kin = solve_kinematics(m, x, xd, xdd, t)
    sm = singularity_measures(m, kin.q)
    for arr in (sm.inverse, sm.constraint):
        assert np.all((arr > 0) & (arr <= 1))
    if m.na == m.nt:
        assert np.all((sm.direct > 0) & (sm.direct <= 1))


def test_delta_direct_singularity_measure_falls_towards_a_stretched_arm():
    """A Delta whose platform drops towards full reach: the forearm lines up with the upper arm
    and the inverse-kinematic (type I) measure falls towards zero; then the pose is refused."""
    m = load_mechanism(ex.MACHINES / "delta" / "delta.toml")
    reach = -np.sqrt((0.524 + 1.244) ** 2 - (0.163678801315259 - 0.0219393102292058) ** 2)  # arm and forearm in line
    z = np.linspace(-1.0, reach + 1e-4, 400)
    x = np.stack([np.zeros_like(z), np.zeros_like(z), z], axis=-1)
    kin = solve_kinematics(m, x)
    sm = singularity_measures(m, kin.q)
    assert sm.inverse[-1] < 0.2 * sm.inverse[0]
    assert np.all(np.diff(sm.inverse[-50:]) < 0)
    beyond = np.concatenate([x, [[0.0, 0.0, reach - 0.01]]])
    with pytest.raises((UnreachablePoseError, SingularityError), match=r"sample 400\b"):
        solve_kinematics(m, beyond)


def test_unreachable_pose_names_the_sample_and_loop():
    """The first sample beyond the reach (z = -1.776 m, the reach of arm and forearm being
    1.768 m), its time and the row left open: a loop's, or the task coordinate that the loops
    cannot follow (at an unreachable pose either row may carry the residual: which one depends
    on the rounding of the idle freedoms' basis, an arbitrary basis of their null space)."""
    m = load_mechanism(ex.MACHINES / "delta" / "delta.toml")
    x = np.tile(reference_task(m), (30, 1))
    x[:, 2] -= np.linspace(0.0, 1.5, 30)  # below the reach of arm and forearm (1.768 m)
    t = np.linspace(0.0, 1.0, 30)
    with pytest.raises(UnreachablePoseError, match=r"sample 15 \(t = 0.517241 s\).*(loop \d+ \(cut \w+\): \w+|task "
                                                   r"coordinate [xyz]) does not close"):
        solve_kinematics(m, x, t=t)


def test_a_joint_traversed_backwards_gives_the_same_motion():
    """Describing joints the other way round (the tree then inverts their motion) changes nothing."""
    for plain, flipped in ((ex.four_bar(), ex.four_bar_cut_b()), (ex.builtin_dict("stewart"), ex.stewart_flipped_spheres())):
        m1, m2 = load_mechanism(plain), load_mechanism(flipped)
        assert m2.joint_flipped.any()
        name = m1.name
        t = np.linspace(0.0, 1.0, 50)
        x, xd, xdd = ex.smooth_motion(reference_task(m1), np.array(AMP["stewart" if name == "stewart" else name]), t)
        k1, k2 = solve_kinematics(m1, x, xd, xdd), solve_kinematics(m2, x, xd, xdd)
        for b, nm in enumerate(m1.body_names):
            b2 = m2.body_names.index(nm)
            for f in ("R", "origin", "w", "wd", "origin_a"):
                assert np.allclose(getattr(k1, f)[:, b], getattr(k2, f)[:, b2], atol=1e-10), (name, nm, f)
        assert np.allclose(k1.act_q, k2.act_q, atol=1e-12) and np.allclose(k1.act_qdd, k2.act_qdd, atol=1e-9)


def test_bad_motion_arrays_are_refused():
    m = load_mechanism(ex.four_bar())
    with pytest.raises(MotionError, match="x: expected shape"):
        solve_kinematics(m, np.zeros((5, 2)))
    with pytest.raises(MotionError, match="non-finite"):
        solve_kinematics(m, np.array([[np.nan]]))


def test_a_coarsely_sampled_motion_is_bridged_and_matches_a_fine_one(monkeypatch):
    """A Bennett crank stepped by 1.8 rad in one sample: one Newton solve does not get there,
    the step is bridged, and the result is the fine path's (same assembly branch)."""
    import pkmdyn.multibody.kinematics.inverse as kinematics

    used = []
    bridge = kinematics._bridge
    monkeypatch.setattr(kinematics, "_bridge", lambda *a: used.append(a[3]) or bridge(*a))
    m = load_mechanism(ex.MACHINES / "bennett" / "bennett.toml")
    coarse = solve_kinematics(m, np.array([[1.047], [2.5], [-2.0]]))
    assert used == [2]
    fine_x = np.concatenate([np.linspace(1.047, 2.5, 100), np.linspace(2.5, 2.5 + (2 * np.pi - 4.5), 300)])
    fine = solve_kinematics(m, ((fine_x + np.pi) % (2 * np.pi) - np.pi)[:, None])
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    assert np.allclose(wrap(coarse.q[-1] - fine.q[-1]), 0.0, atol=1e-10)
    assert np.allclose(coarse.R[-1], fine.R[-1], atol=1e-10)


def _planar_angle(v):
    return np.arctan2(v[..., 1], v[..., 0])


@pytest.mark.parametrize("cut", ["B", "C", "D"])
def test_joint_coordinates_of_cut_and_tree_joints_follow_the_links_angles(cut):
    """Each revolute joint's coordinate, whether the joint is in the tree or cut, equals the
    relative angle of its two links computed from the joint centres alone (child link's
    angle less the parent link's, the ground's being zero)."""
    from pkmdyn.multibody.kinematics.inverse import joint_coordinates

    d = ex.four_bar()
    d["mechanism"]["cut_joints"] = [cut]
    m = load_mechanism(d)
    assert m.joint_cut[m.joint_index(cut)]
    t = np.linspace(0.0, 2.0, 40)
    x, xd, xdd = _motion(m, "four_bar", t)
    kin = solve_kinematics(m, x, xd, xdd, t)
    names = ["A", "B", "C", "D"]
    P = {nm: kin.joint_point[:, m.joint_index(nm)] for nm in names}
    link = {"crank": _planar_angle(P["B"] - P["A"]), "coupler": _planar_angle(P["C"] - P["B"]),
            "rocker": _planar_angle(P["C"] - P["D"])}
    link = {k: np.unwrap(v) - v[0] for k, v in link.items()}  # change from the first sample
    expect = {"A": link["crank"], "B": link["coupler"] - link["crank"], "C": link["rocker"] - link["coupler"],
              "D": -link["rocker"]}  # D: child ground relative to parent rocker
    c = joint_coordinates(m, kin, [m.joint_index(nm) for nm in names])
    for i, nm in enumerate(names):
        assert np.abs((c[:, i] - c[0, i]) - expect[nm]).max() < 1e-10, nm


@pytest.mark.parametrize("cut", ["C", "D"])
def test_a_sliding_joints_coordinate_is_its_displacement_whether_cut_or_not(cut):
    from pkmdyn.multibody.kinematics.inverse import joint_coordinates

    d = ex.slider_crank()
    d["mechanism"]["cut_joints"] = [cut]
    m = load_mechanism(d)
    t = np.linspace(0.0, 2.0, 30)
    x, xd, xdd = _motion(m, "slider_crank", t)
    kin = solve_kinematics(m, x, xd, xdd, t)
    j = m.joint_index("D")
    c = joint_coordinates(m, kin, [j])[:, 0]
    slider_x = kin.joint_point[:, m.joint_index("C"), 0]  # the pin on the slider
    assert np.abs(c - (slider_x - 0.3354101966249684)).max() < 1e-12


def _stewart_motion(m, n=30):
    t = np.linspace(0.0, 1.0, n)
    x = np.tile(reference_task(m), (n, 1))
    x[:, 2] += 0.3 * t  # rise by 0.3 m: the legs lengthen
    x[:, 3] += 0.1 * t
    return t, x


def test_a_motion_beyond_a_joint_limit_is_refused_naming_the_joint_and_the_sample():
    from pkmdyn.multibody.kinematics.inverse import joint_coordinates

    d = ex.builtin_dict("stewart")
    m = load_mechanism(d)
    t, x = _stewart_motion(m)
    free = solve_kinematics(m, x, t=t, limits=False)
    legs = joint_coordinates(m, free)
    longest = float(legs.max())
    worst = [m.joint_names[j] for j in range(len(m.joint_names)) if m.joint_limits[j]][int(np.argmax(legs.max(axis=0)))]
    first = int(np.flatnonzero(legs.max(axis=1) > longest - 1e-6)[0])
    for leg in d["legs"]:
        for jd in leg["joints"]:
            if "limits_m" in jd:
                jd["limits_m"] = [0.9, longest + 1e-6]
    within = load_mechanism(d)
    kin = solve_kinematics(within, x, t=t, limits=True)  # within the limits by 1 um: solved
    assert np.array_equal(kin.q, free.q)
    for leg in d["legs"]:
        for jd in leg["joints"]:
            if "limits_m" in jd:
                jd["limits_m"] = [0.9, longest - 1e-6]
    beyond = load_mechanism(d)
    with pytest.raises(UnreachablePoseError) as e:
        solve_kinematics(beyond, x, t=t, limits=True)
    msg = str(e.value)
    assert f"sample {first} " in msg and f"joint {worst!r}" in msg and "limits" in msg
    from pkmdyn.multibody.kinematics.inverse import limit_violation

    kin = solve_kinematics(beyond, x, t=t)  # without limits=True: solved, the violation told apart
    assert np.array_equal(kin.q, free.q)
    s, j, v = limit_violation(beyond, kin)
    assert (s, beyond.joint_names[j]) == (first, worst) and v > longest - 1e-6
    assert limit_violation(within, kin) is None
    from pkmdyn.multibody import reachable

    ok = reachable(beyond, x[[0, first]])
    assert ok.tolist() == [True, False]
    assert reachable(within, x[[0, first]]).tolist() == [True, True]


@pytest.mark.parametrize("command", ["run", "control"])
def test_cli_warns_where_the_motion_leaves_the_limits(tmp_path, capsys, command):
    """The run goes on (the kinematics hold beyond a limit) and says where the motion leaves the
    limits: one warning line on stderr and, for run, in summary.json; none within them."""
    import json

    from pkmdyn.cli import main

    m = load_mechanism(ex.MACHINES / "stewart" / "stewart.toml")
    t = np.linspace(0.0, 1.0, 21)
    for rise, beyond in ((0.5, True), (0.05, False)):
        x = np.tile(reference_task(m), (21, 1))
        x[:, 2] += rise * t  # legs 1.22 m at the reference, limits 0.9 to 1.6 m
        f = tmp_path / f"m{rise}.csv"
        cols = [f"{nm}_{u}" for nm, u in zip(m.task_names, m.task_units)]
        f.write_text("t_s," + ",".join(cols) + "\n" + "".join(f"{a:.17g}," + ",".join(f"{v:.17g}" for v in r) + "\n"
                                                            for a, r in zip(t, x)), encoding="utf-8")
        out = tmp_path / f"o{rise}"
        code = main([command, "--machine", "stewart", "--motion", str(f), "--out", str(out)])
        warn = [ln for ln in capsys.readouterr().err.splitlines() if "joint limits" in ln]
        assert code == 0
        if beyond:
            assert len(warn) == 1 and "joint 'P_" in warn[0] and "beyond its limits [0.9, 1.6] m" in warn[0]
        else:
            assert warn == []
        if command == "run":
            lim = json.loads((out / "summary.json").read_text())["joint_limits"]
            assert lim["kept"] is (not beyond)
            assert (lim["first_beyond"] is not None) is beyond


@pytest.mark.parametrize("ref", [0.4, -0.7])
def test_a_cut_joints_coordinate_carries_its_reference_value_as_the_same_joint_in_the_tree(ref):
    """The same joint with the same reference angle gives the same absolute coordinate whether
    the tree holds it or it is cut (its reference value included, not only its changes)."""
    from pkmdyn.multibody.kinematics.inverse import joint_coordinates

    values = []
    for cut in ("B", "C"):
        d = ex.four_bar()
        d["mechanism"]["cut_joints"] = [cut]
        next(j for j in d["joints"] if j["name"] == "B")["angle_at_reference_rad"] = ref
        m = load_mechanism(d)
        t = np.linspace(0.0, 2.0, 30)
        x, xd, xdd = _motion(m, "four_bar", t)
        kin = solve_kinematics(m, x, xd, xdd, t)
        values.append(joint_coordinates(m, kin, [m.joint_index("B")])[:, 0])
    assert np.abs(values[0] - values[1]).max() < 1e-10
    assert abs(values[0][0] - ref) < 1e-12 and np.abs(values[0] - ref).max() > 0.1  # it starts at ref and moves


@pytest.mark.parametrize("name,amp", [("stewart", 0.05), ("rrr3", 0.04)])
@pytest.mark.parametrize("eps", [1e-14, 1e-12, 1e-9, 0.0])
def test_a_near_repeated_time_at_an_acceleration_jump_keeps_the_solution(name, amp, eps):
    """Two motion segments joined at a time repeated to within ``eps``, the accelerations
    jumping there (bang-bang): the predictor's jerk term from the last step's change of the
    accelerations must not take a near-zero step as a jerk; the solution along the times is
    the one without times (the same loops closed, no turn gained)."""
    m = load_mechanism(ex.builtin_dict(name))
    x0 = reference_task(m)
    a = np.full(m.nt, 200.0 * amp)  # [m/s^2, rad/s^2]: amp at the switch, twice amp at the end
    T, dt = 0.1, 1e-3
    t = np.concatenate([np.arange(0.0, T + dt / 2, dt), T + eps + np.arange(0.0, T + dt / 2, dt)])
    acc = np.where(t <= T, 1.0, -1.0)[:, None] * a[None, :]
    tt = np.where(t <= T, t, t - eps)  # the motion's own clock: continuous through the switch
    vel = np.where(tt[:, None] <= T, a * tt[:, None], a * T - a * (tt[:, None] - T))
    pos = np.where(tt[:, None] <= T, 0.5 * a * tt[:, None] ** 2,
                   0.5 * a * T**2 + a * T * (tt[:, None] - T) - 0.5 * a * (tt[:, None] - T) ** 2)
    x = x0 + pos
    timed = solve_kinematics(m, x, vel, acc, t)
    untimed = solve_kinematics(m, x, vel, acc)
    assert np.abs(timed.q - untimed.q).max() < 1e-9


@pytest.mark.parametrize("name,amp", [("delta", 0.1), ("rrr3", 0.04)])
@pytest.mark.parametrize("scale", [1e-6, 1.0, 1e3])
def test_positions_do_not_depend_on_the_rates_given_without_times(name, amp, scale):
    """Without times the predictor's second-order term follows the given rates; rates out of
    scale with the positions' own steps (other units, a wrong column) must not move the
    solved positions off the branch the positions alone give."""
    m = load_mechanism(ex.builtin_dict(name))
    t = np.linspace(0.0, 1.0, 201)
    w = 2.0 * np.pi
    amp = amp * np.linspace(1.0, 0.6, m.nt) * (m.task_kind == m.task_kind)
    x = reference_task(m) + amp * np.sin(w * t)[:, None]
    xd = amp * w * np.cos(w * t)[:, None]
    plain = solve_kinematics(m, x)
    rated = solve_kinematics(m, x, scale * xd)
    assert np.abs(rated.q - plain.q).max() < 1e-9

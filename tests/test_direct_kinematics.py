"""Direct kinematics of described mechanisms (pkmdyn.multibody.kinematics.direct): the pose from the
actuator coordinates against independent closed forms (tests/oracles: the Delta's three-sphere
intersection, the Gough-Stewart leg lengths), round trips with the inverse kinematics on every
built-in machine, the assembly-mode search, and the commands (``pkmdyn assemble``, ``pkmdyn run
--actuator-motion``) with their refusals."""

from __future__ import annotations

import re

import json
from pathlib import Path

import numpy as np
import pytest

import multibody_examples as ex
from oracles import delta, stewart
from pkmdyn.cli import main
from pkmdyn.errors import MotionError, ParameterError, SingularityError, UnreachablePoseError
from pkmdyn.machines.registry import described_machines, generated_machines
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.kinematics.direct import actuator_reference, assembly_modes, direct_kinematics, parse_actuators
from pkmdyn.multibody.model.poses import body_poses

MACHINES = Path(__file__).resolve().parents[1] / "src" / "pkmdyn" / "machines"


def _model(name):
    if name in generated_machines():
        return load_mechanism(generated_machines()[name].description())
    return load_mechanism(described_machines()[name])


def _scaled(model):
    """Task coordinates scaled to dimensionless (lengths over the mechanism's size)."""
    return np.where(model.task_kind == 0, 1.0 / model.length_scale, 1.0)


def _smooth(model, n=240, seed=0, size=1.0):
    t = np.linspace(0.0, 1.2, n)
    amp = size * np.where(model.task_kind == 1, 0.06, 0.04 * model.length_scale)
    x, xd, xdd = ex.smooth_motion(reference_task(model), amp, t, seed)
    return t, x, xd, xdd


def _run(capsys, *args):
    code = main([str(a) for a in args])
    out = capsys.readouterr()
    return code, out.out, out.err


# ----------------------------------------------------------------------------- independent closed forms
@pytest.mark.parametrize("seed", [3, 4])
def test_delta_pose_from_the_arm_angles_is_the_three_sphere_intersection(seed):
    """Arm angles from the oracle's inverse kinematics of a random motion below the base; the
    direct kinematics (continuation from the reference pose) gives back the oracle's
    three-sphere intersection and the motion's rates."""
    m = _model("delta")
    g = delta.williams_irb360_geometry()
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.0, 200)
    x0 = np.array([0.0, 0.0, -1.0])
    a, w, ph = rng.uniform(-1, 1, 3) * [0.15, 0.15, 0.1], rng.uniform(2, 6, 3), rng.uniform(0, 6, 3)
    x = x0 + a * (np.sin(w * t[:, None] + ph) - np.sin(ph))
    xd = a * w * np.cos(w * t[:, None] + ph)
    xdd = -a * w * w * np.sin(w * t[:, None] + ph)
    ref = delta.kinematics(x, g["R_b"], g["R_p"], g["L_A"], g["L_B"], xd, xdd)
    legs = [m.actuator_names.index(f"R_{i + 1}") for i in range(3)]
    s = np.empty((len(t), 3))
    sd, sdd = np.empty_like(s), np.empty_like(s)
    s[:, legs], sd[:, legs], sdd[:, legs] = ref["theta"], ref["thetad"], ref["thetadd"]
    dk = direct_kinematics(m, s, sd, sdd, t)
    fk = delta.forward_kinematics(ref["theta"], g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    assert np.abs(dk.x - fk).max() <= 1e-10 * m.length_scale
    assert np.abs(dk.x - x).max() <= 1e-10 * m.length_scale
    assert np.abs(dk.xd - xd).max() <= 1e-8 * np.abs(xd).max()
    assert np.abs(dk.xdd - xdd).max() <= 1e-8 * np.abs(xdd).max()
    assert np.all(dk.residual <= 1e-12) and np.all(np.sign(dk.det) == np.sign(dk.det[0]))


def test_delta_assembly_modes_include_both_sphere_intersections():
    """At one set of arm angles, the modes with the platform parallel to the base are exactly
    the two intersections of the three spheres (the oracle's lower one and its mirror image in
    the plane of the sphere centres); the others turn the platform (the rod pairs crossed)."""
    m = _model("delta")
    g = delta.williams_irb360_geometry()
    p = np.array([[0.06, -0.04, -0.95]])
    theta = delta.inverse_kinematics(p, g["R_b"], g["R_p"], g["L_A"], g["L_B"])
    legs = [m.actuator_names.index(f"R_{i + 1}") for i in range(3)]
    s = np.empty(3)
    s[legs] = theta[0]
    modes = assembly_modes(m, s, starts=600, seed=1)
    centres = delta.elbow_points(theta, g["R_b"], g["L_A"])[0] - g["R_p"] * delta.leg_directions()
    normal = np.cross(centres[1] - centres[0], centres[2] - centres[0])
    normal /= np.linalg.norm(normal)
    low = delta.forward_kinematics(theta, g["R_b"], g["R_p"], g["L_A"], g["L_B"])[0]
    high = low - 2.0 * np.dot(low - centres[0], normal) * normal
    pl = m.body_names.index("platform")
    parallel = [a.x for a in modes.modes if np.abs(body_poses(m, a.q)[0][pl] - np.eye(3)).max() < 1e-9]
    assert len(parallel) == 2
    found = sorted(parallel, key=lambda v: v[2])
    assert np.abs(found[0] - low).max() <= 1e-9 and np.abs(found[1] - high).max() <= 1e-9
    assert np.abs(modes.modes[0].x - low).max() <= 1e-9  # nearest the reference pose first
    for a in modes.modes:
        assert a.round_trip <= 1e-10 and a.residual <= 1e-12 and a.hits >= 1


@pytest.mark.parametrize("seed", [1, 2])
def test_stewart_pose_from_the_leg_lengths(seed):
    """Leg lengths (and their rates) of a random motion by the oracle's inverse kinematics
    (Merlet ch. 3); the direct kinematics gives the motion back."""
    m = _model("stewart")
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 1.5, 300)
    amp = np.array([0.06, 0.06, 0.05, 0.08, 0.08, 0.1])
    a, w, ph = rng.uniform(-1, 1, 6) * amp, rng.uniform(2, 6, 6), rng.uniform(0, 6, 6)
    x = np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0]) + a * (np.sin(w * t[:, None] + ph) - np.sin(ph))
    xd = a * w * np.cos(w * t[:, None] + ph)
    xdd = -a * w * w * np.sin(w * t[:, None] + ph)
    A, B, _ = stewart.default_geometry()
    ref = stewart.inverse_kinematics(A, B, x[:, :3], x[:, 3:], "XYZ", xd[:, :3], xd[:, 3:], xdd[:, :3], xdd[:, 3:])
    legs = [m.actuator_names.index(f"P_{i + 1}") for i in range(6)]
    s, sd, sdd = (np.empty((len(t), 6)) for _ in range(3))
    s[:, legs], sd[:, legs], sdd[:, legs] = ref["L"], ref["Ld"], ref["Ldd"]
    dk = direct_kinematics(m, s, sd, sdd, t)
    sc = _scaled(m)
    assert np.abs((dk.x - x) * sc).max() <= 1e-10
    assert np.abs((dk.xd - xd) * sc).max() <= 1e-8 * np.abs(xd * sc).max()
    assert np.abs((dk.xdd - xdd) * sc).max() <= 1e-8 * np.abs(xdd * sc).max()
    pl = m.body_names.index("platform")
    R = np.stack([body_poses(m, q)[0][pl] for q in dk.q[::50]])
    assert np.abs(R - ref["R"][::50]).max() <= 1e-10


# ----------------------------------------------------------------------------- every built-in machine
BUILTINS = ["stewart", "delta", "rrr3", "bennett", "hip", "pdm"]


@pytest.mark.parametrize("name", BUILTINS)
def test_round_trips_with_the_inverse_kinematics(name):
    """direct(inverse(x)) = x to 1e-10 and inverse(direct(s)) = s to 1e-12 (scaled), rates and
    accelerations included, along a random motion away from singularities; the batched
    route's tree coordinates are the inverse kinematics' own."""
    m = _model(name)
    t, x, xd, xdd = _smooth(m, seed=7)
    kin = solve_kinematics(m, x, xd, xdd, t)
    dk = direct_kinematics(m, kin.act_q, kin.act_qd, kin.act_qdd, t)
    sc = _scaled(m)
    assert np.abs((dk.x - x) * sc).max() <= 1e-10
    assert np.abs((dk.xd - xd) * sc).max() <= 1e-8 * max(np.abs(xd * sc).max(), 1e-12)
    assert np.abs((dk.xdd - xdd) * sc).max() <= 1e-8 * max(np.abs(xdd * sc).max(), 1e-12)
    back = solve_kinematics(m, dk.x, dk.xd, dk.xdd, t)
    act_sc = np.where(m.coord_motion[m.act_coord] >= 3, 1.0 / m.length_scale, 1.0)
    assert np.abs((back.act_q - kin.act_q) * act_sc).max() <= 1e-12
    assert np.abs(dk.q - kin.q).max() <= 1e-9
    # dq/ds by finite differences of the direct kinematics itself
    k = 60
    h = 1e-6
    for a in range(m.na):
        e = np.zeros(m.na)
        e[a] = h * (m.length_scale if m.coord_motion[m.act_coord[a]] >= 3 else 1.0)
        xp = direct_kinematics(m, (kin.act_q[k] + e)[None], q_start=dk.q[k]).x[0]
        xm = direct_kinematics(m, (kin.act_q[k] - e)[None], q_start=dk.q[k]).x[0]
        one = np.zeros((1, m.na))
        one[0, a] = 1.0
        rate = direct_kinematics(m, kin.act_q[k][None], one, q_start=dk.q[k]).xd[0]
        assert np.abs((xp - xm) / (2 * e[a]) - rate).max() <= 1e-6 * max(np.abs(rate).max(), 1.0)


@pytest.mark.parametrize("name", BUILTINS)
def test_one_sample_at_a_time_gives_the_motion_back(name):
    """The controller's route (``direct_one``: one compiled call per sample from the previous
    sample's solution, the checked route where that call cannot answer) gives the motion's
    poses and rates back from its actuator coordinates, also after a jump from the last sample
    back to the first; the compiled call answered the motion's samples."""
    from pkmdyn.multibody.kinematics import _direct_kernels as D
    from pkmdyn.multibody.kinematics.direct import one_state, task_state
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = _model(name)
    t, x, xd, xdd = _smooth(m, seed=5)
    kin = solve_kinematics(m, x, xd, xdd, t)
    V = machine_verbs(m)
    sc = _scaled(m)
    for _ in range(2):
        got = np.array([np.concatenate(V.direct_one(m, kin.act_q[k], kin.act_qd[k])) for k in range(len(t))])
        assert np.abs((got[:, :m.nt] - x) * sc).max() <= 1e-10
        assert np.abs((got[:, m.nt:] - xd) * sc).max() <= 1e-8 * max(np.abs(xd * sc).max(), 1e-12)
        st = V._state(m)
        # the task-space route where every actuator belongs to a leg placed from the task alone
        assert bool(st.direct_task) == (name in ("stewart", "hip"))
        state = task_state(st.direct_task[1]) if st.direct_task else one_state(st.direct[0])
        assert state[0] == D.ONE_FACTORED
    with pytest.raises((MotionError, ParameterError), match="actuator|column|shape|expected"):
        V.direct_one(m, kin.act_q[0][:-1], kin.act_qd[0][:-1])  # one actuator short: the checked route refuses


def test_the_first_sample_is_reached_from_the_reference_pose():
    """Without a start, the first sample comes by continuation from the reference actuator
    coordinates: the assembly mode of the description's reference pose."""
    m = _model("stewart")
    s0 = actuator_reference(m)
    dk = direct_kinematics(m, s0[None])
    assert np.abs((dk.x[0] - reference_task(m)) * _scaled(m)).max() <= 1e-12


@pytest.mark.parametrize("name", ["stewart", "hip", "UPS", "RUS", "PUS"])
def test_task_motion_by_the_actuated_coordinates_alone_matches_the_tree_route(name):
    """Asked for the task motion alone, the direct kinematics along a motion takes each sample
    after the first from the legs' actuated coordinates' closed forms (their slides and cranks:
    Gough-Stewart, hip, and U-P-S, R-U-S, P-U-S platforms turned by an arbitrary rotation). Its
    poses, rates and accelerations are those of the tree-space route (whose accelerations come
    from the loop rows' drift, not from the legs' closure derivatives) and of the motion the
    actuators came from, its branch keeps the tree-space route's sign, and it leaves out the tree
    coordinates."""
    from test_explicit_legs import _rot, platform

    from pkmdyn.multibody.kinematics.direct import _by_the_actuated_coordinates

    m = _model(name) if name in ("stewart", "hip") else load_mechanism(platform(name, _rot([0.3, -0.8, 0.5], 2.1)))
    t, x, xd, xdd = _smooth(m, n=300, seed=7, size=0.7)
    kin = solve_kinematics(m, x, xd, xdd, t)
    s, sd, sdd = kin.act_q, kin.act_qd, kin.act_qdd
    full = direct_kinematics(m, s, sd, sdd, t)
    assert _by_the_actuated_coordinates(m, s, sd, sdd, full.q[0], full.x[0]) is not None
    alone = direct_kinematics(m, s, sd, sdd, t, bodies=False)
    assert alone.q is None and alone.qd is None and alone.qdd is None
    sc = _scaled(m)
    for got, ref, true in ((alone.x, full.x, x), (alone.xd, full.xd, xd), (alone.xdd, full.xdd, xdd)):
        size = np.abs(true * sc).max()
        assert np.abs((got - ref) * sc).max() <= 1e-10 * size
        assert np.abs((got - true) * sc).max() <= 1e-10 * size
    assert np.all(alone.det * full.det > 0)  # one sign along the motion, the tree-space route's
    assert np.all(alone.residual <= 1e-12) and np.all(alone.iterations <= 3)


# ----------------------------------------------------------------------------- refusals
@pytest.mark.parametrize("bodies", [True, False])
def test_unreachable_actuator_coordinates_name_the_sample_and_an_actuator(bodies):
    m = _model("stewart")
    t, x, xd, xdd = _smooth(m)
    s = solve_kinematics(m, x, xd, xdd, t).act_q.copy()
    k = m.actuator_names.index("P_4")
    s[150:, k] += np.linspace(0.0, 3.0, len(t) - 150) ** 2  # leg 4 far longer than the others allow
    with pytest.raises(UnreachablePoseError, match=r"sample 1[5-9]\d .*actuator 'P_\d'.*reach no pose"):
        direct_kinematics(m, s, t=t, bodies=bodies)


def _five_bar():
    """The planar five-bar of the drives' oracle test (tests/test_drives_oracle.py), its
    description and oracle parameters."""
    import tomllib

    import test_drives_oracle as tdo

    par, _, text, _, _, _ = tdo.five_bar_case(11, Path("."))
    return par, load_mechanism(tomllib.loads(text))


def test_a_motion_through_a_singularity_is_refused():
    """The five-bar's end point driven through a type II singularity (the distal links in line,
    the end point between the elbows; constructed from the oracle's geometry), its actuator
    motion with rates from the oracle's inverse kinematics: the direct kinematics refuses at
    the crossing, naming the sample, instead of reflecting onto the other assembly mode."""
    import dataclasses

    from oracles import five_bar

    par, m = _five_bar()
    A, l1, l2 = par.base, par.l1, par.l2
    ref = five_bar.inverse_kinematics(par, five_bar.DEFAULT_POSE)
    B1 = ref["B"][0, 0]
    span = l2[0] + l2[1]
    al = np.linspace(-np.pi, np.pi, 400001)  # directions d with |B1 + span d - A2| = l1_2
    f = np.linalg.norm(B1 + span * np.stack([np.cos(al), np.sin(al)], 1) - A[1], axis=1) - l1[1]
    found = False
    for k in np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:])):
        d = np.array([np.cos(al[k]), np.sin(al[k])])
        P_sing = B1 + l2[0] * d
        B2 = B1 + span * d
        cross = [np.cross(np.append(P_sing - A[i], 0), np.append(B - A[i], 0))[2] for i, B in enumerate((B1, B2))]
        par_k = dataclasses.replace(par, sigma=np.sign(cross))
        if not np.all(par_k.sigma == par.sigma):
            continue  # the description's elbows are on these branches
        found = True
        t = np.linspace(0.0, 1.0, 101)
        v = 0.04 * np.array([-d[1], d[0]])
        P = P_sing + (t[:, None] - 0.5) * v
        ik = five_bar.inverse_kinematics(par_k, P, np.tile(v, (len(t), 1)), np.zeros_like(P))
        assert np.all(np.isfinite(ik["q"])) and np.abs(ik["distal_sine"]).min() < 1e-3
        order = [m.actuator_names.index(f"A{i + 1}") for i in range(2)]
        s, sd, sdd = (np.empty((len(t), 2)) for _ in range(3))
        s[:, order], sd[:, order], sdd[:, order] = ik["q"], ik["qd"], ik["qdd"]
        start = solve_kinematics(m, P[:1]).q[0]  # the configuration of the motion's first pose
        with pytest.raises(SingularityError, match=r"sample (49|50|51) .*crosses a singularity"):
            direct_kinematics(m, s, sd, sdd, t, q_start=start)
        # up to the crossing the motion is followed exactly
        dk = direct_kinematics(m, s[:45], sd[:45], sdd[:45], t[:45], q_start=start)
        assert np.abs(dk.x - P[:45]).max() <= 1e-10
        # one sample at a time (the controller's route, on the tree coordinates here): the
        # same, not the pose turning back with the actuators onto the other assembly mode
        from pkmdyn.multibody.dynamics.verbs import machine_verbs

        from pkmdyn.multibody.kinematics.direct import prime_one

        V = machine_verbs(m)
        V.direct_one(m, s[0], sd[0])  # (from the reference pose: another mode) then from the motion's start
        assert not V._state(m).direct_task
        prime_one(V._state(m).direct[0], dk.q[0], dk.x[0], s[0], float(dk.det[0]))
        with pytest.raises(SingularityError, match="crossed a singularity"):
            for i in range(1, len(t)):
                got, _ = V.direct_one(m, s[i], sd[i])
                # exact away from the singularity; near it the pose the actuators give is
                # ill-conditioned, but it never turns back (a turned-back pose is a step away)
                assert np.abs(got - P[i]).max() <= (1e-9 if i < 45 else 1e-6)
        assert 47 <= i <= 53
    assert found


def test_five_bar_assembly_modes_are_the_two_circle_intersections():
    """At random reachable actuator angles the five-bar has exactly two assembly modes, the
    intersections of the circles of the distal links about the elbows (computed here from the
    oracle's elbows)."""
    from oracles import five_bar

    par, m = _five_bar()
    rng = np.random.default_rng(5)
    order = [m.actuator_names.index(f"A{i + 1}") for i in range(2)]
    for _ in range(3):
        P = five_bar.DEFAULT_POSE + rng.uniform(-0.03, 0.03, 2)
        ik = five_bar.inverse_kinematics(par, P)
        B = ik["B"][0]
        d = np.linalg.norm(B[1] - B[0])
        a = (l2_0 := par.l2[0]) ** 2 - par.l2[1] ** 2 + d * d
        a /= 2.0 * d
        h = np.sqrt(l2_0 ** 2 - a * a)
        e = (B[1] - B[0]) / d
        mid = B[0] + a * e
        both = [mid + h * np.array([-e[1], e[0]]), mid - h * np.array([-e[1], e[0]])]
        s = np.empty(2)
        s[order] = ik["q"][0]
        modes = assembly_modes(m, s, starts=200, seed=2)
        assert len(modes.modes) == 2
        got = sorted((a_.x for a_ in modes.modes), key=lambda v: v[0])
        want = sorted(both, key=lambda v: v[0])
        for g_, w_ in zip(got, want):
            assert np.abs(g_ - w_).max() <= 1e-9
        assert np.abs(modes.modes[0].x - P).max() <= 1e-9 or np.abs(modes.modes[1].x - P).max() <= 1e-9
        assert {a_.det_sign for a_ in modes.modes} == {-1, 1}  # the two modes lie on either side of a singularity


def test_bad_calls_are_refused_by_name():
    m = _model("stewart")
    with pytest.raises(MotionError, match="sample 3"):
        s = np.tile(actuator_reference(m), (5, 1))
        s[3, 2] = np.nan
        direct_kinematics(m, s)
    with pytest.raises(ParameterError, match="'P_9'"):
        parse_actuators(m, "P_1=1,P_2=1,P_3=1,P_4=1,P_5=1,P_9=1")
    with pytest.raises(ParameterError, match="'P_6': missing"):
        parse_actuators(m, "P_1=1,P_2=1,P_3=1,P_4=1,P_5=1")
    with pytest.raises(ParameterError, match="P_2: 'x' is not a number"):
        parse_actuators(m, "P_1=1,P_2=x")
    serial = load_mechanism(ex.serial_arm())
    if serial.na != serial.nt:
        with pytest.raises(ParameterError, match="as many actuated joints as degrees of freedom"):
            direct_kinematics(serial, np.zeros((1, serial.na)))


# ----------------------------------------------------------------------------- commands
def _stewart_lengths():
    m = _model("stewart")
    return m, ",".join(f"{a}={v:.12g}" for a, v in zip(m.actuator_names, actuator_reference(m) + 0.05))


@pytest.mark.parametrize("how", ["--starts", "--patience"])
def test_assemble_lists_verified_modes_and_writes_them(capsys, tmp_path, how):
    m, text = _stewart_lengths()
    out = tmp_path / "modes"
    code, stdout, err = _run(capsys, "assemble", "--machine", "stewart", "--actuators", text, how, 300,
                             "--out", out)
    assert code == 0, err
    doc = json.loads((out / "assemblies.json").read_text())
    if how == "--starts":  # exactly the starts asked, the reference configuration's among them
        assert doc["stopping_rule"] == {"kind": "fixed", "starts": 300} and doc["starts"] == 300
    else:  # until 300 starts in a row found no new mode
        assert doc["stopping_rule"] == {"kind": "no new mode in consecutive starts", "patience": 300}
        assert doc["starts"] - doc["last_new_mode_at_start"] >= 300
        assert f"starts: {doc['starts']:,} (until 300 starts in a row found no new mode" in stdout
    assert (out / "report.html").is_file()
    assert doc["mechanism"] == "stewart" and len(doc["modes"]) >= 2
    assert f"assembly modes found: {len(doc['modes'])}" in stdout
    for mode in doc["modes"]:
        assert mode["round_trip"] <= 1e-10
        x = np.array([mode["task"][f"{n}_{u}"] for n, u in zip(m.task_names, m.task_units)])
        s = solve_kinematics(m, x[None], q_start=np.array(list(mode["tree_coordinates"].values()))).act_q[0]
        assert np.abs(s - [doc["actuators"][a]["value"] for a in m.actuator_names]).max() <= 1e-10
    poses = np.array([[v for v in mode["task"].values()] for mode in doc["modes"]])
    assert len({tuple(np.round(p, 6)) for p in poses}) == len(poses)  # distinct
    # the report's slider counts modes as the table numbers them, not seconds from 0
    page = (out / "report.html").read_text(encoding="utf-8")
    slider = re.search(r'"currentvalue": ?\{"prefix": ?"([^"]*)", ?"suffix": ?"([^"]*)"', page)
    assert slider is not None and slider.groups() == ("mode = ", ""), slider
    labels = re.findall(r'"label": ?"([^"]*)", ?"value": ?"\d+", ?"method": ?"animate"', page)
    assert labels == [str(k) for k in range(1, len(doc["modes"]) + 1)]


@pytest.mark.parametrize("actuators, pattern", [
    ("P_1=1.0", "'P_3': missing"),
    ("P_1=1,P_2=1,P_3=1,P_4=1,P_5=1,P_6=1,Q=2", "'Q': not an actuated joint"),
    ("P_1=0.2,P_2=3,P_3=0.2,P_4=3,P_5=0.2,P_6=3", "reach no pose"),
])
def test_assemble_refusals_are_one_line(capsys, tmp_path, actuators, pattern):
    out = tmp_path / "o"
    code, _, err = _run(capsys, "assemble", "--machine", "stewart", "--actuators", actuators, "--starts", 50,
                        "--out", out)
    assert code == 2 and pattern in err and err.count("\n") == 1
    assert not out.exists()


def test_assemble_takes_a_count_or_a_stopping_rule_not_both(capsys):
    _, text = _stewart_lengths()
    code, _, err = _run(capsys, "assemble", "--machine", "stewart", "--actuators", text, "--starts", 100,
                        "--patience", 300)
    assert code == 2 and "--starts and --patience exclude each other" in err


def _write_actuator_motion(path, model, kin, rates=True):
    cols = {"t_s": kin.t}
    for i, (a, u) in enumerate(zip(model.actuator_names, model.actuator_units)):
        cols[f"{a}_pos_{u}"] = kin.act_q[:, i]
        if rates:
            cols[f"{a}_vel_{u}_s"] = kin.act_qd[:, i]
            cols[f"{a}_acc_{u}_s2"] = kin.act_qdd[:, i]
    data = np.stack(list(cols.values()), axis=1)
    np.savetxt(path, data, delimiter=",", header=",".join(cols), comments="", fmt="%.17g")


def _table(path):
    a = np.genfromtxt(path, delimiter=",", names=True)
    return {n: a[n] for n in a.dtype.names}


def test_run_from_an_actuator_motion_gives_the_task_motions_files(capsys, tmp_path):
    """The same motion given in task coordinates and in actuator coordinates (with rates): every
    column of results.csv agrees."""
    m = _model("stewart")
    t, x, xd, xdd = _smooth(m, n=120)
    kin = solve_kinematics(m, x, xd, xdd, t)
    task = tmp_path / "task.csv"
    cols = ["t_s"] + [f"{n}_{u}" for n, u in zip(m.task_names, m.task_units)] \
        + [f"{n}d_{u}_s" for n, u in zip(m.task_names, m.task_units)] \
        + [f"{n}dd_{u}_s2" for n, u in zip(m.task_names, m.task_units)]
    np.savetxt(task, np.column_stack([t, x, xd, xdd]), delimiter=",", header=",".join(cols), comments="", fmt="%.17g")
    act = tmp_path / "act.csv"
    _write_actuator_motion(act, m, kin)
    assert _run(capsys, "run", "--machine", "stewart", "--motion", task, "--out", tmp_path / "a")[0] == 0
    code, _, err = _run(capsys, "run", "--machine", "stewart", "--actuator-motion", act, "--out", tmp_path / "b")
    assert code == 0, err
    a, b = _table(tmp_path / "a" / "results.csv"), _table(tmp_path / "b" / "results.csv")
    assert a.keys() == b.keys()
    for k in a:
        assert np.abs(a[k] - b[k]).max() <= 1e-8 * max(np.abs(a[k]).max(), 1e-9), k


def test_run_from_actuator_positions_alone_differentiates_them(capsys, tmp_path):
    """Positions only: the rates by the smoothing differentiator (default) or the spline
    (--sg-window 0); the poses are exact either way and the rates close to the motion's."""
    m = _model("rrr3")
    t, x, xd, xdd = _smooth(m, n=400)
    kin = solve_kinematics(m, x, xd, xdd, t)
    act = tmp_path / "act.csv"
    _write_actuator_motion(act, m, kin, rates=False)
    for window, out in (("15", "sg"), ("0", "spline")):
        code, _, err = _run(capsys, "run", "--machine", "rrr3", "--actuator-motion", act, "--sg-window", window,
                            "--out", tmp_path / out)
        assert code == 0, err
        r = _table(tmp_path / out / "results.csv")
        for i, (n, u) in enumerate(zip(m.task_names, m.task_units)):
            assert np.abs(r[f"{n}_{u}"] - x[:, i]).max() <= 1e-10 * m.length_scale
        for i, (a, u) in enumerate(zip(m.actuator_names, m.actuator_units)):
            assert np.abs(r[f"{a}_vel_{u}_s"] - kin.act_qd[:, i]).max() <= 1e-3 * np.abs(kin.act_qd).max()


@pytest.mark.parametrize("edit, pattern", [
    (lambda rows: rows[:3] + [rows[4], rows[3]] + rows[5:], "row 4, column 't_s'"),
    (lambda rows: [rows[0].replace("P_1_pos_m", "P_7_pos_m")] + rows[1:], "P_7_pos_m"),
    (lambda rows: [",".join(rows[0].split(",")[:-3])] + [",".join(r.split(",")[:-3]) for r in rows[1:]],
     "P_6_pos_m"),
])
def test_bad_actuator_motion_files_are_one_line(capsys, tmp_path, edit, pattern):
    m = _model("stewart")
    t, x, xd, xdd = _smooth(m, n=40)
    kin = solve_kinematics(m, x, xd, xdd, t)
    act = tmp_path / "act.csv"
    _write_actuator_motion(act, m, kin)
    lines = act.read_text().splitlines()
    act.write_text("\n".join(edit(lines)) + "\n")
    code, _, err = _run(capsys, "run", "--machine", "stewart", "--actuator-motion", act, "--out", tmp_path / "o")
    assert code == 2 and pattern in err and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()


def test_an_unreachable_actuator_motion_writes_nothing(capsys, tmp_path):
    m = _model("stewart")
    t, x, xd, xdd = _smooth(m, n=60)
    kin = solve_kinematics(m, x, xd, xdd, t)
    s = kin.act_q.copy()
    s[40:, 0] += 2.0
    k2 = type(kin)(**{**kin.__dict__, "act_q": s})
    act = tmp_path / "act.csv"
    _write_actuator_motion(act, m, k2)
    code, _, err = _run(capsys, "run", "--machine", "stewart", "--actuator-motion", act, "--out", tmp_path / "o")
    assert code == 2 and "sample 40" in err and "actuator '" in err and err.count("\n") == 1, err
    assert not (tmp_path / "o").exists()


# ----------------------------------------------------------------------------- planar 3-RPR against its polynomial
def _rpr3_description(par, pose):
    """A planar 3-RPR (tests/oracles/rpr3.py) as a description in the x-y plane: per leg a
    cylinder turning about the base point A_i, a rod sliding in it (the actuated prismatic
    joint, its coordinate the leg length) and a revolute joint at the platform point C_i; the
    task the platform's position and its turn about z, the oracle's pose."""
    x0, y0, phi0 = pose
    c, s = np.cos(phi0), np.sin(phi0)
    C = np.array([[x0 + c * b[0] - s * b[1], y0 + s * b[0] + c * b[1]] for b in par.b])
    bodies = [{"name": "platform", "mass_kg": 1.0, "com_m": [x0, y0, 0.0],
               "inertia_kgm2": [0.01, 0.01, 0.02, 0.0, 0.0, 0.0]}]
    joints = []
    for i in range(3):
        A = par.A[i]
        d = C[i] - A
        rho = float(np.hypot(*d))
        u = d / rho
        bodies += [{"name": f"cylinder_{i + 1}", "mass_kg": 0.5, "com_m": [*(A + 0.25 * d), 0.0],
                    "inertia_kgm2": [0.001, 0.001, 0.001, 0.0, 0.0, 0.0]},
                   {"name": f"rod_{i + 1}", "mass_kg": 0.3, "com_m": [*(A + 0.75 * d), 0.0],
                    "inertia_kgm2": [0.001, 0.001, 0.001, 0.0, 0.0, 0.0]}]
        joints += [{"name": f"RA_{i + 1}", "type": "revolute", "parent": "ground", "child": f"cylinder_{i + 1}",
                    "point_m": [*A, 0.0], "axis": [0.0, 0.0, 1.0]},
                   {"name": f"P_{i + 1}", "type": "prismatic", "parent": f"cylinder_{i + 1}", "child": f"rod_{i + 1}",
                    "point_m": [*A, 0.0], "axis": [*u, 0.0], "actuated": True, "position_at_reference_m": rho},
                   {"name": f"RC_{i + 1}", "type": "revolute", "parent": f"rod_{i + 1}", "child": "platform",
                    "point_m": [*C[i], 0.0], "axis": [0.0, 0.0, 1.0]}]
    return {"mechanism": {"name": "rpr3", "gravity_m_s2": [0.0, 0.0, -9.80665]}, "bodies": bodies, "joints": joints,
            "task": {"body": "platform", "point_m": [x0, y0, 0.0], "position": ["x", "y"], "euler_sequence": "ZYX",
                     "orientation": [1]}}


def _rpr3_case(geometry=None):
    from oracles import rpr3

    par = rpr3.default_rpr3() if geometry is None else geometry
    m = load_mechanism(_rpr3_description(par, rpr3.DEFAULT_POSE))
    order = [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    return rpr3, par, m, order


def test_rpr3_pose_and_rates_from_the_leg_lengths():
    rpr3, par, m, order = _rpr3_case()
    t = np.linspace(0.0, 1.0, 150)
    amp = np.array([0.03, 0.02, 0.2])
    w = np.array([3.0, 4.0, 2.5])
    pose = rpr3.DEFAULT_POSE + amp * np.sin(w * t[:, None])
    pose_d = amp * w * np.cos(w * t[:, None])
    ik = rpr3.inverse_kinematics(par, pose)
    s, sd = np.empty((len(t), 3)), np.empty((len(t), 3))
    s[:, order] = ik["rho"]
    sd[:, order] = np.einsum("nij,nj->ni", ik["J"], pose_d)
    dk = direct_kinematics(m, s, sd, None, t)
    assert np.abs(dk.x - pose).max() <= 1e-10
    assert np.abs(dk.xd - pose_d).max() <= 1e-8 * np.abs(pose_d).max()


@pytest.mark.parametrize("rho", [None, (0.758, 0.214, 0.775), "random"])
def test_rpr3_assembly_modes_are_the_real_roots_of_its_polynomial(rho):
    """Every real assembly mode of the planar 3-RPR (the oracle's sextic of Gosselin, Sefrioui
    and Richard, every real root refined) is found, each once, and nothing else."""
    rpr3, par, m, order = _rpr3_case()
    cases = []
    if rho is None:
        cases.append(rpr3.inverse_kinematics(par, rpr3.DEFAULT_POSE[None])["rho"][0])
    elif rho == "random":
        rng = np.random.default_rng(8)
        for _ in range(2):
            p = rpr3.DEFAULT_POSE + rng.uniform([-0.1, -0.1, -1.0], [0.1, 0.1, 1.0])
            cases.append(rpr3.inverse_kinematics(par, p[None])["rho"][0])
    else:
        cases.append(np.array(rho))
    for r in cases:
        want = rpr3.forward_kinematics(par, r)
        assert len(want) >= 2
        s = np.empty(3)
        s[order] = r
        got = assembly_modes(m, s, starts=1500, seed=3)
        assert len(got.modes) == len(want), (r, [a.x for a in got.modes], want)
        for w_ in want:
            d = [max(np.abs(a.x[:2] - w_[:2]).max(), abs((a.x[2] - w_[2] + np.pi) % (2 * np.pi) - np.pi))
                 for a in got.modes]
            assert min(d) <= 1e-9, (w_, d)


def test_rpr3_with_six_real_assembly_modes():
    """A geometry with six real modes (the constructed case of tests/oracles/test_oracles.py,
    confirmed there by an independent scan): all six found, described at one of them."""
    from oracles import rpr3

    par = rpr3.RPR3(A=[[0.0, 0.0], [0.7, 0.05], [0.2, 0.55]], b=[[-0.25, -0.12], [0.2, -0.1], [0.05, 0.25]])
    rho = np.array([0.55, 0.288, 0.611])
    want = rpr3.forward_kinematics(par, rho)
    assert len(want) == 6
    m = load_mechanism(_rpr3_description(par, want[0]))
    order = [m.actuator_names.index(f"P_{i + 1}") for i in range(3)]
    s = np.empty(3)
    s[order] = rho
    got = assembly_modes(m, s, starts=3000, seed=4)
    assert len(got.modes) == 6
    # the description's reference pose is want[0]: its task angle is measured from there
    for w_ in want:
        d = [max(np.abs(a.x[:2] - w_[:2]).max(), abs((a.x[2] + want[0][2] - w_[2] + np.pi) % (2 * np.pi) - np.pi))
             for a in got.modes]
        assert min(d) <= 1e-9, (w_, d)


def test_the_default_search_stops_when_no_new_mode_comes():
    """Without a count the search starts until ``patience`` consecutive starts found no new mode:
    all six modes of the six-mode 3-RPR, the rule and where it stopped reported; a fixed count is
    exactly the starts tried (the reference configuration and the continuation among them)."""
    from oracles import rpr3

    par = rpr3.RPR3(A=[[0.0, 0.0], [0.7, 0.05], [0.2, 0.55]], b=[[-0.25, -0.12], [0.2, -0.1], [0.05, 0.25]])
    rho = np.array([0.55, 0.288, 0.611])
    want = rpr3.forward_kinematics(par, rho)
    m = load_mechanism(_rpr3_description(par, want[0]))
    s = np.empty(3)
    s[[m.actuator_names.index(f"P_{i + 1}") for i in range(3)]] = rho
    got = assembly_modes(m, s, seed=4)
    assert len(got.modes) == 6 and got.patience == 5000
    assert 1 <= got.last_new_mode_at and got.starts - got.last_new_mode_at >= 5000
    assert sum(a.hits for a in got.modes) <= got.converged <= got.starts
    assert got.starts == got.last_new_mode_at + 5000  # stops at the start the rule names
    short = assembly_modes(m, s, seed=4, patience=20)
    assert short.starts == short.last_new_mode_at + 20 and short.starts < got.starts
    for n in (1, 2, 3, 1234):
        fixed = assembly_modes(m, s, starts=n, seed=4)
        assert fixed.starts == n and fixed.patience is None
    with pytest.raises(ParameterError, match="patience: expected an integer from 1"):
        assembly_modes(m, s, patience=0)


def test_a_seed_gives_the_same_search_whatever_the_calls_sizes(monkeypatch):
    """The compiled calls are sized by the clock (a quarter second each); the starts are drawn in
    one order regardless, so a seed gives the same modes, hits and stopping start on a fast or a
    loaded machine."""
    import pkmdyn.multibody.kinematics.direct as direct

    m = _model("stewart")
    s = actuator_reference(m) + 0.03

    def search(call_s, **kw):
        monkeypatch.setattr(direct, "_CALL_S", call_s)
        a = assembly_modes(m, s, seed=7, **kw)
        return a.starts, a.converged, a.last_new_mode_at, [(x.hits, tuple(np.round(x.x, 9))) for x in a.modes]

    assert search(0.25, patience=600) == search(1e-4, patience=600)
    assert search(0.25, starts=900) == search(1e-4, starts=900)


def test_one_sample_at_a_time_refuses_a_crossing_instead_of_turning_back():
    """The Stewart platform turned about its vertical axis through the singularity where the
    inverse kinematics' Jacobian ``d(legs)/d(pose)`` changes sign (found here from that
    Jacobian alone). The legs' lengths turn back there, so the same lengths also belong to the
    pose turning back on the other assembly mode: the controller's route (``direct_one``, in
    task space for this platform) follows the motion up to the crossing and then refuses with
    a singularity error, instead of returning the turned-back pose."""
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = _model("stewart")
    n = 801
    t = np.linspace(0.0, 1.0, n)
    x = np.tile(reference_task(m), (n, 1))
    x[:, 5] = np.linspace(0.0, 2.0, n)
    xd = np.zeros_like(x)
    xd[:, 5] = 2.0
    kin = solve_kinematics(m, x, xd, np.zeros_like(x), t)
    det = np.linalg.det(kin.G[:, m.act_coord, :])
    k = np.flatnonzero(np.sign(det[:-1]) != np.sign(det[1:]))
    assert k.size == 1 and 100 < k[0] < n - 100
    V = machine_verbs(m)
    for i in range(k[0] + 1):
        got, _ = V.direct_one(m, kin.act_q[i], kin.act_qd[i])
        assert np.abs(got - x[i]).max() <= 1e-9
    assert V._state(m).direct_task
    with pytest.raises(SingularityError, match="crossed a singularity"):
        for i in range(k[0] + 1, k[0] + 4):
            V.direct_one(m, kin.act_q[i], kin.act_qd[i])


@pytest.mark.parametrize("leg", ["RUS", "UPS"])
def test_one_sample_at_a_time_after_large_jumps(leg):
    """A platform whose legs are turned by an arbitrary rotation, its actuators jumping from a
    pose near the reference to one far from it (each pose's actuators from the inverse
    kinematics continued from the reference pose; pairs out of reach left out): the controller's
    route gives the far pose (a move too large for one call is followed in smaller steps)."""
    from test_explicit_legs import _rot, platform

    from pkmdyn.errors import UnreachablePoseError
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = load_mechanism(platform(leg, _rot([0.3, -0.8, 0.5], 2.1)))
    x0 = reference_task(m)
    scale = np.where(m.task_kind == 0, m.length_scale, 1.0)
    rng = np.random.default_rng(3)
    tt = np.linspace(0.0, 1.0, 60)

    def actuators(xb):
        path = x0 + tt[:, None] * (xb - x0)
        k = solve_kinematics(m, path, np.tile(xb - x0, (60, 1)), np.zeros_like(path), tt)
        return k.act_q[-1], k.act_qd[-1]

    done = 0
    for _ in range(80):
        xa = x0 + rng.uniform(-1, 1, 6) * 0.03 * scale
        xb = x0 + rng.uniform(-1, 1, 6) * 0.15 * scale
        try:
            (aa, ada), (ab, adb) = actuators(xa), actuators(xb)
        except UnreachablePoseError:
            continue
        V = machine_verbs(m)
        V.direct_one(m, aa, ada)
        V.direct_one(m, aa + 1e-4 * ada, ada)
        got, _ = V.direct_one(m, ab, adb)
        assert np.abs((got - xb) / scale).max() <= 1e-9
        assert V._state(m).direct_task
        done += 1
    assert done >= 10


@pytest.mark.parametrize("leg, axis", [("RUS", 2), ("PUS", 0)])
def test_one_sample_at_a_time_through_a_legs_own_singularity(leg, axis):
    """A platform (legs turned by an arbitrary rotation) moved along one task coordinate until
    one leg folds (a singularity of that leg alone: the pose can go no further there), then
    back, the leg's actuated coordinate moving on through the fold: an R-U-S leg whose crank
    lines up with its rod, moved along the third coordinate; a P-U-S leg whose rod comes
    normal to its slide, moved along the first. The direct kinematics is regular there: the
    controller's route follows every sample, with no singularity error (the Jacobian of the
    actuators changes sign through infinity there, the branch measure must not)."""
    from test_explicit_legs import _rot, platform

    from pkmdyn.multibody.kinematics.inverse import loop_residuals
    from pkmdyn.multibody.model.legs import place
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = load_mechanism(platform(leg, _rot([0.3, -0.8, 0.5], 2.1)))
    x0 = reference_task(m)
    d = np.zeros(6)
    d[axis] = 1.0

    def reach(q, al):
        qn = place(m, q, x0 + al * d)
        return qn if np.abs(loop_residuals(m, qn[None])).max() < 1e-10 else None

    q, al, step = place(m, m.coord_offset.copy(), x0), 0.0, 0.01
    while step > 1e-13:  # the fold: the farthest pose the legs' closed forms reach along d
        qn = reach(q, al + step)
        if qn is None:
            step /= 2
        else:
            q, al = qn, al + step
        assert al < 1.0
    qa = reach(q, al - 1e-4)
    i_fold = int(np.argmax(np.abs(qa[m.act_coord] - reach(qa, al - 2e-4)[m.act_coord])))
    c, th_star = m.act_coord[i_fold], q[m.act_coord[i_fold]]
    taus = np.linspace(-1.0, 1.0, 80)
    X = np.array([x0 + (al - 0.02 * t**2) * d for t in taus])
    qq = m.coord_offset.copy()
    for a_ in np.linspace(0.0, 1.0, 50):
        qq = place(m, qq, x0 + a_ * (X[0] - x0))
    Qs = []
    for j in range(40):
        qq = place(m, qq, X[j])
        Qs.append(qq.copy())
    for j in range(40, 80):  # back along the same poses, the folding crank mirrored past the fold
        qm = Qs[79 - j].copy()
        qm[c] = 2.0 * th_star - qm[c]
        Qs.append(place(m, qm, X[j]))
    S = np.array(Qs)[:, m.act_coord]
    assert np.all(np.diff(S[:, i_fold]) * np.sign(S[-1, i_fold] - S[0, i_fold]) > 0)  # the crank turns on
    SD = np.gradient(S, taus, axis=0)
    V = machine_verbs(m)
    for j in range(80):
        got, _ = V.direct_one(m, S[j], SD[j])
        assert np.abs(got - X[j]).max() <= 1e-9
    assert V._state(m).direct_task


@pytest.mark.parametrize("name", ["stewart", "hip", "UPS", "RUS", "PUS"])
def test_task_route_by_the_actuated_coordinates_alone_matches_every_leg_placed(name):
    """The task-space route of one sample takes each actuated coordinate and its row of the
    Jacobian from the task alone where the coordinate is the one its leg's closed form gives
    first (A2's first joint, B2's slide), placing the legs' other coordinates only now and
    then. Along a smooth motion of legs of every such kind (turned by an arbitrary rotation),
    it gives the poses, rates and branch signs of the same route placing every leg at every
    call (its branch measure up to one sign: its legs' factors are those of ``det J_L`` that the
    actuated coordinates bring), the motion's poses back, and, after its last placement, every
    coordinate of those legs as the inverse kinematics gives it."""
    from test_explicit_legs import _rot, platform

    from pkmdyn.multibody.kinematics import _direct_kernels as D
    from pkmdyn.multibody.dynamics import _sample_kernels as _one
    from pkmdyn.multibody.kinematics.direct import pack_task, prime_task, task_state

    turn = _rot([0.3, -0.8, 0.5], 2.1)
    if name in ("stewart", "hip"):
        m = _model(name)
    else:
        m = load_mechanism(platform(name, turn))
    n = 1 + 25 * D.TASK_REFRESH  # the last call places every leg
    t, x, xd, _ = _smooth(m, n=n, seed=5, size=0.5)
    kin = solve_kinematics(m, x, xd, np.zeros_like(x), t)
    pk = _one.pack(m)
    alone = pack_task(m)
    flag = alone.view(np.float64)[alone[24]:alone[24] + 1]  # part 24: [alone, calls since placed]
    assert flag[0] == 1.0
    every = alone.copy()
    every.view(np.float64)[every[24]] = 0.0
    outs = {}
    for key, d in (("alone", alone), ("every", every)):
        prime_task(d, kin.q[0], x[0], kin.act_q[0])
        out, got, dets = np.zeros(2 * m.nt), [], []
        for i in range(1, n):
            # (contiguous rows, as the verbs pass them: the kernel compiled for no other signature)
            s_i, sd_i = np.ascontiguousarray(kin.act_q[i]), np.ascontiguousarray(kin.act_qd[i])
            assert D.direct_task_one(pk, d, s_i, sd_i, out) == D.OK, (key, i)
            got.append(out.copy())
            dets.append(float(task_state(d)[1]))
        outs[key] = (np.array(got), np.sign(dets), d.view(np.float64)[d[7]:d[7] + m.nq].copy())
    sc = np.concatenate([_scaled(m), _scaled(m)])
    rate = np.abs(xd * _scaled(m)).max()
    a, e = outs["alone"][0], outs["every"][0]
    assert np.abs((a - e)[:, :m.nt] * sc[:m.nt]).max() <= 1e-12
    assert np.abs((a - e)[:, m.nt:] * sc[m.nt:]).max() <= 1e-10 * rate
    assert np.abs((a[:, :m.nt] - x[1:]) * _scaled(m)).max() <= 1e-9
    prod = outs["alone"][1] * outs["every"][1]  # the two branch measures differ by a factor of one sign
    assert np.all(prod == prod[0])
    legs = m.legs.fixed_coord != 0
    assert legs[m.act_coord].all() and legs.sum() > m.na
    dq = (outs["alone"][2] - kin.q[-1])[legs]
    turns = m.coord_motion[legs] < 3
    dq[turns] = (dq[turns] + np.pi) % (2 * np.pi) - np.pi
    dq[~turns] /= m.length_scale
    assert np.abs(dq).max() <= 1e-9


def test_task_route_by_the_actuated_coordinates_alone_only_where_the_joint_reaches_every_direction():
    """A U-P-S platform whose universal joints' second axes lean 18 deg towards the rod: a leg
    length in reach may then be a direction the joint cannot take, which the actuated
    coordinate alone does not tell; the task route then places every leg (and says where a
    leg is out of reach). The same platform with square joints takes the route by the actuated
    coordinates alone."""
    from test_explicit_legs import _unit, platform

    from pkmdyn.multibody.kinematics.direct import pack_task

    def flag(desc):
        d = pack_task(load_mechanism(desc))
        return d.view(np.float64)[d[24]]

    assert flag(platform("UPS")) == 1.0
    desc = platform("UPS")
    for j in desc["joints"]:
        if j["type"] == "universal":
            a1, a2 = np.array(j["axes"][0]), np.array(j["axes"][1])
            j["axes"][1] = [float(v) for v in _unit(a2 + 3.0 * _unit(np.cross(a1, a2)))]
    assert flag(desc) == 0.0


@pytest.mark.parametrize("name", ["stewart", "delta", "hip"])
def test_direct_one_primed_at_a_known_pose_starts_from_it(name, monkeypatch):
    """``prime_direct`` at a pose away from the reference configuration (the pose a run starts
    from, whose actuated coordinates the encoders solved): the next ``direct_one`` calls answer
    by the single-sample kernel alone (the checked route, which solves from the reference
    configuration, is never taken) and follow a motion from there: the poses of the motion the
    actuator values came from, and its rates."""
    from pkmdyn.multibody.dynamics import verbs as verbs_module
    from pkmdyn.multibody.dynamics.verbs import machine_verbs

    m = _model(name)
    t, x, xd, xdd = _smooth(m, n=60, seed=5)
    V = machine_verbs(m)
    kin = solve_kinematics(m, x, xd, xdd, t)
    V.actuator_coordinates_one(m, x[10], np.zeros(m.nt), fresh=True)

    def refused(*args, **kwargs):
        raise AssertionError("the checked route was taken")

    monkeypatch.setattr(verbs_module, "_direct_checked", refused)
    V.prime_direct(m, x[10])
    sc = _scaled(m)
    for k in range(10, 60):
        pose, rate = V.direct_one(m, kin.act_q[k], kin.act_qd[k])
        assert np.abs((pose - x[k]) * sc).max() <= 1e-10
        assert np.abs((rate - xd[k]) * sc).max() <= 1e-8 * max(1.0, float(np.abs(xd * sc).max()))

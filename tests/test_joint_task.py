"""A task made of joint coordinates (``[task] joints``): a mechanism whose freedoms no single
body carries (two legs, each closed by its own loop).

Oracles, written apart from the engine's task rows:

* a second route: the same physical motion described by a body's task (the crank's angle)
  and by a passive joint's coordinate (the four-bar's coupler-rocker joint, its coordinate
  read from the first route's solution) gives the same tree coordinates, rates,
  accelerations and efforts;
* finite differences: the joint task's rates and accelerations against central differences
  of the solved coordinates;
* the power balance on two legs: the actuators' power against the time derivative of the
  kinetic and potential energy, both computed here from the bodies' motion;
* the import of a two-legged MJCF model (no body carries both legs' freedoms) falls back on
  the joints' coordinates and runs on built-in defaults, an under-actuated one (a sprung
  joint) with its passive freedom simulated.
"""

from __future__ import annotations

import copy
import csv
import json
import tomllib

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics


def _two_legs(task_joints=("A_L", "A_R")):
    """Two four-bars (tests/multibody_examples.py's points), one in the plane z = 0.3, the other
    shifted 3 m along x; each crank actuated."""
    base = ex.four_bar()
    bodies, joints = [], []
    for side, dx in (("L", 0.0), ("R", 3.0)):
        for b in base["bodies"]:
            nb = copy.deepcopy(b)
            nb["name"] = f"{b['name']}_{side}"
            nb["com_m"] = [b["com_m"][0] + dx, b["com_m"][1], b["com_m"][2]]
            bodies.append(nb)
        for j in base["joints"]:
            nj = copy.deepcopy(j)
            nj["name"] = f"{j['name']}_{side}"
            nj["parent"] = j["parent"] if j["parent"] == "ground" else f"{j['parent']}_{side}"
            nj["child"] = j["child"] if j["child"] == "ground" else f"{j['child']}_{side}"
            nj["point_m"] = [j["point_m"][0] + dx, j["point_m"][1], j["point_m"][2]]
            joints.append(nj)
    d = {"mechanism": {"name": "two_legs", "gravity_m_s2": [0.0, -9.81, 0.0]}, "bodies": bodies, "joints": joints,
         "task": {"joints": list(task_joints)}}
    return d


def _motion(m, t, amp=0.3):
    x0 = reference_task(m)
    w = 2 * np.pi / 1.5
    ph = np.arange(m.nt)
    x = x0 + amp * np.sin(w * t[:, None] + ph)
    xd = amp * w * np.cos(w * t[:, None] + ph)
    xdd = -amp * w * w * np.sin(w * t[:, None] + ph)
    return x, xd, xdd


#: (description, the joint task's table, the body task's coordinates it keeps): a passive joint
#: with the task body elsewhere; a joint the tree reaches backwards (a flipped coordinate); a joint
#: whose child is the ground (the default task body its parent); a prismatic joint; the Stewart
#: platform with a leg's length in place of its third angle (a mixed task)
def _cut_at(make, joint):
    def made():
        d = make()
        d["mechanism"]["cut_joints"] = [joint]  # the joint of the task a tree joint of the body route too
        return d
    return made


ROUTES = [
    (ex.four_bar, {"body": "crank", "joints": ["C"]}, []),
    (ex.four_bar_cut_b, {"joints": ["C"]}, []),
    (_cut_at(ex.four_bar, "C"), {"joints": ["D"]}, []),
    (_cut_at(ex.slider_crank, "C"), {"joints": ["D"]}, []),
    (lambda: ex.builtin_dict("stewart"),
     {"body": "platform", "point_m": [0.0, 0.0, 1.0], "position": ["x", "y", "z"], "orientation": [1, 2],
      "joints": ["P_6"]}, [0, 1, 2, 3, 4]),
    (lambda: ex.builtin_dict("stewart"),  # a universal joint's second angle: one coordinate of two
     {"body": "platform", "point_m": [0.0, 0.0, 1.0], "position": ["x", "y", "z"], "orientation": [1, 2],
      "joints": ["U_6:2"]}, [0, 1, 2, 3, 4]),
    (ex.stewart_flipped_spheres,  # a ball the tree reaches from its child: its angles reversed
     {"body": "platform", "point_m": [0.0, 0.0, 1.0], "position": ["x", "y", "z"], "orientation": [1, 2],
      "joints": ["S_1:1"]}, [0, 1, 2, 3, 4]),
]


def _coordinate(m, item):
    """The tree coordinate of a ``[task] joints`` entry, found here from the joint's place in
    the tree (its coordinates reversed where the tree reaches it from its child)."""
    name, _, k = item.partition(":")
    j = m.joint_names.index(name)
    i = int(k) - 1 if k else 0
    n = int(m.joint_nq[j])
    return int(m.joint_q0[j]) + (n - 1 - i if m.joint_flipped[j] else i)


@pytest.mark.parametrize("make, task, kept", ROUTES)
def test_a_joint_task_follows_the_body_task_route(make, task, kept):
    """The motion solved with the description's own (body) task; the joints' coordinates (and
    the body coordinates ``kept``) of that solution, with their rates and accelerations, given
    as the task of the same mechanism: the same tree coordinates, rates, accelerations and
    efforts."""
    d_body = make()
    d_joint = make()
    d_joint["task"] = task
    d_joint.pop("default_motion", None)  # (keyed by the body task's columns)
    mb, mj = load_mechanism(d_body), load_mechanism(d_joint)
    assert list(mj.task_kind) == [0, 0, 0, 1, 1, 2][-mj.nt:] if kept else list(mj.task_kind) == [2]
    t = np.linspace(0.0, 1.0, 41)
    x, xd, xdd = _motion(mb, t, 0.05 if mb.nt == 6 else 0.15)  # (the four-bar's rocker: no dead point)
    kb = solve_kinematics(mb, x, xd, xdd, t)
    assert mb.joint_names == mj.joint_names and mb.nq == mj.nq
    cols = [_coordinate(mb, item) for item in task["joints"]]
    assert not any(mb.joint_cut[mb.joint_names.index(item.partition(":")[0])] for item in task["joints"])
    xj = np.concatenate([kb.x[:, kept], kb.q[:, cols]], axis=1)
    xdj = np.concatenate([kb.xd[:, kept], kb.qd[:, cols]], axis=1)
    xddj = np.concatenate([kb.xdd[:, kept], kb.qdd[:, cols]], axis=1)
    kj = solve_kinematics(mj, xj, xdj, xddj, t)
    # the coordinates of the joints both trees hold (the task's joints enter the tree first, so the
    # cut may differ), joint by joint
    both = [k for k in range(len(mb.joint_names)) if not mb.joint_cut[k] and not mj.joint_cut[k]]
    assert len(both) >= int(np.sum(~mb.joint_cut)) - 1

    def by_joint(m, a):
        return np.concatenate([a[:, m.joint_q0[k]:m.joint_q0[k] + m.joint_nq[k]] for k in both], axis=1)
    np.testing.assert_allclose(by_joint(mj, kj.q), by_joint(mb, kb.q), atol=1e-9)
    np.testing.assert_allclose(by_joint(mj, kj.qd), by_joint(mb, kb.qd), atol=1e-8)
    np.testing.assert_allclose(by_joint(mj, kj.qdd), by_joint(mb, kb.qdd), atol=1e-6)
    np.testing.assert_allclose(kj.x, xj, atol=1e-12)
    ub, uj = inverse_dynamics(mb, kb).u, inverse_dynamics(mj, kj).u
    np.testing.assert_allclose(uj, ub, rtol=1e-7, atol=1e-8 * np.abs(ub).max())


def test_the_joint_tasks_rates_and_accelerations_match_finite_differences():
    m = load_mechanism(_two_legs(("C_L", "B_R")))
    h = 1e-4
    tc = np.linspace(0.1, 0.9, 5)
    t = (tc[:, None] + h * np.array([-1.0, 0.0, 1.0])).reshape(-1)
    x, xd, xdd = _motion(m, t, 0.25)
    k = solve_kinematics(m, x, xd, xdd, t)
    q = k.q.reshape(len(tc), 3, -1)
    qd = k.qd.reshape(len(tc), 3, -1)
    fd_qd = (q[:, 2] - q[:, 0]) / (2 * h)
    fd_qdd = (qd[:, 2] - qd[:, 0]) / (2 * h)
    scale_v = np.abs(qd[:, 1]).max()
    scale_a = np.abs(k.qdd).max()
    assert scale_v > 0.1 and scale_a > 0.1
    np.testing.assert_allclose(qd[:, 1], fd_qd, atol=1e-5 * scale_v)
    np.testing.assert_allclose(k.qdd.reshape(len(tc), 3, -1)[:, 1], fd_qdd, atol=1e-5 * scale_a)
    # the task coordinates are the joints' own coordinates
    for i, nm in enumerate(("C_L", "B_R")):
        c = int(m.joint_q0[m.joint_names.index(nm)])
        np.testing.assert_allclose(k.x[:, i], k.q[:, c], atol=1e-12)


def _energy(m, k):
    """Kinetic and gravity's potential energy from the bodies' motion (computed here)."""
    T = np.zeros(len(k))
    V = np.zeros(len(k))
    for b in range(m.nb):
        I = np.einsum("nij,jk,nlk->nil", k.R[:, b], m.inertia[b], k.R[:, b])
        T += 0.5 * m.mass[b] * np.einsum("ni,ni->n", k.v[:, b], k.v[:, b])
        T += 0.5 * np.einsum("ni,nij,nj->n", k.w[:, b], I, k.w[:, b])
        V -= m.mass[b] * k.p[:, b] @ m.gravity
    return T + V


def test_two_legs_the_power_balance_holds():
    m = load_mechanism(_two_legs(("A_L", "C_R")))
    h = 2e-4
    tc = np.linspace(0.05, 1.2, 9)
    t = (tc[:, None] + h * np.array([-2, -1, 0, 1, 2])[None]).reshape(-1)
    x, xd, xdd = _motion(m, t, 0.3)
    k = solve_kinematics(m, x, xd, xdd, t)
    E = _energy(m, k).reshape(-1, 5)
    dE = (E[:, 0] - 8 * E[:, 1] + 8 * E[:, 3] - E[:, 4]) / (12 * h)
    u = inverse_dynamics(m, k).u
    P = np.einsum("na,na->n", u, k.act_qd).reshape(-1, 5)[:, 2]
    assert np.abs(P).max() > 0.1
    assert np.abs(P - dE).max() <= 1e-6 * np.abs(P).max()


@pytest.mark.parametrize("task, words", [
    ({"joints": ["nope"]}, "joints[0]: 'nope' is not a joint"),
    ({"joints": ["A_L", "A_L"]}, "named twice"),
    ({"position": ["x"]}, "body: missing"),
])
def test_bad_joint_tasks_are_refused_by_name(task, words):
    d = _two_legs()
    d["task"] = task
    with pytest.raises(ParameterError, match=words.replace("[", r"\[").replace("]", r"\]")):
        load_mechanism(d)


def test_a_ball_joint_or_a_cut_joint_is_refused_as_a_task_coordinate():
    d = ex.rssr()
    d["task"] = {"joints": ["S1"]}
    with pytest.raises(ParameterError, match=r"joints\[0\]: 'S1' is a spherical joint of 3 coordinates; name one of "
                                             r"them, 'S1:1' \.\.\. 'S1:3'"):
        load_mechanism(d)
    d["task"] = {"joints": ["S1:4"]}
    with pytest.raises(ParameterError, match=r"joints\[0\]: 'S1:4': joint 'S1' has 3 coordinate"):
        load_mechanism(d)
    d["task"] = {"joints": ["S1:2", "S1:2"]}
    with pytest.raises(ParameterError, match="a joint coordinate is named twice"):
        load_mechanism(d)
    d = ex.four_bar()
    d["mechanism"]["cut_joints"] = ["C"]
    d["task"] = {"body": "crank", "joints": ["C"]}
    with pytest.raises(ParameterError, match="'C' is a loop's cut joint"):
        load_mechanism(d)


def test_the_stiffness_asks_for_a_body_task(tmp_path, capsys):
    d = _two_legs()
    for j in d["joints"]:
        if j.get("actuated"):
            j["stiffness"] = {"drive_Nm_rad": 1e3}
    path = tmp_path / "two.toml"
    from pkmdyn.io import dumps_toml
    path.write_text(dumps_toml(d))
    code = main(["stiffness", "--machine", str(path), "--out", str(tmp_path / "st")])
    err = capsys.readouterr().err
    assert code == 2 and "task coordinate 'A_L_q' is a joint's" in err
    assert not (tmp_path / "st").exists()


def _legs_xml(spring=False, ball=False):
    """Two planar four-bars in MJCF, each closed by a ``connect`` (hinges about z), the cranks
    driven; with ``spring``, the right crank turns on a sprung hinge 0.05 m along a hub that the
    drive turns (a five-bar with a passive freedom: under-actuated); with ``ball``, the left
    coupler hangs from a ball joint, a rod between two balls whose spin is an idle freedom (as
    Cassie's achilles rods)."""
    legs = []
    for side, dx in (("L", 0.0), ("R", 3.0)):
        sprung = spring and side == "R"
        hub = (f'<body name="hub_{side}"><joint name="A_{side}" type="hinge" axis="0 0 1"/>'
               f'<inertial pos="0.025 0 0" mass="0.5" diaginertia="0.01 0.01 0.01"/>'
               f'<body name="crank_{side}" pos="0.05 0 0">'
               f'<joint name="H_{side}" type="hinge" axis="0 0 1" stiffness="40"/>'
               if sprung else
               f'<body name="crank_{side}"><joint name="A_{side}" type="hinge" axis="0 0 1"/>')
        close = "</body></body>" if sprung else "</body>"
        off = 0.05 if sprung else 0.0  # the crank's frame on the hub's arm
        legs.append(f"""
    <body name="base_{side}" pos="{dx} 0 0.3">
      {hub}
        <inertial pos="{0.1 - off} 0.45 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        <body name="coupler_{side}" pos="{0.2 - off} 0.9 0">
          <joint name="B_{side}" type="{'ball' if ball and side == 'L' else 'hinge'}"{'' if ball and side == 'L' else ' axis="0 0 1"'}/>
          <inertial pos="0.75 0.25 0" mass="1" diaginertia="0.01 0.01 0.01"/>
          <site name="tip_{side}" pos="1.5 0.5 0"/>
        </body>
      {close}
      <body name="rocker_{side}" pos="2 0 0">
        <joint name="D_{side}" type="hinge" axis="0 0 1"/>
        <inertial pos="-0.15 0.7 0" mass="1" diaginertia="0.01 0.01 0.01"/>
        <site name="top_{side}" pos="-0.3 1.4 0"/>
      </body>
    </body>""")
    eqs = "".join(f'\n    <connect site1="tip_{s}" site2="top_{s}"/>' for s in "LR")
    acts = "".join(f'\n    <motor name="m_{s}" joint="A_{s}"/>' for s in "LR")
    return ex.mjcf_document("two_legs", "".join(legs), eqs, acts, option='  <option gravity="0 -9.81 0"/>\n')


def _rows(path):
    with open(path, newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("spring, ball", [(False, False), (True, False), (False, True)])
def test_a_two_legged_model_imports_with_a_joint_task_and_runs_on_defaults(tmp_path, capsys, spring, ball):
    pytest.importorskip("mujoco")
    src = tmp_path / "legs.xml"
    src.write_text(_legs_xml(spring, ball))
    out = tmp_path / "legs.toml"
    assert main(["import", "--from", str(src), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "no body's coordinates determine the mechanism's freedoms" in err
    task = tomllib.loads(out.read_text())["task"]
    want = ["A_L", "A_R", "H_R"] if spring else ["A_L", "A_R"]  # the actuated first, then the sprung
    assert task["joints"] == want and not task["position"] and not task["orientation"]
    run = tmp_path / "run"
    assert main(["run", "--machine", str(out), "--out", str(run)]) == 0
    rows = _rows(run / "results.csv")
    summary = json.loads((run / "summary.json").read_text())
    assert summary["samples"] == len(rows) > 100
    # the rod's spin (ball) is idle: no task coordinate of its own, held by the run
    assert summary["topology"]["idle_freedoms"] == (1 if ball else 0)
    for side in "LR":  # an actuated joint's task coordinate is its actuator coordinate
        a = np.array([float(r[f"A_{side}_q_rad"]) for r in rows])
        np.testing.assert_allclose(a, [float(r[f"A_{side}_pos_rad"]) for r in rows], atol=1e-12)
        assert np.ptp(a) > 0.01
    bodies = np.load(run / "bodies.npz")
    names = [str(n) for n in bodies["coordinate_joints"]]
    for j in want:
        np.testing.assert_allclose([float(r[f"{j}_q_rad"]) for r in rows], bodies["q"][:, names.index(j)],
                                   atol=1e-12)
    if spring:  # the sprung hinge moves on its own (simulated), and the motion is consistent
        h = np.array([float(r["H_R_q_rad"]) for r in rows])
        assert np.ptp(h) > 1e-3
        assert summary["max_unactuated_force_ratio"] <= 1e-9
        _mujoco_agrees(src, bodies, rows)


def _mujoco_agrees(src, bodies, rows):
    """The run's motion in MuJoCo's own equations of the same file: ``M qacc + bias - passive``
    (the spring's force among the passive ones) is carried by the equality rows and the motors
    alone, the motors' part is the run's efforts, and the sprung hinge's row balances without
    any actuator (least squares over the equality forces and the motors' efforts)."""
    import mujoco

    mm = mujoco.MjModel.from_xml_path(str(src))
    md = mujoco.MjData(mm)
    names = [str(n) for n in bodies["coordinate_joints"]]
    worst_res = worst_u = 0.0
    for s in range(0, len(rows), 25):
        qacc = np.zeros(mm.nv)
        for j in range(mm.njnt):
            c = names.index(mm.joint(j).name)
            md.qpos[mm.jnt_qposadr[j]] = bodies["q"][s, c]
            md.qvel[mm.jnt_dofadr[j]] = bodies["qd"][s, c]
            qacc[mm.jnt_dofadr[j]] = bodies["qdd"][s, c]
        mujoco.mj_forward(mm, md)
        assert np.abs(md.efc_pos[:md.ne]).max() < 1e-9  # the file's loops closed at the run's poses
        M = np.zeros((mm.nv, mm.nv))
        mujoco.mj_fullM(mm, md, M)
        Q = M @ qacc + md.qfrc_bias - md.qfrc_passive
        B = np.zeros((mm.nv, mm.nu))
        for a in range(mm.nu):
            B[mm.jnt_dofadr[mm.actuator_trnid[a, 0]], a] = mm.actuator_gear[a, 0]
        A = np.hstack([md.efc_J.reshape(md.nefc, mm.nv)[:md.ne].T, B])
        sol, *_ = np.linalg.lstsq(A, Q, rcond=None)
        u_run = np.array([float(rows[s][f"{mm.joint(mm.actuator_trnid[a, 0]).name}_effort_Nm"])
                          for a in range(mm.nu)])
        worst_res = max(worst_res, float(np.abs(A @ sol - Q).max() / np.abs(Q).max()))
        worst_u = max(worst_u, float(np.abs(sol[-mm.nu:] - u_run).max() / np.abs(u_run).max()))
    assert worst_res <= 1e-8 and worst_u <= 1e-8


def test_a_joint_task_survives_export_and_import(tmp_path, capsys):
    pytest.importorskip("mujoco")
    from pkmdyn.io import dumps_toml
    d = _two_legs(("C_L", "A_R"))
    for j in d["joints"]:  # the coordinates' origins away from zero: the round trip must keep them
        if j["name"] in ("C_L", "A_R"):
            j["angle_at_reference_rad"] = 0.3 if j["name"] == "C_L" else -1.1
    path = tmp_path / "two.toml"
    path.write_text(dumps_toml(d))
    for fmt, name in (("mjcf", "two.xml"), ("urdf", "two.urdf")):
        exported = tmp_path / name
        args = ["export", "--machine", str(path), "--format", fmt, "--out", str(exported)]
        assert main(args) == 0, capsys.readouterr().err
        back = tmp_path / f"back_{fmt}.toml"
        extra = ["--sidecar", str(exported.with_suffix(".yaml"))] if fmt == "urdf" else []
        assert main(["import", "--from", str(exported), "--out", str(back), *extra]) == 0, capsys.readouterr().err
        m0, m1 = load_mechanism(d), load_mechanism(tomllib.loads(back.read_text()))
        assert m1.task_names == m0.task_names == ("C_L_q", "A_R_q")
        np.testing.assert_allclose(reference_task(m0), [0.3, -1.1], atol=1e-12)
        np.testing.assert_allclose(reference_task(m1), reference_task(m0), atol=1e-9)
        t = np.linspace(0.0, 1.0, 11)  # the same motion: the same actuator motion and efforts
        x, xd, xdd = _motion(m0, t, 0.1)
        k0, k1 = solve_kinematics(m0, x, xd, xdd, t), solve_kinematics(m1, x, xd, xdd, t)
        np.testing.assert_allclose(k1.act_q, k0.act_q, atol=1e-9)
        u0, u1 = inverse_dynamics(m0, k0).u, inverse_dynamics(m1, k1).u
        np.testing.assert_allclose(u1, u0, atol=1e-8 * np.abs(u0).max())


@pytest.mark.parametrize("make, item", [(lambda: ex.builtin_dict("stewart"), "U_6:2"),
                                        (ex.stewart_flipped_spheres, "S_1:1")])
def test_a_coordinate_of_a_joint_of_several_survives_export_and_import(make, item, tmp_path):
    """One angle of a universal joint, and of a ball the tree reaches from its child (its
    coordinates reversed in the exported tree), as a task coordinate: after an MJCF and a URDF
    round trip the same task motion gives the same actuator motion."""
    pytest.importorskip("mujoco")
    d = make()
    d.pop("default_motion", None)
    d["task"] = {"body": "platform", "point_m": [0.0, 0.0, 1.0], "position": ["x", "y", "z"], "orientation": [1, 2],
                 "joints": [item]}
    m0 = load_mechanism(d)
    name, _, k = item.partition(":")
    assert m0.task_names[-1] == f"{name}_q{k}" and m0.task_joints == (item,)
    t = np.linspace(0.0, 1.0, 6)
    x, xd, xdd = _motion(m0, t, 0.002)
    k0 = solve_kinematics(m0, x, xd, xdd, t)
    assert np.ptp(k0.act_q, axis=0).max() > 1e-3
    for fmt in ("mjcf", "urdf"):
        m1 = load_mechanism(tomllib.loads(ex.round_trip(m0, fmt, tmp_path)))
        k1 = solve_kinematics(m1, x, xd, xdd, t)
        idx = [m1.actuator_names.index(n) for n in m0.actuator_names]
        np.testing.assert_allclose(k1.act_q[:, idx], k0.act_q, atol=1e-9)

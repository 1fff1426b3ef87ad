"""pkmdyn import (MJCF, URDF + loop sidecar, SDFormat) and the exports that go with it.

Checked: the built-in machines exported (MJCF; URDF + sidecar) and imported back give the same
efforts along the same actuator motion; mechanisms written here in other formats (a five-bar in
Gepetto's Extended-URDF conventions and in onshape-to-robot's, the same five-bar in MJCF with
geared motors and armature, a four-bar in SDFormat) give the efforts of another engine's
projected inverse dynamics (Pinocchio, MuJoCo: tests/oracles/projected_id.py) or of the
mechanism described by hand; bad input is one line naming the element, exit 2, nothing written;
MuJoCo's forward dynamics of the stiff exports follows pkmdyn's motion."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

import multibody_examples as ex
from oracles.projected_id import mujoco_efforts, pinocchio_efforts
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import default_motion, load_mechanism, solve_kinematics
from pkmdyn.multibody.kinematics.direct import direct_kinematics
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions
from pkmdyn.multibody.formats.importer import import_description
from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos
from pkmdyn.multibody.formats.urdf_out import mechanism_urdf

mujoco = pytest.importorskip("mujoco")
pin = pytest.importorskip("pinocchio")

REL = 1e-10  # the agreement bound for efforts


def _efforts(model, kin):
    """The efforts with every reaction; an over-constrained mechanism's reactions as the
    minimum-norm ones (an import carries no link compliance; the efforts do not depend on it)."""
    over = model.topology is not None and model.topology.overconstraints > 0
    return joint_reactions(model, kin, overconstrained="minimum-norm" if over else "compliance").u


def _moving(model, seed=0):
    """The default motion of ``model`` and its kinematics."""
    mo = default_motion(model)
    return mo, solve_kinematics(model, mo.x, mo.xd, mo.xdd, mo.t)


def _same_motion(m0, kin0, t, m1):
    """Kinematics of ``m1`` (an export of ``m0`` read back) along ``m0``'s actuator motion: the
    export's joint coordinates are ``m0``'s themselves (both formats keep their origin: MJCF each
    joint's ``ref``, pkmdyn's URDF sidecar its ``reference``)."""
    idx = [m1.actuator_names.index(n) for n in m0.actuator_names]
    s, sd, sdd = (np.empty_like(kin0.act_q) for _ in range(3))
    s[:, idx] = kin0.act_q
    sd[:, idx], sdd[:, idx] = kin0.act_qd, kin0.act_qdd
    dk = direct_kinematics(m1, s, sd, sdd, t)
    return solve_kinematics(m1, dk.x, dk.xd, dk.xdd, t), idx


@pytest.mark.parametrize("name", ex.BUILTIN)
@pytest.mark.parametrize("fmt", ["mjcf", "urdf"])
def test_builtin_export_import_round_trip(name, fmt, tmp_path):
    m0 = load_mechanism(ex.builtin_dict(name))
    m1 = load_mechanism(tomllib.loads(ex.round_trip(m0, fmt, tmp_path)))
    assert sorted(m1.actuator_names) == sorted(m0.actuator_names)
    assert m1.nq == m0.nq and m1.nb == m0.nb
    assert np.isclose(m1.mass.sum(), m0.mass.sum(), rtol=1e-14)
    mo, k0 = _moving(m0)
    k1, idx = _same_motion(m0, k0, mo.t, m1)
    u0, u1 = _efforts(m0, k0), _efforts(m1, k1)[:, idx]
    assert np.abs(u1 - u0).max() <= REL * np.abs(u0).max()
    for j, lim in enumerate(m0.joint_limits):  # the limits come back in the same coordinate
        if lim is not None and j not in set(m0.loop_joint.tolist()):
            assert m1.joint_limits[m1.joint_names.index(m0.joint_names[j])] == pytest.approx(lim, abs=1e-12)
    # key by key: the name, the task (body, coordinates, point in the base frame) and the drives' stiffness
    assert m1.name == m0.name
    assert m1.body_names[m1.task_body] == m0.body_names[m0.task_body]
    assert m1.task_names == m0.task_names and m1.euler_sequence == m0.euler_sequence
    world = [m.p0[m.task_body] + m.R0[m.task_body] @ m.task_point for m in (m0, m1)]
    np.testing.assert_allclose(world[1], world[0], rtol=0, atol=1e-12 * m0.length_scale)
    for j in m0.act_joint:
        k0 = (m0.joint_stiffness[j] or {}).get("drive")
        k1 = (m1.joint_stiffness[m1.joint_names.index(m0.joint_names[j])] or {}).get("drive")
        assert k0 is not None and k1 == pytest.approx(k0, rel=1e-15)


# -- a planar five-bar written in other formats ------------------------------------------------

MOTORS = (np.array([-0.1, 0.0, 0.0]), np.array([0.1, 0.0, 0.0]))
PROX, DIST, END = 0.3, 0.4, np.array([0.03, 0.0, -0.55])
Y = np.array([0.0, 1.0, 0.0])


def _elbow(motor, side):
    """The elbow between ``motor`` and the end point (circle intersection in the x-z plane)."""
    d = END - motor
    L = np.linalg.norm(d)
    a = (PROX ** 2 - DIST ** 2 + L ** 2) / (2 * L)
    h = np.sqrt(PROX ** 2 - a ** 2)
    n = np.cross(Y, d / L)
    return motor + a * d / L + side * h * n


def _five_bar_points():
    return [(m, _elbow(m, s)) for m, s in zip(MOTORS, (1.0, -1.0))]


def _inertial(mass, com, origin):
    c = np.asarray(com, dtype=float) - origin
    I = mass * 0.01
    return (f'<inertial><origin xyz="{_xyz(c)}" rpy="0 0 0"/><mass value="{mass!r}"/>'
            f'<inertia ixx="{I!r}" iyy="{I * 1.3!r}" izz="{I * 0.7!r}" ixy="0" ixz="{I * 0.1!r}" iyz="0"/></inertial>')


def _xyz(v):
    return " ".join(repr(float(x)) for x in v)


def five_bar_urdf(style: str, motor_offset: float = 0.0) -> str:
    """The five-bar in URDF, every link frame parallel to the base at the zero configuration.
    ``style`` ``gepetto``: closed by a 6D pair of joint frames (``closedloop1_A``, a revolute
    joint to a small ball on the left distal link; ``closedloop1_B``, a ball fixed on the right one); ``onshape``: by ``closing_end_1/2`` frames (3D).
    ``motor_offset`` [rad] turns the right motor's zero, so that the file is not assembled."""
    (ml, el), (mr, er) = _five_bar_points()
    parts = ['<robot name="five_bar">', '<link name="base">' + _inertial(2.0, np.zeros(3), np.zeros(3)) + "</link>"]

    def link(name, mass, com, origin):
        parts.append(f'<link name="{name}">' + _inertial(mass, com, origin) + "</link>")

    def joint(name, kind, parent, child, origin_xyz, rpy="0 0 0"):
        lim = '<limit lower="-3" upper="3" effort="1" velocity="1"/>' if kind == "revolute" else ""
        parts.append(f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
                     f'<origin xyz="{_xyz(origin_xyz)}" rpy="{rpy}"/><axis xyz="0 1 0"/>{lim}</joint>')

    joint("mot1", "revolute", "base", "prox_l", ml)
    link("prox_l", 0.8, (ml + el) / 2, ml)
    joint("free1", "revolute", "prox_l", "dist_l", el - ml)
    link("dist_l", 1.1, (el + END) / 2, el)
    joint("mot2", "revolute", "base", "prox_r", mr, rpy=f"0 {motor_offset!r} 0")
    link("prox_r", 0.8, (mr + er) / 2, mr)
    joint("free2", "revolute", "prox_r", "dist_r", er - mr)
    link("dist_r", 1.2, (er + END) / 2, er)
    if style == "gepetto":  # a revolute joint's frame on one side, a fixed one on the other (no idle spin)
        for side, host, origin, kind in (("A", "dist_l", el, "revolute"), ("B", "dist_r", er, "fixed")):
            joint(f"closedloop1_{side}", kind, host, f"ball_{side}", END - origin)
            link(f"ball_{side}", 0.05, END, END)
    else:
        for k, host, origin in (("1", "dist_l", el), ("2", "dist_r", er)):
            parts.append(f'<joint name="closing_end_{k}_frame" type="fixed"><parent link="{host}"/>'
                         f'<child link="closing_end_{k}"/><origin xyz="{_xyz(END - origin)}" rpy="0 0 0"/></joint>')
            parts.append(f'<link name="closing_end_{k}"/>')
    parts.append("</robot>")
    return "\n".join(parts) + "\n"


def _pin_check(model, kin, urdf, closures, samples=range(0, 201, 25)):
    """pkmdyn's efforts against Pinocchio's projected inverse dynamics of the same file."""
    u = _efforts(model, kin)
    act = [model.joint_names[j] for j in model.act_joint]
    one = [k for k in range(len(model.joint_names)) if model.joint_nq[k] == 1]
    for s in samples:
        q_of = {model.joint_names[k]: kin.q[s, model.joint_q0[k]] for k in one}
        qd_of = {model.joint_names[k]: kin.qd[s, model.joint_q0[k]] for k in one}
        qdd_of = {model.joint_names[k]: kin.qdd[s, model.joint_q0[k]] for k in one}
        u_pin, res, spread = pinocchio_efforts(str(urdf), closures, act, q_of, qd_of, qdd_of,
                                               gravity=model.gravity)
        assert res <= 1e-9 * np.abs(u_pin).max() and spread < 1e-9
        assert np.abs(u[s] - u_pin).max() <= REL * np.abs(u_pin).max()


def test_gepetto_style_urdf_with_sidecar_matches_pinocchio(tmp_path):
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(five_bar_urdf("gepetto", motor_offset=0.15))
    side = tmp_path / "robot.yaml"
    side.write_text("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['6d']\nname_mot: ['mot1', 'mot2']\n")
    out = tmp_path / "five_bar.toml"
    # the file is not assembled at zero: refused with the pair and its gap, then closed on request
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--out", str(out)]) == 2
    assert not out.exists()
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--assemble", "--out", str(out)]) == 0
    model = load_mechanism(out)
    assert model.topology.overconstraints == 3 and model.topology.dof == 2  # a planar loop in space
    mo, kin = _moving(model)
    assert np.ptp(kin.act_q, axis=0).min() > 1e-3  # the default motion moves the motors
    _pin_check(model, kin, urdf, [("closedloop1_A", "closedloop1_B", "6d")])


def test_onshape_closing_frames_match_pinocchio(tmp_path):
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(five_bar_urdf("onshape"))
    out = tmp_path / "five_bar.toml"
    assert main(["import", "--from", str(urdf), "--actuated", "mot1,mot2", "--out", str(out)]) == 0
    model = load_mechanism(out)
    # a planar loop closed by a point: the force along the axes is one self-stress
    assert model.topology.overconstraints == 1 and model.topology.dof == 2
    d = tomllib.loads(out.read_text())
    assert d["task"]["position"] == ["x", "z"]  # chosen: the plane's two translations
    assert d["mechanism"]["reactions"] == "minimum-norm"  # no compliance in the file: its runs say so
    mo, kin = _moving(model)
    _pin_check(model, kin, urdf, [("closing_end_1", "closing_end_2", "3d")])
    import json

    assert main(["run", "--machine", str(out), "--out", str(tmp_path / "run")]) == 0
    summary = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert summary["reactions"]["unique"] is False


def five_bar_mjcf(site_connect: bool = False) -> str:
    """The five-bar in MJCF: geared motors with armature and damping, a connect equality."""
    (ml, el), (mr, er) = _five_bar_points()

    def body(name, pos, mass, com, joint, extra=""):
        return (f'<body name="{name}" pos="{_xyz(pos)}"><inertial pos="{_xyz(com)}" mass="{mass!r}" '
                f'diaginertia="{mass * 0.01!r} {mass * 0.013!r} {mass * 0.007!r}"/>'
                f'<joint name="{joint}" type="hinge" axis="0 1 0"{extra}/>')

    motor = ' armature="0.02" damping="0.05"'
    site = f'<site name="end_l" pos="{_xyz(END - el)}"/>' if site_connect else ""
    site_r = f'<site name="end_r" pos="{_xyz(END - er)}"/>' if site_connect else ""
    eq = ('<connect site1="end_l" site2="end_r"/>' if site_connect
          else f'<connect name="close" body1="dist_l" body2="dist_r" anchor="{_xyz(END - el)}"/>')
    return f"""<mujoco model="five_bar">
  <option gravity="0 0 -9.81"/>
  <worldbody>
    {body("prox_l", ml, 0.8, (el - ml) / 2, "mot1", motor)}
      {body("dist_l", el - ml, 1.1, (END - el) / 2, "free1", ' damping="0.01"')}{site}</body>
    </body>
    {body("prox_r", mr, 0.8, (er - mr) / 2, "mot2", motor)}
      {body("dist_r", er - mr, 1.2, (END - er) / 2, "free2")}{site_r}<site name="tool" pos="{_xyz(END - er)}"/></body>
    </body>
  </worldbody>
  <equality>{eq}</equality>
  <actuator><motor name="m1" joint="mot1" gear="12"/><motor name="m2" joint="mot2" gear="12"/></actuator>
</mujoco>
"""


@pytest.mark.parametrize("site_connect, springs", [(False, False), (True, False), (False, True)])
def test_mjcf_with_geared_motors_matches_mujoco(tmp_path, site_connect, springs):
    """With ``springs`` the passive joints carry MuJoCo joint springs (``stiffness``, ``springref``):
    the description's springs, whose forces MuJoCo's passive forces hold too."""
    xml = tmp_path / "five_bar.xml"
    text = five_bar_mjcf(site_connect)
    if springs:
        text = text.replace('joint="free1"', "").replace('name="free1" type="hinge" axis="0 1 0"',
                                                         'name="free1" type="hinge" axis="0 1 0" stiffness="3.5" '
                                                         'springref="0.2"')
        text = text.replace('name="free2" type="hinge" axis="0 1 0"', 'name="free2" type="hinge" axis="0 1 0" '
                                                                       'stiffness="1.2"')
        assert text.count("stiffness=") == 2
    xml.write_text(text)
    out = tmp_path / "five_bar.toml"
    assert main(["import", "--from", str(xml), "--task-point", "tool", "--out", str(out)]) == 0
    d = tomllib.loads(out.read_text())
    if springs:
        sp = {j["name"]: j.get("spring") for j in d["joints"]}
        # MuJoCo's angles are degrees unless the compiler says otherwise: springref 0.2 deg
        assert sp["free1"]["stiffness_Nm_rad"] == 3.5
        assert sp["free1"]["reference_rad"] == pytest.approx(np.radians(0.2), rel=1e-15)
        assert sp["free2"] == {"stiffness_Nm_rad": 1.2, "reference_rad": 0.0}
    drives = {a["joint"]: a for a in d["actuators"]}
    assert drives["mot1"]["gear_ratio"] == 12.0 and np.isclose(drives["mot1"]["rotor_inertia_kgm2"], 0.02 / 144)
    assert np.isclose(drives["mot1"]["viscous_Nm_s_rad"], 0.05 / 144)
    free1 = next(j for j in d["joints"] if j["name"] == "free1")
    assert free1["friction"] == {"viscous_Nm_s_rad": 0.01}
    model = load_mechanism(out)
    mo, kin = _moving(model)
    from pkmdyn.multibody.dynamics.actuators import motor_efforts

    tau = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, _efforts(model, kin)).effort
    names = [model.joint_names[k] for k in range(len(model.joint_names)) if model.joint_nq[k] == 1
             and not model.joint_cut[k]]
    for s in range(0, len(mo.t), 25):
        q_of = {n: kin.q[s, model.joint_q0[model.joint_index(n)]] for n in names}
        qd_of = {n: kin.qd[s, model.joint_q0[model.joint_index(n)]] for n in names}
        qdd_of = {n: kin.qdd[s, model.joint_q0[model.joint_index(n)]] for n in names}
        u_mj, res, spread = mujoco_efforts(str(xml), q_of, qd_of, qdd_of)
        assert spread < 1e-9
        order = [model.drive_name.index(nm) for nm in ("m1", "m2")]
        assert np.abs(tau[s, order] - u_mj).max() <= REL * np.abs(u_mj).max()


SDF = """<?xml version="1.0"?>
<sdf version="1.9">
  <model name="four_bar">
    <link name="crank"><pose>0 0 0.3 0 0 0</pose>
      <inertial><pose>0.1 0.45 0 0 0 0</pose><mass>1</mass>
        <inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial></link>
    <link name="coupler"><pose>0.2 0.9 0.3 0 0 0.4</pose>
      <inertial><pose relative_to="__model__">0.95 1.15 0.3 0 0 0</pose><mass>1</mass>
        <inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial></link>
    <link name="rocker"><pose>2 0 0.3 0 0 0</pose>
      <inertial><pose>-0.15 0.7 0 0 0 0</pose><mass>1</mass>
        <inertia><ixx>0.01</ixx><iyy>0.01</iyy><izz>0.01</izz><ixy>0</ixy><ixz>0</ixz><iyz>0</iyz></inertia></inertial></link>
    <joint name="A" type="revolute"><parent>world</parent><child>crank</child><axis><xyz>0 0 1</xyz></axis></joint>
    <joint name="B" type="revolute"><parent>crank</parent><child>coupler</child><axis><xyz>0 0 1</xyz></axis></joint>
    <joint name="D" type="revolute"><parent>world</parent><child>rocker</child><axis><xyz>0 0 1</xyz></axis></joint>
    <joint name="C" type="revolute"><parent>coupler</parent><child>rocker</child>
      <pose relative_to="__model__">1.7 1.4 0.3 0 0 0</pose><axis><xyz expressed_in="__model__">0 0 1</xyz></axis></joint>
  </model>
</sdf>
"""


def test_sdformat_loop_gives_the_hand_described_efforts(tmp_path):
    """The four-bar of multibody_examples (crank, coupler, rocker; a link with two parents in
    SDFormat) imported gives the efforts of the description written by hand."""
    src = tmp_path / "four_bar.sdf"
    src.write_text(SDF)
    text, _ = import_description(src, "sdf", actuated=("A",))
    hand = ex.four_bar()
    hand["mechanism"]["gravity_m_s2"] = [0.0, 0.0, -9.8]  # SDFormat's default gravity
    m0 = load_mechanism(hand)
    d1 = tomllib.loads(text)
    d1["task"] = hand["task"]  # the same task (the crank's angle) to compare along one motion
    del d1["default_motion"]
    m1 = load_mechanism(d1)
    assert set(m1.joint_names) == {"A", "B", "C", "D"}
    t = np.linspace(0.0, 1.0, 41)
    x, xd, xdd = ex.smooth_motion(np.zeros(1), np.array([0.3]), t, 2)
    u0 = _efforts(m0, solve_kinematics(m0, x, xd, xdd, t))
    u1 = _efforts(m1, solve_kinematics(m1, x, xd, xdd, t))
    assert np.abs(u1 - u0).max() <= REL * np.abs(u0).max()


# -- bad input: one line naming the element, exit 2, nothing written ------------------------------

def _refused(tmp_path, capsys, args, pattern):
    import re

    out = tmp_path / "out.toml"
    assert main(["import", *args, "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and re.search(pattern, err[0]), err
    assert not out.exists()


def test_bad_input_is_refused_by_name(tmp_path, capsys):
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body name='a'>")
    _refused(tmp_path, capsys, ["--from", str(broken)], r"broken\.xml: cannot read it as XML")
    free = tmp_path / "free.xml"
    free.write_text("<mujoco><worldbody><body name='b'><freejoint name='fly'/>"
                    "<inertial pos='0 0 0' mass='1' diaginertia='1 1 1'/></body></worldbody></mujoco>")
    _refused(tmp_path, capsys, ["--from", str(free)], r"joint fly: a free joint")
    tendon = tmp_path / "tendon.xml"
    tendon.write_text(five_bar_mjcf().replace("<equality>", "<equality><joint joint1='free1' joint2='free2'/>"))
    _refused(tmp_path, capsys, ["--from", str(tendon)], r"equality equality_0: a joint equality has no equivalent")
    urdf = tmp_path / "robot.urdf"
    urdf.write_text(five_bar_urdf("gepetto", motor_offset=0.15))
    side = tmp_path / "robot.yaml"
    side.write_text("closed_loop: [['closedloop1_A', 'closedloop9_B']]\ntype: ['6d']\nname_mot: ['mot1', 'mot2']\n")
    _refused(tmp_path, capsys, ["--from", str(urdf), "--sidecar", str(side)],
             r"closed_loop frame 'closedloop9_B': no frame of that name")
    side.write_text("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['6d']\nname_mot: ['mot1', 'mot2']\n")
    _refused(tmp_path, capsys, ["--from", str(urdf), "--sidecar", str(side)],
             r"loop closure closedloop1: its frames are 0\.\d+ m apart")
    side.write_text("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['6d']\nname_mot: ['mot7']\n")
    _refused(tmp_path, capsys, ["--from", str(urdf), "--sidecar", str(side), "--assemble"],
             r"actuated joint 'mot7': no joint of that name")
    # a 6D pair whose frames are turned by half a turn about an axis the loop cannot turn about:
    # the refusal names the angle left, not only the gap
    turned = tmp_path / "turned.urdf"
    text = five_bar_urdf("gepetto")
    at = text.index('name="closedloop1_B"')
    end = text.index("</joint>", at)
    turned.write_text(text[:at] + text[at:end].replace('rpy="0 0 0"', 'rpy="0 0 3.141592653589793"') + text[end:])
    assert turned.read_text() != text
    side.write_text("closed_loop: [['closedloop1_A', 'closedloop1_B']]\ntype: ['6d']\nname_mot: ['mot1', 'mot2']\n")
    _refused(tmp_path, capsys, ["--from", str(turned), "--sidecar", str(side), "--assemble"],
             r"closedloop1_A-closedloop1_B: the loops do not close near the zero configuration \(gap \S+ m and "
             r"3\.14\d* rad after assembly\)")
    sdf = tmp_path / "screw.sdf"
    sdf.write_text(SDF.replace('name="B" type="revolute"', 'name="B" type="screw"'))
    _refused(tmp_path, capsys, ["--from", str(sdf), "--actuated", "A"], r"joint B: a screw joint has no equivalent")
    massless = tmp_path / "massless.urdf"
    massless.write_text(five_bar_urdf("onshape").replace(
        _inertial(1.1, (_five_bar_points()[0][1] + END) / 2, _five_bar_points()[0][1]), ""))
    _refused(tmp_path, capsys, ["--from", str(massless), "--actuated", "mot1,mot2"], r"link dist_l: no mass")


def test_an_existing_output_is_not_replaced(tmp_path, capsys):
    xml = tmp_path / "five_bar.xml"
    xml.write_text(five_bar_mjcf())
    assert main(["import", "--from", str(xml), "--out", str(xml)]) == 2
    assert xml.read_text() == five_bar_mjcf()


# -- exports -----------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ex.BUILTIN)
def test_stiff_mjcf_export_follows_pkmdyn_forward_dynamics(name):
    """MuJoCo's accelerations under pkmdyn's efforts along the default motion, at the export's
    default (stiff) settings, within 1 % of the motion's own (forward(inverse) = identity in
    pkmdyn). MuJoCo's equality rows leave out the velocity product term of the constraints'
    acceleration (it stabilises them instead), which is what remains."""
    m = load_mechanism(ex.builtin_dict(name))
    mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
    md = mujoco.MjData(mm)
    o = mujoco_order(m, mm)
    mo, kin = _moving(m)
    u = _efforts(m, kin)
    a = m.act_coord
    scale = np.abs(kin.qdd[:, a]).max()
    for s in range(0, len(mo.t), 10):
        md.qpos[:] = mujoco_qpos(m, kin.q[s], mm)
        md.qvel[o] = kin.qd[s]
        md.ctrl[:] = u[s]
        mujoco.mj_forward(mm, md)
        assert np.abs(md.qacc[o][a] - kin.qdd[s, a]).max() <= 0.01 * scale


def test_export_options_and_refusals(tmp_path, capsys):
    out = tmp_path / "s.xml"
    assert main(["export", "--machine", "stewart", "--format", "mjcf", "--solref", "0.002,1",
                 "--solimp", "0.99,0.995,0.001,0.5,2", "--out", str(out)]) == 0
    mm = mujoco.MjModel.from_xml_path(str(out))
    assert np.allclose(mm.eq_solref, [0.002, 1.0]) and np.allclose(mm.eq_solimp[:, :2], [0.99, 0.995])
    assert main(["export", "--machine", "stewart", "--format", "mjcf", "--solref", "0.002",
                 "--out", str(tmp_path / "t.xml")]) == 2
    assert "--solref: 2 numbers" in capsys.readouterr().err
    urdf = tmp_path / "s.urdf"
    assert main(["export", "--machine", "delta", "--format", "urdf", "--out", str(urdf)]) == 0
    assert urdf.exists() and (tmp_path / "s.yaml").exists()
    d = ex.four_bar()
    d["bodies"][1]["mass_kg"] = 0.0
    with pytest.raises(ParameterError, match=r"\[bodies\] coupler: no mass"):
        mechanism_mjcf(load_mechanism(d))



@pytest.mark.parametrize("name", ex.BUILTIN)
def test_pinocchio_with_the_urdf_export_gives_pkmdyn_efforts(name, tmp_path):
    """The URDF + sidecar export in Pinocchio: its parser's model, the sidecar's loop frames,
    Pinocchio's own RNEA and frame Jacobians, projected, give pkmdyn's efforts (the Delta's
    rod spins held by pkmdyn's documented rule, whose force directions the projection takes)."""
    m = load_mechanism(ex.builtin_dict(name))
    text, side, _ = mechanism_urdf(m)
    urdf = tmp_path / "m.urdf"
    urdf.write_text(text)
    closures = [(a, b, k) for (a, b), k in zip(side["closed_loop"], side["type"])]
    mo, kin = _moving(m)
    u = _efforts(m, kin)
    act = list(side["name_mot"])
    H = np.asarray(m.solver_idle, dtype=float).T  # the idle freedoms' holding rules (dynamics.idle_holding)
    for s in range(0, len(mo.t), 40):
        q_of, qd_of, qdd_of, held = {}, {}, {}, {}
        for k, jn in enumerate(m.joint_names):
            n = 0 if m.joint_cut[k] else int(m.joint_nq[k])
            for i in range(n):  # the export's one-coordinate joints: <joint> or <joint>_<i>
                c = int(m.joint_q0[k]) + i
                nm = jn if n == 1 else f"{jn}_{i + 1}"
                q_of[nm], qd_of[nm], qdd_of[nm] = kin.q[s, c] - m.coord_offset[c], kin.qd[s, c], kin.qdd[s, c]
                held[nm] = H[c]
        u_pin, res, spread = pinocchio_efforts(str(urdf), closures, act, q_of, qd_of, qdd_of, gravity=m.gravity,
                                               held=held if H.shape[1] else None)
        assert res <= 1e-9 * np.abs(u_pin).max() and spread < 1e-9
        assert np.abs(u[s] - u_pin).max() <= REL * np.abs(u_pin).max()


SERIAL = """<robot name="arm">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="0.25 0 0"/><mass value="1"/><inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="b"><inertial><origin xyz="0.2 0 0"/><mass value="0.5"/><inertia ixx="0.005" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="a"/><child link="b"/><origin xyz="0.5 0 0"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>
"""


def test_a_serial_urdf_takes_its_last_link_as_task(tmp_path):
    """No loop: the link with most joints (the first) cannot see both freedoms; the task
    body chosen is the one whose coordinates determine the pose."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(SERIAL)
    text, _ = import_description(urdf, "urdf", actuated=("j1", "j2"))
    d = tomllib.loads(text)
    assert d["task"]["body"] == "b" and len(d["task"]["position"]) + len(d["task"]["orientation"]) == 2
    load_mechanism(d)


def test_more_bad_input(tmp_path, capsys):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(SERIAL.replace('<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>\n</robot>',
                                   '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
                                   '<mimic joint="j1"/></joint>\n</robot>'))
    _refused(tmp_path, capsys, ["--from", str(urdf), "--actuated", "j1"], r"joint j2: a mimic joint")
    urdf.write_text(SERIAL)
    side = tmp_path / "arm.yaml"
    side.write_text("name_mot: [j1, j2]\ntask: {point: [1, a, 2]}\n")
    _refused(tmp_path, capsys, ["--from", str(urdf), "--sidecar", str(side)], r"arm\.yaml: \[task\] point: expected")


def test_a_generic_robot_name_gives_way_to_the_files_name(tmp_path):
    """A URDF that calls itself ``robot`` (as Gepetto's published loops do) is named after its
    file; a URDF with a name of its own keeps it."""
    generic = tmp_path / "five_bar_gepetto.urdf"
    generic.write_text(five_bar_urdf("onshape").replace('<robot name="five_bar">', '<robot name="robot">'))
    named = tmp_path / "other_file.urdf"
    named.write_text(five_bar_urdf("onshape"))
    for src, want in ((generic, "five_bar_gepetto"), (named, "five_bar")):
        text, _ = import_description(src, "urdf", actuated=("mot1", "mot2"))
        assert load_mechanism(tomllib.loads(text)).name == want


@pytest.mark.parametrize("text, words", [
    ("a: &a [1, 2]\nb: [*a, *a]\n", "anchors and aliases"),
    ("closed_loop: " + "[" * 12 + "]" * 12 + "\n", "nested more than 8 deep"),
    ("name_mot: [" + "1" * 5000 + "]\n", "cannot read it as YAML"),
    ("name_mot: [[j1], j2]\n", "[name_mot] 0: has the wrong type"),
    ("gravity_m_s2: [true, false, true]\n", "[gravity_m_s2] 0: has the wrong type"),
    ("gravity_m_s2: [" + "9" * 401 + ", 0, 0]\n", "[gravity_m_s2] 0"),
    ("gravity_m_s2: [.nan, 0, 0]\n", "[gravity_m_s2] 0"),
    ("closed_loop: [[a, b]]\ntype: [6d, 3d]\n", "type: one of '3d' or '6d' per closed_loop pair"),
    ("task: {point: [1, 2]}\n", "[task] point: expected a frame name or three finite numbers"),
    ("task: {orientation: [4]}\n", "[task] orientation"),
    ("tasks: {}\n", "[tasks]"),
])
def test_a_hostile_sidecar_is_one_line(tmp_path, capsys, text, words):
    """The sidecar has a schema as the descriptions have; anchors, deep nesting and numbers too
    long to read are refused before anything is built."""
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(SERIAL)
    side = tmp_path / "arm.yaml"
    side.write_text(text)
    out = tmp_path / "arm.toml"
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and words in err[0], err
    assert not out.exists()


def test_a_billion_laughs_sidecar_is_refused_at_once(tmp_path, capsys):
    lines = ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    lines += [f"a{k}: &a{k} [*a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}, *a{k - 1}]"
              for k in range(1, 10)]
    side = tmp_path / "laughs.yaml"
    side.write_text("\n".join(lines) + "\nname_mot: *a9\n")
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(SERIAL)
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--out", str(tmp_path / "o.toml")]) == 2
    assert "anchors and aliases" in capsys.readouterr().err


def test_the_sidecars_sequence_and_an_empty_type_list(tmp_path, capsys):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(SERIAL)
    side = tmp_path / "arm.yaml"
    side.write_text("task: {euler_sequence: XXY}\n")
    out = tmp_path / "arm.toml"
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--out", str(out)]) == 2
    assert "[task] euler_sequence: 'XXY': no axis twice in a row" in capsys.readouterr().err
    side.write_text("name_mot: [j1, j2]\ntype: []\n")  # no loops and no types: nothing to say
    assert main(["import", "--from", str(urdf), "--sidecar", str(side), "--out", str(out)]) == 0

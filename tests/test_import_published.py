"""MJCF written as MuJoCo users write it, imported as published: a Gough-Stewart platform whose
platform is a free body held by six connects (checked against the closed-form leg lengths and
the static leg forces of tests/oracles/stewart.py), a floating base (refused naming the option
that welds it, or welded with it), every refusal of a file listed in one pass, MuJoCo's
warnings kept out of the working folder, and a ball joint's damping as its viscous friction."""

from __future__ import annotations

import re
import tomllib

import numpy as np
import pytest

import multibody_examples as ex
from oracles import stewart
from pkmdyn.cli import main
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

mujoco = pytest.importorskip("mujoco")

LEG_KG = 1e-6  # the legs all but massless: the static leg forces are the platform's weight's


def _fmt(v):
    return " ".join(f"{c:.15g}" for c in v)


def stewart_free_xml(platform_kg=10.0):
    """Six U-P legs from the ground (two hinges, then a slide whose ``ref`` is the leg length),
    the platform a free body, six ``connect``s between the legs' tips and its sites."""
    a, b, home = stewart.default_geometry()
    legs = []
    for i in range(6):
        top = home + b[i]
        L = float(np.linalg.norm(top - a[i]))
        u = (top - a[i]) / L
        x1 = np.cross([0.0, 0.0, 1.0], u)
        x1 /= np.linalg.norm(x1)
        legs.append(f"""
    <body name="cyl{i + 1}" pos="{_fmt(a[i])}">
      <joint name="u{i + 1}a" type="hinge" axis="{_fmt(x1)}"/>
      <joint name="u{i + 1}b" type="hinge" axis="{_fmt(np.cross(u, x1))}"/>
      <inertial pos="{_fmt(0.25 * L * u)}" mass="{LEG_KG}" diaginertia="{LEG_KG} {LEG_KG} {LEG_KG}"/>
      <body name="pis{i + 1}">
        <joint name="p{i + 1}" type="slide" axis="{_fmt(u)}" ref="{L:.15g}"/>
        <inertial pos="{_fmt(0.75 * L * u)}" mass="{LEG_KG}" diaginertia="{LEG_KG} {LEG_KG} {LEG_KG}"/>
        <site name="tip{i + 1}" pos="{_fmt(L * u)}"/>
      </body>
    </body>""")
    sites = "".join(f'\n      <site name="s{i + 1}" pos="{_fmt(b[i])}"/>' for i in range(6))
    eqs = "".join(f'\n    <connect name="c{i + 1}" site1="tip{i + 1}" site2="s{i + 1}"/>' for i in range(6))
    acts = "".join(f'\n    <motor name="m{i + 1}" joint="p{i + 1}"/>' for i in range(6))
    platform = f"""
    <body name="platform" pos="{_fmt(home)}">
      <freejoint name="float"/>
      <inertial pos="0 0 0" mass="{platform_kg}" diaginertia="0.625 0.625 1.25"/>{sites}
    </body>"""
    return ex.mjcf_document("stewart_free", "".join(legs) + platform, eqs, acts)


def _import(tmp_path, xml, *extra, name="m"):
    src = tmp_path / f"{name}.xml"
    src.write_text(xml)
    out = tmp_path / f"{name}.toml"
    code = main(["import", "--from", str(src), "--out", str(out), *extra])
    return code, out


def test_a_stewart_with_a_free_platform_held_by_connects(tmp_path, capsys):
    code, out = _import(tmp_path, stewart_free_xml())
    assert code == 0, capsys.readouterr().err
    assert "a free joint whose body the loops hold" in capsys.readouterr().err
    m = load_mechanism(out)
    assert m.topology.dof == 6 and m.na == 6 and m.body_names[m.task_body] == "platform"
    a, b, home = stewart.default_geometry()
    rng = np.random.default_rng(5)
    x = reference_task(m) + rng.uniform(-1, 1, (8, 6)) * [0.05, 0.05, 0.05, 0.06, 0.06, 0.1]
    kin = solve_kinematics(m, x)
    order = [m.actuator_names.index(f"p{i + 1}") for i in range(6)]
    ref = stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")
    np.testing.assert_allclose(kin.act_q[:, order], ref["L"], rtol=0, atol=1e-11)
    # at rest: the legs' forces carry the platform's weight, sum u_i n_i + m g = 0 with the
    # moments about the platform point (the oracle's unit leg vectors)
    u = joint_reactions(m, kin).u[:, order]
    for s in range(len(x)):
        n = ref["u"][s]
        R = stewart.axis_rotation("X", x[s, 3]) @ stewart.axis_rotation("Y", x[s, 4]) @ stewart.axis_rotation("Z", x[s, 5])
        A = np.vstack([n.T, np.cross(b @ R.T, n).T])
        want = np.linalg.solve(A, -np.array([0.0, 0.0, -9.81 * 10.0, 0.0, 0.0, 0.0]))
        assert np.abs(u[s] - want).max() <= 1e-5 * np.abs(want).max()


def test_a_floating_base_is_refused_naming_the_option_or_welded_with_it(tmp_path, capsys):
    """The five-bar of tests/test_import.py on a free body (a robot's floating pelvis, its loop
    inside): refused with the option named; welded with it, the same mechanism as on the ground."""
    from test_import import five_bar_mjcf

    plain = five_bar_mjcf()
    body = plain[plain.index("<worldbody>") + len("<worldbody>"):plain.index("</worldbody>")]
    floating = plain.replace(body, '<body name="pelvis" pos="0 0 0"><freejoint name="root"/>'
                                   '<inertial pos="0 0 0.1" mass="5" diaginertia="0.1 0.1 0.1"/>' + body + "</body>")
    code, out = _import(tmp_path, floating, "--task-point", "tool", name="floating")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "joint root: a free joint whose body no loop closure holds" in err[0]
    assert "--weld-free" in err[0] and not out.exists()
    code, welded = _import(tmp_path, floating, "--task-point", "tool", "--weld-free", name="welded")
    assert code == 0 and "welded to the ground at its reference pose (--weld-free)" in capsys.readouterr().err
    code, ground = _import(tmp_path, plain, "--task-point", "tool", name="ground")
    assert code == 0
    m1, m0 = load_mechanism(welded), load_mechanism(ground)
    assert m1.actuator_names == m0.actuator_names and m1.task_names == m0.task_names
    x = reference_task(m0) + np.array([[0.01, -0.02], [-0.015, 0.01]])[:, :m0.nt]
    k0, k1 = solve_kinematics(m0, x), solve_kinematics(m1, x)
    np.testing.assert_allclose(k1.act_q, k0.act_q, rtol=0, atol=1e-12)
    u0, u1 = (joint_reactions(m, k, overconstrained="minimum-norm").u for m, k in ((m0, k0), (m1, k1)))
    np.testing.assert_allclose(u1, u0, rtol=1e-12, atol=1e-12)


def test_every_refusal_of_a_file_in_one_line(tmp_path, capsys):
    xml = stewart_free_xml()
    xml = xml.replace("<equality>", '<tendon><fixed name="band" stiffness="30"><joint joint="p1" coef="1"/>'
                                     '</fixed></tendon>\n  <equality>')
    xml = xml.replace('<body name="cyl2" pos=', '<body name="cyl2" gravcomp="1" pos=')
    xml = xml.replace('<motor name="m3" joint="p3"/>', '<motor name="m3" joint="p3" gear="1e-300"/>')
    xml = xml.replace("</equality>", '  <joint joint1="p4" joint2="p5"/>\n  </equality>')
    code, out = _import(tmp_path, xml)
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and not out.exists()
    for words in ("4 refusals:", "tendon band: a tendon's spring", "body cyl2: gravity compensation",
                  "actuator m3: gear 1e-300", "a joint equality has no equivalent"):
        assert words in err[0], err[0]


def test_mujocos_warnings_stay_out_of_the_working_folder(tmp_path, capsys, monkeypatch):
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    xml = re.sub(r'<site name="s1" pos="[^"]*"', '<site name="s1" pos="nan 0 0"', stewart_free_xml())
    assert 'pos="nan 0 0"' in xml
    src = tmp_path / "nan.xml"
    src.write_text(xml)
    code = main(["import", "--from", str(src), "--out", str(tmp_path / "nan.toml")])
    capsys.readouterr()
    assert code == 2 and list(work.iterdir()) == []
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()


def test_a_ball_joints_damping_is_its_viscous_friction(tmp_path, capsys):
    """Leg 1 on a ball joint at the base (an S-P-S leg, its spin idle) with damping and dry
    friction: the spherical joint's viscous and Coulomb friction, the same numbers."""
    xml = stewart_free_xml()
    start = xml.index('<joint name="u1a"')
    end = xml.index("\n", xml.index('<joint name="u1b"'))
    xml = xml[:start] + '<joint name="u1" type="ball" damping="0.7" frictionloss="0.2"/>' + xml[end:]
    code, out = _import(tmp_path, xml)
    assert code == 0, capsys.readouterr().err
    ball = next(j for j in tomllib.loads(out.read_text())["joints"] if j["name"] == "u1")
    assert ball["type"] == "spherical" and ball["friction"] == {"viscous_Nm_s_rad": 0.7, "coulomb_torque_Nm": 0.2}
    m = load_mechanism(out)
    assert m.topology.dof == 6 and m.topology.idle == 1


def test_a_loop_left_open_in_the_file_is_closed_by_assemble(tmp_path, capsys):
    """The platform written 2 mm above where the legs meet it (as a published keyframe may leave
    a loop open): refused naming --assemble; with it, closed by least change and the same
    mechanism as the closed file (the closed-form leg lengths at poses of the platform)."""
    xml = stewart_free_xml()
    a, b, home = stewart.default_geometry()
    opened = xml.replace(f'<body name="platform" pos="{_fmt(home)}">',
                         f'<body name="platform" pos="{_fmt(home + [0.0, 0.0, 0.002])}">')
    assert opened != xml
    code, out = _import(tmp_path, opened, name="open")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "0.002 m apart" in err[0] and "--assemble" in err[0]
    code, out = _import(tmp_path, opened, "--assemble", name="open")
    assert code == 0 and "the loops closed from the file's configuration (--assemble; they were 0.002 m" in \
        capsys.readouterr().err
    m = load_mechanism(out)
    rng = np.random.default_rng(9)
    x = reference_task(m) + rng.uniform(-1, 1, (6, 6)) * [0.04, 0.04, 0.04, 0.05, 0.05, 0.08]
    order = [m.actuator_names.index(f"p{i + 1}") for i in range(6)]
    ref = stewart.inverse_kinematics(a, b, x[:, :3], x[:, 3:], "XYZ")
    np.testing.assert_allclose(solve_kinematics(m, x).act_q[:, order], ref["L"], rtol=0, atol=1e-11)


def _with_asset(asset, geom):
    """The free-platform Stewart with ``asset`` in an ``<asset>`` element and ``geom`` on its
    platform."""
    xml = stewart_free_xml().replace("<worldbody>", f"<asset>{asset}</asset>\n  <worldbody>", 1)
    return xml.replace('<freejoint name="float"/>', f'<freejoint name="float"/>{geom}')


def _beside_plain(tmp_path, capsys, xml, note):
    """``xml`` imported (saying ``note``) and the plain free-platform Stewart: both descriptions."""
    code, out = _import(tmp_path, xml, name="variant")
    err = capsys.readouterr().err
    assert code == 0, err
    assert note in err
    code, plain = _import(tmp_path, stewart_free_xml(), name="plain")
    assert code == 0
    capsys.readouterr()
    return tuple(tomllib.loads(p.read_text()) for p in (out, plain))


def test_missing_mesh_files_where_the_inertia_is_given(tmp_path, capsys):
    """A model published without its mesh files: where each body gives its <inertial>, the mesh
    geoms are left out (said) and the mechanism is the one without them; a body whose inertia
    the missing mesh would give is refused by name."""
    meshed = _with_asset('<mesh name="plate" file="meshes/plate.stl"/>', '<geom type="mesh" mesh="plate"/>')
    a, b = _beside_plain(tmp_path, capsys, meshed, "mesh files missing (meshes/plate.stl): their geoms left out of "
                                                   "bodies platform")
    assert [bd["mass_kg"] for bd in a["bodies"]] == [bd["mass_kg"] for bd in b["bodies"]]
    no_inertial = meshed.replace('<inertial pos="0 0 0" mass="10.0" diaginertia="0.625 0.625 1.25"/>', "")
    assert no_inertial != meshed
    code, out = _import(tmp_path, no_inertial, name="guessed")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "body platform: its inertia would come from mesh plate" in err[0]


def test_a_missing_texture_only_colours_and_is_left_out(tmp_path, capsys):
    """A model published without its texture image (Menagerie's Cassie names one from its
    material): the texture is left out (said), the material and the mechanism stay."""
    textured = _with_asset('<texture name="skin" file="assets/skin.png" type="2d"/>'
                           '<material name="skin" texture="skin" rgba="1 0 0 1"/>',
                           '<geom type="sphere" size="0.05" material="skin" mass="0"/>')
    a, b = _beside_plain(tmp_path, capsys, textured, "texture files missing (assets/skin.png): left out")
    assert a["bodies"] == b["bodies"] and a["joints"] == b["joints"]


def test_a_floor_mesh_and_inertia_from_geoms(tmp_path, capsys):
    """A missing mesh on the world (a floor) decides no inertia and is left out; with
    inertiafromgeom="true" every body's inertia comes from its geoms, so a missing mesh on a
    moving body is refused even beside an <inertial>."""
    xml = stewart_free_xml().replace("<worldbody>", '<asset><mesh name="floor" file="floor.stl"/>'
                                                    '<mesh name="plate" file="plate.stl"/></asset>\n  <worldbody>'
                                                    '\n    <geom type="mesh" mesh="floor"/>', 1)
    code, _ = _import(tmp_path, xml, name="floor")
    assert code == 0 and "mesh files missing (floor.stl, plate.stl): their geoms left out of bodies world" in \
        capsys.readouterr().err
    both = xml.replace('<freejoint name="float"/>', '<freejoint name="float"/><geom type="mesh" mesh="plate"/>')
    both = both.replace('<compiler angle="radian"/>', '<compiler angle="radian" inertiafromgeom="true"/>')
    code, _ = _import(tmp_path, both, name="fromgeoms")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "body platform: its inertia would come from mesh plate" in err[0]
    assert 'drop inertiafromgeom="true"' in err[0]


def test_two_free_bodies_held_only_by_each_other_float(tmp_path, capsys):
    xml = """<mujoco model="pair">
  <worldbody>
    <body name="a" pos="0 0 1"><freejoint name="fa"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>
    <body name="b" pos="0.5 0 1"><freejoint name="fb"/><inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>
  </worldbody>
  <equality><connect body1="a" body2="b" anchor="0.25 0 0"/></equality>
</mujoco>"""
    code, out = _import(tmp_path, xml, name="pair")
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "2 refusals" in err[0]
    assert "joint fa: a free joint whose body no loop closure holds" in err[0] and "joint fb" in err[0]
    assert "--weld-free" in err[0] and not out.exists()

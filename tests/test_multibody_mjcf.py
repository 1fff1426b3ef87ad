"""MJCF export of described mechanisms, checked in MuJoCo: body poses, loop closure, the mass
matrix, and the tree's Newton-Euler generalised forces against MuJoCo's own (M qacc + bias)."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import ParameterError
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics
from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos

mujoco = pytest.importorskip("mujoco")

CASES = {"stewart": lambda: ex.builtin_dict("stewart"), "delta": lambda: ex.builtin_dict("delta"),
         "bennett": lambda: ex.builtin_dict("bennett"), "four_bar_cut_b": ex.four_bar_cut_b,
         "stewart_flipped_spheres": ex.stewart_flipped_spheres, "rssr": ex.rssr}


@pytest.mark.parametrize("name", sorted(CASES))
def test_export_matches_in_mujoco(name):
    m = load_mechanism(CASES[name]())
    mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
    md = mujoco.MjData(mm)
    o = mujoco_order(m, mm)
    t = np.linspace(0.0, 0.5, 4)
    amp = np.where(m.task_kind == 1, 0.04, 0.02 * m.length_scale)
    x, xd, xdd = ex.smooth_motion(reference_task(m), amp, t, 0)
    kin = solve_kinematics(m, x, xd, xdd, t)
    Q = inverse_dynamics(m, kin).Q
    ids = [mm.body(nm).id for nm in m.body_names]
    for s in range(len(t)):
        md.qpos[:] = mujoco_qpos(m, kin.q[s], mm)
        md.qvel[o] = kin.qd[s]
        mujoco.mj_forward(mm, md)
        for b in range(m.nb):
            assert np.abs(md.xpos[ids[b]] - kin.origin[s, b]).max() < 1e-12 * m.length_scale
            assert np.abs(md.xmat[ids[b]].reshape(3, 3) - kin.R[s, b]).max() < 1e-12
        if md.ne:
            assert np.abs(md.efc_pos[:md.ne]).max() < 1e-9 * m.length_scale  # the loops are closed
        M = np.zeros((mm.nv, mm.nv))
        mujoco.mj_fullM(mm, md, M)
        qa = np.zeros(mm.nv)
        qa[o] = kin.qdd[s]
        Q_mj = (M @ qa + md.qfrc_bias)[o]
        assert np.abs(Q_mj - Q[s]).max() <= 1e-10 * np.abs(Q[s]).max()


def test_cut_joints_that_mujoco_cannot_express_are_refused():
    d = ex.four_bar()
    d["joints"][3]["type"] = "universal"
    d["joints"][3]["axes"] = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    del d["joints"][3]["axis"]
    m = load_mechanism(d)
    if not m.joint_cut[3]:
        pytest.skip("the universal joint is in the tree")
    with pytest.raises(ParameterError, match=r"\[joints\] D: a cut universal joint cannot be written"):
        mechanism_mjcf(m)


def test_export_command_writes_a_model_mujoco_loads(tmp_path, capsys):
    from pkmdyn.cli import main

    out = tmp_path / "stewart.xml"
    assert main(["export", "--machine", "stewart", "--format", "mjcf", "--out", str(out)]) == 0
    mm = mujoco.MjModel.from_xml_path(str(out))
    assert mm.neq == 5 and mm.nu == 6


def test_export_command_refuses_an_inexpressible_cut_joint(tmp_path, capsys):
    import test_multibody_dynamics as td

    from pkmdyn.cli import main

    d = ex.four_bar()
    d["joints"][3]["type"] = "universal"
    d["joints"][3]["axes"] = [[0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]
    del d["joints"][3]["axis"]
    src = tmp_path / "fb.toml"
    src.write_text(td._toml(d))
    out = tmp_path / "fb.xml"
    assert main(["export", "--machine", str(src), "--format", "mjcf", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "D: a cut universal joint" in err[0]
    assert not out.exists()


def test_drives_export_as_gear_armature_and_damping_and_give_the_motor_torques():
    """A Stewart platform on ball screws (rotor inertia, viscous motor friction) in MuJoCo: each
    motor's gear is the transmission ratio k, each actuated joint's armature k^2 I_r and damping
    k^2 b; MuJoCo's tree forces (M qacc + bias - passive, its armature and damping included)
    projected through the loop closure give the motor torques pkmdyn computes (Eq. A1)."""
    from pkmdyn.multibody.dynamics.actuators import motor_efforts
    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

    d = ex.builtin_dict("stewart")
    for leg in d["legs"]:
        leg["actuators"] = [{"joint": "P", "name": "M", "screw_lead_m": 0.004, "gear_ratio": 3.0,
                             "rotor_inertia_kgm2": 4e-5, "viscous_Nm_s_rad": 3e-4}]
    m = load_mechanism(d)
    mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
    md = mujoco.MjData(mm)
    k = 3.0 * 2 * np.pi / 0.004
    assert np.allclose(mm.actuator_gear[:, 0], k)
    assert [mm.actuator(i).name for i in range(mm.nu)] == list(m.drive_name)
    o = mujoco_order(m, mm)
    t = np.linspace(0.0, 0.5, 4)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.where(m.task_kind == 1, 0.04, 0.02), t, 1)
    kin = solve_kinematics(m, x, xd, xdd, t)
    tau = motor_efforts(m, kin.act_q, kin.act_qd, kin.act_qdd, joint_reactions(m, kin).u).effort
    for s in range(len(t)):
        md.qpos[:] = mujoco_qpos(m, kin.q[s], mm)
        md.qvel[o] = kin.qd[s]
        mujoco.mj_forward(mm, md)
        M = np.zeros((mm.nv, mm.nv))
        mujoco.mj_fullM(mm, md, M)
        qa = np.zeros(mm.nv)
        qa[o] = kin.qdd[s]
        Q = (M @ qa + md.qfrc_bias - md.qfrc_passive)[o]
        # J_ax^T k tau = G^T Q (the virtual work of the motors through the loop closure)
        tau_mj = np.linalg.solve(kin.J_ax[s].T * k, kin.G[s].T @ Q)
        assert np.abs(tau_mj - tau[s]).max() <= 1e-9 * np.abs(tau[s]).max()


@pytest.mark.parametrize("name", ["stewart", "delta"])
def test_joint_limits_export_as_ranges_of_mujocos_coordinate(name):
    """A limited tree joint is ``limited`` in MuJoCo with its range in MuJoCo's coordinate
    (:func:`mujoco_qpos`): the limits themselves land on the range's ends; unlimited joints
    stay unlimited; every joint's ``qpos0`` (its ``ref``) is the tree coordinate's reference value."""
    m = load_mechanism(CASES[name]())
    mm = mujoco.MjModel.from_xml_string(mechanism_mjcf(m))
    cut = set(m.loop_joint.tolist())
    limited = 0
    for j, lim in enumerate(m.joint_limits):
        if m.joint_nq[j] != 1 or j in cut:  # (a cut joint is an equality constraint in MuJoCo)
            continue
        jid = mm.joint(m.joint_names[j]).id
        if lim is None:
            assert not mm.jnt_limited[jid]
            continue
        limited += 1
        assert mm.jnt_limited[jid]
        c = int(m.joint_q0[j])
        for q_value, end in ((lim[0], 0), (lim[1], 1)):
            q = m.coord_offset.copy()
            q[c] = q_value
            assert mujoco_qpos(m, q, mm)[mm.jnt_qposadr[jid]] == pytest.approx(mm.jnt_range[jid, end], abs=1e-12)
    assert limited == sum(lim is not None for j, lim in enumerate(m.joint_limits) if j not in cut) > 0
    np.testing.assert_allclose(mm.qpos0, mujoco_qpos(m, m.coord_offset, mm), rtol=0, atol=1e-15)

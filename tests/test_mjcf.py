"""The hip's MJCF export (the engine's writer, :mod:`pkmdyn.multibody.formats.mjcf_out`, on the hip's
description) against MuJoCo: inverse dynamics, forward dynamics, loop closure, command line."""

from __future__ import annotations

import dataclasses
import re
import sys

import numpy as np
import pytest

from hip_helpers import random_model
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError
from pkmdyn.machines.hip_simulator.description import hip_description
from pkmdyn.machines.hip_simulator.params import DEFAULT_PARAMS_TEXT, load_params
from pkmdyn.multibody import load_mechanism, solve_kinematics
from pkmdyn.multibody.dynamics.verbs import machine_verbs
from pkmdyn.multibody.formats.mjcf_out import mechanism_mjcf, mujoco_order, mujoco_qpos

mujoco = pytest.importorskip("mujoco")

#: the mass the export gives the massless platforms (their centres of mass on their fixed ball joints)
PLATFORM_MASS_KG = 1e-3


def _frictionless(model):
    return dataclasses.replace(model, friction=dataclasses.replace(model.friction, mu_h=0.0, mu_t=0.0))


def _models():
    rng = np.random.default_rng(3)
    yield _frictionless(load_params())
    for _ in range(2):
        # a slender rod: I_xx and I_yy within I_zz of each other (a physical rigid body)
        i_zz = 5e-4 * rng.uniform(0.5, 2.0)
        i_xx = 0.026 * rng.uniform(0.9, 1.1)
        lever = [i_xx, i_xx + i_zz * rng.uniform(-0.9, 0.9), i_zz]
        yield _frictionless(random_model(rng, inertia={"lever_inertia_kgm2": lever}, euler_sequence=str(rng.choice(["XYZ", "zyx"]))))


def _mujoco(model):
    """The compiled description and its MuJoCo model (the export of ``pkmdyn hip export``)."""
    mech = load_mechanism(hip_description(model))
    return mech, mujoco.MjModel.from_xml_string(mechanism_mjcf(mech, massless_kg=PLATFORM_MASS_KG))


def _states(mech, mj, rng: np.random.Generator, n: int):
    """Angles, rates and accelerations of the platforms, MuJoCo's ``qpos, qvel, qacc`` of them
    (the tree coordinates of the engine's kinematics) and the engine's motor torques."""
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3))
    qd[0] = 0.0
    qdd = rng.uniform(-20.0, 20.0, (n, 3))
    kin = solve_kinematics(mech, q, qd, qdd)
    idx = mujoco_order(mech, mj)
    qpos = np.array([mujoco_qpos(mech, kin.q[k], mj) for k in range(n)])
    qvel, qacc = np.empty((n, mj.nv)), np.empty((n, mj.nv))
    qvel[:, idx], qacc[:, idx] = kin.qd, kin.qdd
    tau = machine_verbs(mech).inverse_dynamics(mech, q, qd, qdd, np.zeros(n))
    return kin, qpos, qvel, qacc, tau


def _actuator_columns(mj_model) -> np.ndarray:
    """``B (nv, nu)``: generalised forces of unit controls, from MuJoCo's own transmission data."""
    B = np.zeros((mj_model.nv, mj_model.nu))
    for a in range(mj_model.nu):
        B[mj_model.jnt_dofadr[mj_model.actuator_trnid[a, 0]], a] = mj_model.actuator_gear[a, 0]
    return B


def test_mj_inverse_actuator_forces_match_friction_free_inverse_dynamics() -> None:
    """At consistent states, MuJoCo's ``qfrc_inverse`` (21 dof) splits into actuator forces and
    loop-closure forces, ``qfrc_inverse = B u + G^T lambda`` with MuJoCo's constraint Jacobian
    ``G = efc_J``. The softness of MuJoCo's constraints changes only ``lambda`` (its constraint
    force lies in the range of ``G^T``), so ``u`` must equal the engine's motor torques."""
    rng = np.random.default_rng(5)
    for model in _models():
        mech, mj = _mujoco(model)
        assert (mj.nq, mj.nv, mj.nu, mj.neq) == (21, 21, 3, 6)
        data = mujoco.MjData(mj)
        _, qpos, qvel, qacc, tau = _states(mech, mj, rng, 6)
        B = _actuator_columns(mj)
        for k in range(len(tau)):
            data.qpos[:], data.qvel[:], data.qacc[:] = qpos[k], qvel[k], qacc[k]
            mujoco.mj_inverse(mj, data)
            G = data.efc_J.reshape(data.nefc, mj.nv)
            assert data.nefc == 18
            # the state closes every loop in position, velocity and acceleration
            assert np.abs(data.efc_pos).max() < 1e-10
            assert np.abs(G @ qvel[k]).max() < 1e-10 * (1 + np.abs(qvel[k]).max())
            x = np.linalg.solve(np.hstack((B, G.T)), data.qfrc_inverse)
            np.testing.assert_allclose(x[:3], tau[k], rtol=0, atol=1e-8 * np.abs(tau[k]).max())


def test_mj_forward_accelerations_within_soft_constraint_accuracy() -> None:
    """The engine's motor torques applied in MuJoCo give back the upper platform's coordinate
    accelerations, to the accuracy MuJoCo's soft loop constraints allow at their stiffest
    impedance (0.9999); the bound is 2e-3 relative."""
    rng = np.random.default_rng(6)
    for model in _models():
        mech, mj = _mujoco(model)
        mj.eq_solref[:] = [1e-4, 1.0]
        data = mujoco.MjData(mj)
        kin, qpos, qvel, _, tau = _states(mech, mj, rng, 4)
        upper = [c for c, j in enumerate(mech.coord_joint) if mech.joint_names[j] == "S0_upper"]
        dof = mujoco_order(mech, mj)[upper]
        for k in range(len(tau)):
            data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], tau[k]
            mujoco.mj_forward(mj, data)
            err = np.abs(data.qacc[dof] - kin.qdd[k, upper]).max() / np.abs(kin.qdd[k, upper]).max()
            assert err < 2e-3
            assert err > 1e-7  # the constraints are soft: an exact answer here would be suspect


def test_export_needs_physical_inertias(tmp_path, capsys) -> None:
    model = load_params()
    bad = dataclasses.replace(model, inertia=dataclasses.replace(model.inertia, I_l=np.array([0.03, 0.02, 0.005])))
    with pytest.raises(ParameterError, match="lever_upper_1.*triangle inequality"):
        load_mechanism(hip_description(bad))
    p = tmp_path / "bad.toml"
    text = re.sub(r"(?m)^lever_inertia_kgm2 = .*$", "lever_inertia_kgm2 = [0.03, 0.02, 0.005]", DEFAULT_PARAMS_TEXT)
    assert text != DEFAULT_PARAMS_TEXT
    p.write_text(text, encoding="utf-8")
    target = tmp_path / "never.xml"
    capsys.readouterr()
    assert main(["hip", "export", "--format", "mjcf", "--params", str(p), "--out", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "triangle inequality" in err
    assert not target.exists()


def test_export_needs_no_mujoco(tmp_path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Writing the XML needs nothing of MuJoCo (an optional dependency)."""
    monkeypatch.setitem(sys.modules, "mujoco", None)
    out = tmp_path / "machine.xml"
    assert main(["hip", "export", "--format", "mjcf", "--out", str(out)]) == 0
    assert out.read_text(encoding="utf-8").startswith('<mujoco model="hip">')


def test_cli_export(tmp_path, capsys) -> None:
    out = tmp_path / "sub" / "machine.xml"
    assert main(["hip", "export", "--format", "mjcf", "--out", str(out)]) == 0
    mj = mujoco.MjModel.from_xml_path(str(out))
    assert mj.nv == 21 and mj.nu == 3
    np.testing.assert_allclose(mj.actuator_gear[:, 0], 2 * np.pi / load_params().geometry.p)
    # the same writer as pkmdyn export --machine hip: the same file, the platforms given 1 g
    mech = load_mechanism(hip_description(load_params()))
    assert out.read_text(encoding="utf-8") == mechanism_mjcf(mech, massless_kg=PLATFORM_MASS_KG)
    step = tmp_path / "step.xml"
    assert main(["hip", "export", "--format", "mjcf", "--timestep", "0.0005", "--out", str(step)]) == 0
    assert mujoco.MjModel.from_xml_path(str(step)).opt.timestep == pytest.approx(5e-4)
    # a bad parameter file: one line, exit 2, nothing written
    bad = tmp_path / "bad.toml"
    bad.write_text("[geometry]\nbase_radius_m = -1\n")
    target = tmp_path / "never.xml"
    capsys.readouterr()
    assert main(["hip", "export", "--format", "mjcf", "--params", str(bad), "--out", str(target)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pkmdyn: error:" in err
    assert not target.exists()
    assert main(["hip", "export", "--format", "urdf", "--out", str(target)]) == 2
    assert not target.exists()

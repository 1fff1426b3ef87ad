"""The MJCF export against MuJoCo: inverse dynamics, forward dynamics, loop closure, command line."""

from __future__ import annotations

import dataclasses
import sys

import numpy as np
import pytest

from hip_helpers import random_model
from pkmdyn.cli import main
from pkmdyn.errors import ParameterError, PkmdynError
from pkmdyn.machines.hip_simulator import load_params, minimal
from pkmdyn.machines.hip_simulator.mjcf import load_mujoco, mjcf_string, mujoco_state
from pkmdyn.spatial import euler_kinematics

mujoco = pytest.importorskip("mujoco")


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


def _states(model, rng: np.random.Generator, n: int):
    q = np.deg2rad(rng.uniform(-20.0, 20.0, (n, 3)))
    qd = rng.uniform(-2.0, 2.0, (n, 3))
    qd[0] = 0.0
    qdd = rng.uniform(-20.0, 20.0, (n, 3))
    R, w, wd = euler_kinematics(model.geometry.euler_sequence, q, qd, qdd)
    tau = minimal.inverse_dynamics(model, q, qd, qdd, np.zeros(n))
    return R, w, wd, tau


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
    force lies in the range of ``G^T``), so ``u`` must equal pkmdyn's motor torques exactly."""
    rng = np.random.default_rng(5)
    for model in _models():
        mj = load_mujoco(model)
        assert (mj.nv, mj.nu, mj.neq) == (21, 3, 6)
        data = mujoco.MjData(mj)
        R, w, wd, tau = _states(model, rng, 6)
        qpos, qvel, qacc = mujoco_state(model, mj, R, w, wd)
        B = _actuator_columns(mj)
        for k in range(len(tau)):
            data.qpos[:], data.qvel[:], data.qacc[:] = qpos[k], qvel[k], qacc[k]
            mujoco.mj_inverse(mj, data)
            G = data.efc_J.reshape(data.nefc, mj.nv)
            assert data.nefc == 18
            # the state closes every loop in position, velocity and acceleration
            assert np.abs(data.efc_pos).max() < 1e-12
            assert np.abs(G @ qvel[k]).max() < 1e-12 * (1 + np.abs(qvel[k]).max())
            x = np.linalg.solve(np.hstack((B, G.T)), data.qfrc_inverse)
            np.testing.assert_allclose(x[:3], tau[k], rtol=0, atol=1e-9 * np.abs(tau[k]).max())


def test_mj_forward_accelerations_within_soft_constraint_accuracy() -> None:
    """pkmdyn's motor torques applied in MuJoCo give back the platform's angular acceleration,
    to the accuracy MuJoCo's soft loop constraints allow at their stiffest impedance (0.9999):
    measured 2e-4 to 7e-4 relative (the same with the export's solref); the bound is 2e-3."""
    rng = np.random.default_rng(6)
    for model in _models():
        mj = load_mujoco(model)
        mj.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_REFSAFE
        mj.eq_solref[:] = [1e-4, 1.0]
        data = mujoco.MjData(mj)
        R, w, wd, tau = _states(model, rng, 4)
        qpos, qvel, _ = mujoco_state(model, mj, R, w, wd)
        dof = mj.joint("platform1").dofadr[0]
        for k in range(len(tau)):
            data.qpos[:], data.qvel[:], data.ctrl[:] = qpos[k], qvel[k], tau[k]
            mujoco.mj_forward(mj, data)
            wd_mj = R[k] @ data.qacc[dof : dof + 3]
            err = np.abs(wd_mj - wd[k]).max() / np.abs(wd[k]).max()
            assert err < 2e-3
            assert err > 1e-7  # the constraints are soft: an exact answer here would be suspect


def test_export_needs_physical_inertias() -> None:
    model = load_params()
    bad = dataclasses.replace(model, inertia=dataclasses.replace(model.inertia, I_l=np.array([0.03, 0.02, 0.005])))
    with pytest.raises(ParameterError, match="lever_inertia_kgm2"):
        mjcf_string(bad)


def test_missing_mujoco_is_a_clear_error(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(PkmdynError, match=r"pip install 'pkmdyn\[validate\]'"):
        load_mujoco(load_params())


def test_cli_export(tmp_path, capsys) -> None:
    out = tmp_path / "sub" / "machine.xml"
    assert main(["hip", "export", "--format", "mjcf", "--out", str(out)]) == 0
    mj = mujoco.MjModel.from_xml_path(str(out))
    assert mj.nv == 21 and mj.nu == 3
    np.testing.assert_allclose(mj.actuator_gear[:, 0], 2 * np.pi / load_params().geometry.p)
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

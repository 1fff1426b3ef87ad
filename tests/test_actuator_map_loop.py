"""The batched actuator map along a motion by the single-sample kernel's compiled loop
(``verbs.actuator_map``, :func:`pkmdyn.multibody.dynamics._sample_kernels.actuator_maps`) against the
batched solver's own (the route below ``MAP_SAMPLES`` poses)."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.errors import PkmdynError
from pkmdyn.multibody import load_mechanism, reference_task
from pkmdyn.multibody.dynamics import verbs as machine_module
from pkmdyn.multibody.dynamics.verbs import MechanismData, machine_verbs

CASES = {"stewart": lambda: ex.builtin_dict("stewart"), "delta": lambda: ex.builtin_dict("delta"),
         "rrr3": lambda: ex.builtin_dict("rrr3"), "stewart_sps": ex.stewart_sps}


def _motion(m, n=120, seed=7):
    t = np.linspace(0.0, 1.0, n)
    amp = np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale)
    return ex.smooth_motion(reference_task(m), amp, t, seed)[0]


def _checked(m, x, monkeypatch):
    with monkeypatch.context() as mp:
        mp.setattr(machine_module, "MAP_SAMPLES", 10**9)
        return machine_verbs(m).actuator_map(m, x)


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_loop_equals_the_batched_solver(name, monkeypatch):
    m = load_mechanism(CASES[name]())
    x = _motion(m)
    V = machine_verbs(m)
    assert V._state(m).pk is not None  # the kernel answers for these mechanisms
    B = V.actuator_map(m, x)
    ref = _checked(m, x, monkeypatch)
    assert B.shape == ref.shape == (len(x), m.nt, m.na)
    assert np.abs(B - ref).max() <= 1e-10 * np.abs(ref).max()
    # the last pose is remembered: a single-sample call there starts from it
    q_last = V._state(m).last_q()
    kin = machine_module._kin(m, MechanismData(m), x[-1:])
    assert np.abs(q_last - kin.q[0]).max() <= 1e-9 * max(1.0, np.abs(kin.q[0]).max())


def test_the_hip_map_along_its_cycle():
    from pkmdyn.machines.hip_simulator import control_job
    from pkmdyn.machines.hip_simulator.params import load_params
    from pkmdyn.profiles.iso14242 import iso14242_motion

    cm = control_job.control_model(load_params())
    verbs = control_job.verbs(cm)
    q = iso14242_motion(cycles=1.0, samples_per_cycle=400).angles
    B = verbs.actuator_map(cm, q)
    m = cm.mechanism
    kin = machine_module._kin(m, MechanismData(m), q)
    ref = np.swapaxes(kin.J_ax, 1, 2) * m.drive_ratio
    assert np.abs(B - ref).max() <= 1e-10 * np.abs(ref).max()


def test_an_unreachable_pose_gives_the_checked_error(monkeypatch):
    m = load_mechanism(ex.builtin_dict("delta"))
    x = _motion(m)
    x[60:] += 10.0 * m.length_scale  # out of reach from sample 60 on
    with pytest.raises(PkmdynError) as fast:
        machine_verbs(m).actuator_map(m, x)
    with pytest.raises(PkmdynError) as checked:
        _checked(m, x, monkeypatch)
    assert type(fast.value) is type(checked.value)
    assert "60" in str(fast.value) and "60" in str(checked.value)


@pytest.mark.parametrize("name", sorted(CASES))
def test_repeated_and_near_repeated_poses_keep_the_map(name, monkeypatch):
    """The kernel's predictor takes its second-order term from the path the solutions took: a pose
    given twice, one a hair (1e-12 of a step) past the one before, or a jump back along the path
    leave the map as the batched solver has it."""
    m = load_mechanism(CASES[name]())
    x = _motion(m)
    near = x[80] + 1e-12 * (x[81] - x[80])
    x = np.concatenate([x[:41], x[40:41], x[41:81], near[None], x[81:], x[30:40]])
    B = machine_verbs(m).actuator_map(m, x)
    ref = _checked(m, x, monkeypatch)
    assert np.abs(B - ref).max() <= 1e-10 * np.abs(ref).max()
    # and the kernel itself solves every pose, none left to the checked route
    from pkmdyn.multibody.dynamics import _sample_kernels as one

    pk = one.pack(m)
    kin = machine_module._kin(m, MechanismData(m), x[:1])
    one.prime(pk, kin.q[0], kin.x[0], kin.G[0])
    steps = np.diff(x, axis=0)
    out = np.empty((len(x) - 1, m.na * m.nt))
    assert one.actuator_maps(pk, x[1:], steps, out) == len(x) - 1
    mine = np.swapaxes(out.reshape(-1, m.na, m.nt), 1, 2) * m.drive_ratio  # J_ax^T K, as the verb gives it
    assert np.abs(mine - ref[1:]).max() <= 1e-10 * np.abs(ref).max()


@pytest.mark.parametrize("tiny", [1e-300, 1e-200, 1e-160, 1e-100])
def test_a_step_below_rounding_along_the_path_keeps_the_map(tiny, monkeypatch):
    """Poses ``tiny`` metres past each other along the path after steps of 0.5 mm (a curvature
    measured over such a step is rounding, or its square underflows): the map stays finite and
    the batched solver's, with no error."""
    m = load_mechanism(CASES["delta"]())
    x = np.tile(reference_task(m), (43, 1))
    x[:40, 0] += np.linspace(-20e-3, 0.0, 40)  # steps of 0.5 mm along x, then two of tiny metres, then 1 mm
    x[40:, 0] += np.array([tiny, 2.0 * tiny, 1e-3])
    B = machine_verbs(m).actuator_map(m, x)
    ref = _checked(m, x, monkeypatch)
    assert np.all(np.isfinite(B))
    assert np.abs(B - ref).max() <= 1e-10 * np.abs(ref).max()


def test_uneven_steps_keep_the_map(monkeypatch):
    """Steps alternately a whole and a third of the motion's sampling: the map is the batched
    solver's, and the kernel solves every pose."""
    m = load_mechanism(CASES["delta"]())
    t = np.sort(np.concatenate([np.linspace(0.0, 1.0, 121), np.linspace(0.0, 1.0, 121)[:-1] + 1.0 / 360.0]))
    x = ex.smooth_motion(reference_task(m), np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale), t, 7)[0]
    B = machine_verbs(m).actuator_map(m, x)
    ref = _checked(m, x, monkeypatch)
    assert np.abs(B - ref).max() <= 1e-10 * np.abs(ref).max()

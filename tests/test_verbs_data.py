"""The single-sample verbs as free functions over ``(model, data)``
(:mod:`pkmdyn.multibody.dynamics.verbs`): all they keep between calls is in ``data``, so two
loops on one model with two ``data`` do not see each other, and the methods of
:class:`MechanismVerbs` are the same functions."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.multibody.dynamics import verbs as V


def _path(m, seed, n=30):
    t = np.linspace(0.0, 0.3, n)
    amp = np.where(m.task_kind == 1, 0.05, 0.03 * m.length_scale)
    return ex.smooth_motion(reference_task(m), amp, t, seed)


@pytest.mark.parametrize("name", ["stewart", "delta"])
def test_two_data_on_one_model_are_two_loops(name):
    m = load_mechanism(ex.builtin_dict(name))
    paths = []
    for seed in (3, 11):
        x, xd, xdd = _path(m, seed)
        kin = solve_kinematics(m, x, xd, xdd)
        u = V.inverse_dynamics(m, V.MechanismData(m), x, xd, xdd)
        paths.append((x, xd, xdd, u, kin))
    alone = []
    for x, xd, _, u, _ in paths:
        d = V.MechanismData(m)
        alone.append(np.array([_run_one(m, d, x, xd, u, k) for k in range(len(x))]))
    # the two loops interleaved, sample by sample, each with its own data
    d1, d2 = V.MechanismData(m), V.MechanismData(m)
    (x1, xd1, _, u1, _), (x2, xd2, _, u2, _) = paths
    both = [[], []]
    for k in range(len(x1)):
        for j, (d, x, xd, u) in enumerate(((d1, x1, xd1, u1), (d2, x2, xd2, u2))):
            both[j].append(_run_one(m, d, x, xd, u, k))
    for j in range(2):
        np.testing.assert_array_equal(np.array(both[j]), alone[j])
        # and the loop is right: forward(inverse) the path's accelerations, the direct kinematics its poses
        x, xd, xdd, u, kin = paths[j]
        nt, na = m.nt, m.na
        assert np.abs(alone[j][:, :nt] - xdd).max() <= 1e-8 * max(np.abs(xdd).max(), 1.0)
        assert np.abs(alone[j][:, nt:nt + na] - kin.act_q).max() <= 1e-10
        assert np.abs(alone[j][:, nt + na:2 * nt + na] - x).max() <= 1e-9


def _run_one(m, data, x, xd, u, k):
    a = V.actuator_coordinates_one(m, data, x[k], xd[k], fresh=(k == 0))
    return np.concatenate([V.forward_dynamics_one(m, data, x[k], xd[k], u[k]), a,
                           *V.direct_one(m, data, a, np.zeros(m.na))])


def test_the_methods_are_the_functions_with_the_models_data():
    m = load_mechanism(ex.builtin_dict("stewart"))
    x, xd, xdd = _path(m, 5)
    verbs = V.machine_verbs(m)
    data = V.MechanismData(m)
    for k in range(len(x)):
        np.testing.assert_array_equal(verbs.inverse_dynamics_one(m, x[k], xd[k], xdd[k]),
                                      V.inverse_dynamics_one(m, data, x[k], xd[k], xdd[k]))
    np.testing.assert_array_equal(verbs.mass_matrix(m, x), V.mass_matrix(m, data, x))
    assert verbs.data(m) is verbs.data(m) and verbs.data(m) is not data

"""A warm start out of the first sample's reach (tree coordinates from another part of a motion,
as a machine's verbs keep between calls) falls back to the start from the reference
configuration: the same solution as without a warm start, not an unreachable-pose error."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.machines.hip_simulator.description import hip_description
from pkmdyn.machines.hip_simulator.params import default_params_dict, model_from_dict
from pkmdyn.multibody import load_mechanism, solve_kinematics
from pkmdyn.multibody.kinematics import inverse as kin_module


@pytest.fixture(scope="module")
def model():
    d = default_params_dict()
    d["geometry"]["euler_sequence"] = "ZXY"
    return load_mechanism(hip_description(model_from_dict(d, "ZXY")))


def test_a_start_out_of_reach_gives_the_solution_without_one(model):
    x = np.array([[0.4363, 0.0156, 0.0156], [0.44, 0.02, 0.01]])
    plain = solve_kinematics(model, x)
    far = plain.q[0] + np.where(np.arange(model.nq) % 2 == 0, 2.5, -2.5)  # far from every branch nearby
    # the warm start alone does not reach the first sample (what makes the fallback needed)
    out = kin_module._run(model, x, np.zeros_like(x), np.zeros_like(x), np.ascontiguousarray(far), None)
    assert out["status"][0] != kin_module.K.OK
    got = solve_kinematics(model, x, q_start=far)
    np.testing.assert_allclose(got.q, plain.q, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.act_q, plain.act_q, rtol=0, atol=1e-12)


def test_a_start_within_reach_is_still_followed(model, monkeypatch):
    """A warm start near a solution is kept: the start from the reference configuration is not
    even looked for (the fallback only acts on a failure)."""
    x = np.array([[0.1, 0.02, -0.03]])
    plain = solve_kinematics(model, x)

    def no_reference_start(*args, **kwargs):
        raise AssertionError("the reference start was looked for")

    monkeypatch.setattr(kin_module, "_start", no_reference_start)
    got = solve_kinematics(model, x, q_start=plain.q[0] + 1e-6)
    np.testing.assert_allclose(got.q, plain.q, rtol=0, atol=1e-10)
    with pytest.raises(AssertionError, match="reference start"):  # the probe does bite
        solve_kinematics(model, x)

"""The hip's paper view (machines/hip_simulator/paper.py: the engine's solve named as the paper
does) against the closed form of Eq. 1-16 (tests/oracles/hip.py), quantity by quantity: the
slider motions of both platforms, the Jacobian measures of Eq. 3, the motor torques and each
part of Eq. 14, the bearing friction of Eq. 16 and the motors' power."""

from __future__ import annotations

import numpy as np
import pytest

from hip_helpers import random_model
from oracles import hip
from pkmdyn.machines.hip_simulator import PaperView, load_params
from pkmdyn.profiles.iso14242 import iso14242_motion

PARTS = ("platform", "lever", "slider", "screw", "friction")


def _rel(a, b):
    return float(np.abs(np.asarray(a) - np.asarray(b)).max() / max(float(np.abs(b).max()), 1e-300))


@pytest.mark.parametrize("seed", [None, 3, 4])
def test_the_paper_view_is_the_closed_form(seed):
    model = load_params() if seed is None else random_model(np.random.default_rng(seed), friction=True)
    motion = iso14242_motion(cycles=1, samples_per_cycle=300)
    got = PaperView(model).solve(motion)
    kin = hip.kinematics(model, motion.angles, motion.rates, motion.accels)
    ref = hip.inverse_dynamics(model, kin, motion.load)
    tol = 1e-9
    assert _rel(got.L, kin.L) < tol and _rel(got.Ld, kin.Ld) < tol and _rel(got.Ldd, kin.Ldd) < tol
    assert _rel(got.det_Ja, kin.det_Ja) < tol and _rel(got.det_Jb, kin.det_Jb) < tol
    assert _rel(got.cond_J, kin.cond_J) < tol
    assert _rel(got.tau, ref.tau) < tol
    scale = np.abs(ref.tau).max()
    for part in PARTS:  # each part against its own, to the torques' scale where a part is small
        assert np.abs(got.parts[part] - getattr(ref, part)).max() < tol * max(np.abs(getattr(ref, part)).max(),
                                                                             1e-3 * scale), part
    assert _rel(got.hip_friction, ref.hip_friction) < tol
    assert _rel(got.power, ref.power) < tol
    # the parts are each other's: swapping two would show
    assert _rel(got.parts["platform"], ref.lever) > 1e-3 and _rel(got.parts["lever"], ref.platform) > 1e-3

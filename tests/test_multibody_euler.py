"""Euler-angle task coordinates: the compiled extraction and rate map against pkmdyn.spatial
for every sequence, and a Stewart platform driven in other sequences (extrinsic included)."""

from __future__ import annotations

import numpy as np
import pytest

import multibody_examples as ex
from pkmdyn.multibody.model import _tree_kernels as K
from pkmdyn.multibody import load_mechanism, reference_task, solve_kinematics
from pkmdyn.spatial import euler_kinematics, euler_to_matrix

SEQS = [a + b + c for a in "XYZ" for b in "XYZ" for c in "XYZ" if a != b and b != c]


@pytest.mark.parametrize("seq", SEQS)
def test_extraction_inverts_the_sequence(seq):
    rng = np.random.default_rng(len(seq) + ord(seq[0]) + 7 * ord(seq[2]))
    axes = np.array(["XYZ".index(c) for c in seq], dtype=np.int64)
    proper = seq[0] == seq[2]
    for _ in range(20):
        ang = rng.uniform(-np.pi, np.pi, 3)
        ang[1] = rng.uniform(0.2, np.pi - 0.2) if proper else rng.uniform(-1.3, 1.3)
        R = euler_to_matrix(seq, ang[None])[0]
        out = np.empty(3)
        K.euler_angles(R, axes, out)
        assert np.allclose(out, ang, atol=1e-12)
        E = np.empty((3, 3))
        K.euler_rate_map(ang, axes, E)
        for k in range(3):
            rate = np.zeros((1, 3))
            rate[0, k] = 1.0
            _, w, _ = euler_kinematics(seq, ang[None], rate, np.zeros((1, 3)))
            assert np.allclose(E[:, k], w[0], atol=1e-12)


@pytest.mark.parametrize("seq", ["ZYX", "xyz", "YXZ"])
def test_stewart_in_another_sequence_moves_the_platform_as_asked(seq):
    d = ex.builtin_dict("stewart")
    d["task"]["euler_sequence"] = seq
    m = load_mechanism(d)
    t = np.linspace(0.0, 1.0, 80)
    x, xd, xdd = ex.smooth_motion(reference_task(m), np.array([0.03, 0.03, 0.03, 0.1, 0.15, 0.1]), t, seed=2)
    kin = solve_kinematics(m, x, xd, xdd, t)
    pl = m.body_names.index("platform")
    R, w, wd = euler_kinematics(seq, x[:, 3:], xd[:, 3:], xdd[:, 3:])
    assert np.allclose(kin.R[:, pl], R, atol=1e-11)
    assert np.allclose(kin.w[:, pl], w, atol=1e-10)
    assert np.allclose(kin.wd[:, pl], wd, atol=1e-8)
    # the task point (the platform centre) follows x
    centre = kin.origin[:, pl] + np.einsum("nij,j->ni", kin.R[:, pl], m.task_point)
    assert np.allclose(centre, x[:, :3], atol=1e-11)

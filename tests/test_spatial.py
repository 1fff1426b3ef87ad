import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pkmdyn.errors import ParameterError
from pkmdyn.spatial import cross, euler_kinematics, euler_to_matrix, skew

SEQUENCES = ["XYZ", "ZYX", "ZXZ", "xyz", "zyx", "YXY"]


@pytest.mark.parametrize("seq", SEQUENCES)
def test_euler_matrix_matches_scipy(seq):
    rng = np.random.default_rng(1)
    q = rng.uniform(-1.2, 1.2, (50, 3))
    np.testing.assert_allclose(euler_to_matrix(seq, q), Rotation.from_euler(seq, q).as_matrix(), atol=1e-13)


@pytest.mark.parametrize("seq", SEQUENCES)
def test_angular_velocity_and_acceleration_against_finite_differences(seq):
    rng = np.random.default_rng(2)
    a, w, ph = rng.uniform(0.2, 1.0, 3), rng.uniform(1, 3, 3), rng.uniform(0, 6, 3)

    def q_of(t):
        t = np.atleast_1d(t)[:, None]
        return a * np.sin(w * t + ph), a * w * np.cos(w * t + ph), -a * w**2 * np.sin(w * t + ph)

    t = np.linspace(0, 2, 25)
    h = 1e-6
    R, om, omd = euler_kinematics(seq, *q_of(t))
    Rp, omp, _ = euler_kinematics(seq, *q_of(t + h))
    Rm, omm, _ = euler_kinematics(seq, *q_of(t - h))
    W = ((Rp - Rm) / (2 * h)) @ R.transpose(0, 2, 1)
    np.testing.assert_allclose(W, skew(om), atol=1e-8)
    np.testing.assert_allclose((omp - omm) / (2 * h), omd, atol=1e-7 * (1 + np.abs(omd).max()))


def test_cross_and_bad_sequence():
    rng = np.random.default_rng(3)
    a, b = rng.normal(size=(2, 10, 3))
    np.testing.assert_allclose(cross(a, b), np.cross(a, b), atol=1e-15)
    for bad in ["XXY", "XYz", "AB", "XYZW"]:
        with pytest.raises(ParameterError, match="euler_sequence"):
            euler_to_matrix(bad, np.zeros((1, 3)))

"""The compiled small dense solver shared by the single-sample paths, against numpy's LAPACK."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn._dense import solve_in_place


@pytest.mark.parametrize("m", [1, 3, 4, 9, 14])
def test_solution_determinant_and_pivot_match_lapack(m):
    rng = np.random.default_rng(m)
    for _ in range(20):
        A = rng.normal(size=(m, m)) * rng.uniform(0.1, 10.0, size=m)[:, None]
        b = rng.normal(size=m)
        x = b.copy()
        det, small = solve_in_place(A.copy(), x)
        np.testing.assert_allclose(x, np.linalg.solve(A, b), rtol=1e-9, atol=1e-12 * np.abs(x).max())
        assert det == pytest.approx(np.linalg.det(A), rel=1e-9)
        assert 0.0 < small <= np.abs(A).max()


def test_an_exactly_singular_matrix_reports_zero():
    A = np.array([[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 0.0, 1.0]])
    det, small = solve_in_place(A.copy(), np.ones(3))
    assert det == 0.0 and small == 0.0


def test_a_nearly_singular_matrix_has_a_small_pivot():
    A = np.array([[1.0, 1.0], [1.0, 1.0 + 1e-15]])
    det, small = solve_in_place(A.copy(), np.ones(2))
    assert small < 1e-14

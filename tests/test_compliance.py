"""The general compliance solver (pkmdyn.analysis.compliance) on textbook statically
indeterminate beams: clamped at both ends, loaded between the clamps."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.analysis.compliance import (
    beam_flexibility,
    circular_section,
    compatibility_rows,
    segment_wrenches,
    solve_redundants,
    unique_reactions,
)
from pkmdyn.errors import SingularityError

SEC = circular_section(7e10, 0.3, 0.03, 0.01)
L = 0.8


def _moved(point: np.ndarray) -> np.ndarray:
    """6 x 6 map of a wrench (f, m about ``point``) to (f, m about the origin)."""
    T = np.eye(6)
    x, y, z = point
    T[3:, :3] = [[0, -z, y], [z, 0, -x], [-y, x, 0]]
    return T


def _clamped_clamped(a: float, load: np.ndarray):
    """One beam along x from 0 to L, clamped at both ends (12 unknowns: the two clamp wrenches on
    the beam, about their clamps), loaded by ``load`` (f, m) at x = a; 6 equilibrium rows."""
    A = np.hstack([_moved(np.zeros(3)), _moved(np.array([L, 0, 0]))])[None]
    b = -(_moved(np.array([a, 0, 0])) @ load)[None]
    s = np.array([[0.0, a, L]])
    unit = np.zeros((1, 3, 6, 12))
    unit[0, 0, :, :6] = np.eye(6)
    unit[0, 2, :, 6:] = np.eye(6)
    ext = np.zeros((1, 3, 6))
    ext[0, 1] = load
    length, G = segment_wrenches(s, unit)
    _, w0 = segment_wrenches(s, ext)
    C = beam_flexibility(length, SEC)
    return A, b, G, w0, C


def test_central_transverse_loads_give_the_textbook_end_moments():
    P = 120.0
    for axis, moment in ((1, 5), (2, 4)):  # load along y bends about z; along z bends about y
        load = np.zeros(6)
        load[axis] = -P
        res = unique_reactions(*_clamped_clamped(L / 2, load))
        left, right = res.lam[0, :6], res.lam[0, 6:]
        assert np.isclose(left[axis], P / 2) and np.isclose(right[axis], P / 2)
        sign = 1.0 if axis == 1 else -1.0  # hogging end moments: +z for a -y load, -y for a -z load
        assert np.isclose(left[moment], sign * P * L / 8, rtol=1e-10)
        assert np.isclose(right[moment], -sign * P * L / 8, rtol=1e-10)
        assert res.residual.max() < 1e-9 * P


def test_off_centre_axial_force_and_torque_split_by_the_stiffness_of_the_two_parts():
    a = L / 3
    load = np.array([90.0, 0, 0, 7.0, 0, 0])
    res = unique_reactions(*_clamped_clamped(a, load))
    left, right = res.lam[0, :6], res.lam[0, 6:]
    # the shorter (stiffer) part carries (L - a) / L of an axial force and of a torque
    assert np.isclose(-left[0], 90.0 * (L - a) / L) and np.isclose(-right[0], 90.0 * a / L)
    assert np.isclose(-left[3], 7.0 * (L - a) / L) and np.isclose(-right[3], 7.0 * a / L)


def test_off_centre_point_load_matches_the_closed_form_end_moments():
    a, P = 0.3, 50.0
    bb = L - a
    load = np.array([0, -P, 0, 0, 0, 0])
    res = unique_reactions(*_clamped_clamped(a, load))
    # clamped-clamped beam, point load P at a: M_A = P a b^2 / L^2, M_B = P a^2 b / L^2,
    # R_A = P b^2 (3a + b) / L^3
    assert np.isclose(res.lam[0, 5], P * a * bb**2 / L**2, rtol=1e-10)
    assert np.isclose(res.lam[0, 11], -P * a**2 * bb / L**2, rtol=1e-10)
    assert np.isclose(res.lam[0, 1], P * bb**2 * (3 * a + bb) / L**3, rtol=1e-10)


def test_redundant_coordinates_give_the_same_answer_as_the_null_space_route():
    load = np.array([10.0, -40.0, 25.0, 3.0, -2.0, 1.0])
    A, b, G, w0, C = _clamped_clamped(0.37, load)
    res = unique_reactions(A, b, G, w0, C)
    # redundants: the right clamp's wrench; the left one follows from equilibrium
    Aleft, Aright = A[0, :, :6], A[0, :, 6:]
    base = np.linalg.solve(Aleft, b[0])
    dx = -np.linalg.solve(Aleft, Aright)
    W0 = np.einsum("nsak,k->nsa", G[:, :, :, :6], base) + w0
    Wx = np.einsum("nsak,kr->nsar", G[:, :, :, :6], dx) + G[:, :, :, 6:]
    x = solve_redundants(Wx, C, W0)
    assert np.allclose(x[0], res.lam[0, 6:], rtol=1e-10, atol=1e-10)
    rows, rhs = compatibility_rows(G, C, w0, res.null)
    assert rows.shape == (1, 6, 12)
    assert np.allclose(rows[0] @ res.lam[0], rhs[0], atol=1e-12 * np.abs(rows).max() * np.abs(res.lam).max())


def test_flexibility_is_eq64_symmetric_positive_definite_and_scales_with_length():
    C = beam_flexibility(np.array([0.5, 1.0]), SEC)
    assert np.allclose(C, np.swapaxes(C, 1, 2))
    assert np.all(np.linalg.eigvalsh(C) > 0)
    E, I = SEC.E, SEC.Iz
    assert np.isclose(C[1, 1, 1], 1.0 / (3 * E * I)) and np.isclose(C[1, 1, 5], 1.0 / (2 * E * I))
    assert np.isclose(C[1, 2, 4], -1.0 / (2 * E * SEC.Iy)) and np.isclose(C[0, 3, 3], 0.5 / (SEC.G * SEC.Ip))


def test_a_self_stress_that_strains_no_link_is_refused():
    A, b, G, w0, C = _clamped_clamped(0.4, np.array([0, -1.0, 0, 0, 0, 0]))
    with pytest.raises(SingularityError):
        unique_reactions(A, b, G * 0.0, w0, C)


def test_pivot_basis_gives_the_reactions_of_the_singular_value_route():
    """A stack of rank-deficient systems (random, with dependent rows and columns) and a random
    positive definite energy: the null space from pivots chosen at the first sample (a square
    solve per sample) and from every sample's SVD give the same unique reactions; where the
    rank changes along the stack the pivots are refused and the SVD says so."""
    from pkmdyn.analysis.compliance import _pivot_basis, unique_reactions_energy

    rng = np.random.default_rng(5)
    n, m, k, r = 40, 9, 12, 6
    left = rng.standard_normal((m, r)) + 0.2 * rng.standard_normal((n, m, r))
    A = left @ (rng.standard_normal((r, k)) + 0.2 * rng.standard_normal((n, r, k)))  # rank r at every sample
    b = np.einsum("nmk,nk->nm", A, rng.standard_normal((n, k)))
    Q = rng.standard_normal((n, k, k))
    H = Q @ np.swapaxes(Q, 1, 2) + 0.1 * np.eye(k)
    h = rng.standard_normal((n, k))
    assert _pivot_basis(A, b, 1e-10) is not None
    a = unique_reactions_energy(A, b, H, h)
    s = unique_reactions_energy(A, b, H, h, method="svd")
    assert np.abs(a.lam - s.lam).max() <= 1e-9 * np.abs(s.lam).max()
    assert np.all(a.rank == r) and a.residual.max() <= 1e-10 * np.abs(b).max()
    A2 = A.copy()
    A2[n // 2] += 0.3 * rng.standard_normal((m, k))  # one sample of full rank
    assert _pivot_basis(A2, b, 1e-10) is None
    with pytest.raises(SingularityError):
        unique_reactions_energy(A2, b, H, h)

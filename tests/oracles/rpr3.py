"""Planar 3-RPR parallel manipulator: inverse kinematics and every real assembly mode of
the direct kinematics.

References: C. M. Gosselin, J. Sefrioui & M. J. Richard, "Solutions polynomiales au
problème de la cinématique directe des manipulateurs parallèles plans à trois degrés de
liberté", Mech. Mach. Theory 27(2) (1992) 107-119 (elimination of the position, a polynomial
of degree 6 in ``tan(phi/2)``); C. M. Gosselin & J.-P. Merlet, "The direct kinematics of
planar parallel manipulators: special architectures and number of solutions", Mech. Mach.
Theory 29(8) (1994) 1083-1097; J.-P. Merlet, *Parallel Robots*, 2nd ed., Springer 2006,
ch. 4 (direct kinematics of the planar 3-RPR: at most 6 real assembly modes; with one leg cut
the third platform joint traces a tricircular sextic); K. H. Hunt, "Structural kinematics of
in-parallel-actuated robot-arms", J. Mech. Trans. Autom. Des. 105 (1983) 705-712.
(The spherical counterpart is Gosselin, Sefrioui & Richard, J. Mech. Des. 116 (1994).)

Conventions
-----------
* Planar base frame, angles counter-clockwise from +x. Leg ``i = 0, 1, 2``: a passive
  revolute at the base point ``A_i`` (base frame), an actuated prismatic joint of length
  ``rho_i`` (the leg length), a passive revolute at the platform point ``b_i`` (platform
  frame).
* Platform pose ``(x, y, phi)``: ``p = (x, y)`` is the platform frame's origin,
  ``R(phi) = [[c, -s], [s, c]]``. Platform joint ``C_i = p + R(phi) b_i``; leg vector
  ``w_i = C_i - A_i``, ``rho_i = |w_i|``, ``u_i = w_i / rho_i``.
* Velocity: ``rho_dot_i = u_i . (p_dot + phi_dot perp(R b_i)) = J_i . (x_dot, y_dot, phi_dot)``
  with ``J_i = [u_i, cross(R b_i, u_i)]``, ``perp(v) = (-v_y, v_x)``,
  ``cross(a, b) = a_x b_y - a_y b_x``.

Direct kinematics (elimination of ``x``, ``y``; Gosselin et al. 1992, Merlet 2006)
----------------------------------------------------------------------------------
With ``v_i(phi) = R(phi) b_i - A_i`` the loop equations are

    E_i:  |p|^2 + 2 p . v_i + |v_i|^2 - rho_i^2 = 0,        i = 0, 1, 2.

``E_1 - E_0`` and ``E_2 - E_0`` are linear in ``p`` for a given ``phi``:

    M(phi) p = r(phi),   row i of M = 2 (v_i - v_0)^T,
    r_i = rho_i^2 - rho_0^2 - |v_i|^2 + |v_0|^2,  |v_i|^2 = |b_i|^2 + |A_i|^2 - 2 A_i . R b_i.

Every entry of ``M``, ``r``, ``v_0`` and ``|v_0|^2`` is affine in ``(cos phi, sin phi)``;
``det M`` is affine too (its quadratic part is ``4 cross(b_1 - b_0, b_2 - b_0)``, constant
since ``det R = 1``). With ``D = det M`` and ``N = adj(M) r`` (so ``p = N / D``),
substituting ``p`` into ``E_0`` and multiplying by ``D^2`` gives one equation in ``phi``:

    F(phi) = |N|^2 + 2 D (N . v_0) + D^2 (|v_0|^2 - rho_0^2) = 0.

``F`` is a trigonometric polynomial ``F = sum_k f_k e^{i k phi}`` (``f_{-k} = conj(f_k)``);
the nominal degree is 4, but the 4th harmonic cancels identically (this is the
"degree 6 in ``tan(phi/2)``" of Gosselin et al. / Merlet, i.e. at most 6 real modes; the
self-tests check it). Writing ``z = e^{i phi}`` (``cos phi = (z + 1/z)/2``,
``sin phi = (z - 1/z)/(2i)``), ``z^K F`` is an ordinary polynomial of degree ``2K``
(``K = 3`` generically) whose roots on the unit circle are the real solutions ``phi = arg z``.
This is the same sextic as the tangent-half-angle form (``z = (1 + i t)/(1 - i t)``,
``t = tan(phi/2)``) but has no degenerate leading coefficient at ``phi = pi``. Outer
harmonics whose coefficients are negligible (``<= 1e-12`` of the largest) are dropped before
``numpy.roots``.

For each root close to the unit circle, ``p = N / D``; where ``D`` nearly vanishes (the
points ``A_i - R b_i`` collinear) ``M p = r`` reduces to one line, which is intersected with
the circle ``E_0`` as well (there ``F`` has a double root: the pose and its mirror image in
that line share ``phi``). Each candidate is refined by Newton steps on the original ``E_0, E_1, E_2``
in ``(x, y, phi)`` and kept if every leg-length residual ``| |w_i| - rho_i |`` is below
``1e-9`` times the size of the manipulator (largest of ``rho``, ``|A_i|``, ``|b_i|``).
Duplicates (a double root near a singularity) are merged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._batch import as_batch as _as_batch

RESIDUAL_TOL = 1e-9     # accepted leg-length residual, relative to the size
UNIT_CIRCLE_TOL = 1e-5  # | |z| - 1 | below which a root of the sextic is a candidate
HARMONIC_TOL = 1e-12    # relative size below which an outer harmonic of F is dropped


@dataclass
class RPR3:
    """Geometry of a planar 3-RPR: base points ``A (3, 2)`` [m] in the base frame and
    platform points ``b (3, 2)`` [m] in the platform frame (leg i joins ``A_i`` to ``b_i``)."""

    A: np.ndarray
    b: np.ndarray

    def __post_init__(self):
        self.A = np.asarray(self.A, float).reshape(3, 2)
        self.b = np.asarray(self.b, float).reshape(3, 2)


def rotation(phi):
    """``R(phi) (..., 2, 2)``, counter-clockwise."""
    c, s = np.cos(phi), np.sin(phi)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def wrap(a):
    """Angle wrapped to (-pi, pi]."""
    a = np.asarray(a, float)
    return a - 2.0 * np.pi * np.ceil((a - np.pi) / (2.0 * np.pi))


def inverse_kinematics(par: RPR3, pose):
    """Leg lengths of the 3-RPR for platform poses.

    ``pose (n, 3) = (x, y, phi)`` [m, m, rad]. Returns a dict: ``rho (n, 3)`` leg lengths [m];
    ``C (n, 3, 2)`` platform joint points ``p + R(phi) b_i`` in the base frame;
    ``r (n, 3, 2) = R(phi) b_i``; ``u (n, 3, 2)`` unit leg directions ``(C_i - A_i)/rho_i``;
    ``J (n, 3, 3)`` with ``rho_dot = J (x_dot, y_dot, phi_dot)``, row i ``[u_i, cross(r_i, u_i)]``.
    """
    pose = _as_batch(pose, 3)
    r = np.einsum("nij,kj->nki", rotation(pose[:, 2]), par.b)
    C = pose[:, None, :2] + r
    w = C - par.A[None]
    rho = np.linalg.norm(w, axis=-1)
    u = w / rho[..., None]
    J = np.concatenate([u, (r[..., 0] * u[..., 1] - r[..., 1] * u[..., 0])[..., None]], -1)
    return {"rho": rho, "C": C, "r": r, "u": u, "J": J}


# -- Laurent polynomials in z = e^{i phi}: centred coefficient arrays, exponents -k..k ---------

def _affine(alpha, beta, gamma):
    """``alpha + beta cos(phi) + gamma sin(phi)`` as coefficients of ``z^-1, z^0, z^1``."""
    return np.array([(beta + 1j * gamma) / 2.0, alpha, (beta - 1j * gamma) / 2.0], complex)


def _add(*terms):
    k = max(len(t) for t in terms)
    out = np.zeros(k, complex)
    for t in terms:
        pad = (k - len(t)) // 2
        out[pad:pad + len(t)] += t
    return out


def _mul(*factors):
    out = np.array([1.0 + 0j])
    for f in factors:
        out = np.convolve(out, f)
    return out


def _eliminant(par: RPR3, rho):
    """Laurent pieces of the elimination: ``M`` (2x2), ``r`` (2,), ``v0`` (2,), ``D``,
    ``N`` (2,), ``Q = |v_0|^2 - rho_0^2`` and ``F``, each a centred coefficient array."""
    A, b = par.A, par.b
    rho2 = np.asarray(rho, float) ** 2
    # R b_i = (c bx - s by, s bx + c by); v_i = R b_i - A_i
    v = [[_affine(-A[i, 0], b[i, 0], -b[i, 1]), _affine(-A[i, 1], b[i, 1], b[i, 0])] for i in range(3)]
    # |v_i|^2 = |b_i|^2 + |A_i|^2 - 2 A_i . R b_i
    #         = |b|^2 + |A|^2 - 2 (Ax bx + Ay by) cos - 2 (Ay bx - Ax by) sin
    vv = [_affine(b[i] @ b[i] + A[i] @ A[i], -2.0 * (A[i] @ b[i]), -2.0 * (A[i, 1] * b[i, 0] - A[i, 0] * b[i, 1]))
          for i in range(3)]
    M = [[2.0 * (v[i][j] - v[0][j]) for j in range(2)] for i in (1, 2)]
    r = [_add(np.array([rho2[i] - rho2[0]], complex), -vv[i], vv[0]) for i in (1, 2)]
    # det M is affine in (cos, sin): its +-2 harmonics (from the constant quadratic part
    # 4 cross(R(b_1 - b_0), R(b_2 - b_0))) cancel exactly in theory and are dropped
    D = _add(_mul(M[0][0], M[1][1]), -_mul(M[0][1], M[1][0]))[1:-1]
    N = [_add(_mul(M[1][1], r[0]), -_mul(M[0][1], r[1])),
         _add(-_mul(M[1][0], r[0]), _mul(M[0][0], r[1]))]
    Q = _add(vv[0], np.array([-rho2[0]], complex))
    F = _add(_mul(N[0], N[0]), _mul(N[1], N[1]),
             2.0 * _mul(D, _add(_mul(N[0], v[0][0]), _mul(N[1], v[0][1]))),
             _mul(D, D, Q))
    return {"M": M, "r": r, "v0": v[0], "D": D, "N": N, "Q": Q, "F": F}


def eliminant_harmonics(par: RPR3, rho):
    """Coefficients ``f_k`` of ``F(phi) = sum_k f_k e^{i k phi}`` for ``k = -K..K`` (complex,
    centred; no trimming). ``f_{-k} = conj(f_k)``; ``|f_k|`` for ``|k| >= 4`` vanish to rounding."""
    return _eliminant(par, np.asarray(rho, float).reshape(3))["F"]


def _eval(coef, phi):
    k = (len(coef) - 1) // 2
    return np.real(np.exp(1j * np.outer(np.atleast_1d(phi), np.arange(-k, k + 1))) @ coef)


def _residuals(par, pose):
    """``E_i = |p + R b_i - A_i|^2`` (before subtracting ``rho_i^2``) and its Jacobian."""
    x, y, phi = pose
    r = rotation(phi) @ par.b.T  # (2, 3)
    w = np.array([x, y])[:, None] + r - par.A.T
    jac = np.column_stack([2.0 * w[0], 2.0 * w[1], 2.0 * (w[0] * -r[1] + w[1] * r[0])])
    return np.sum(w * w, axis=0), jac, w


def _newton(par, rho, pose, steps=8):
    pose = np.array(pose, float)
    rho2 = rho**2
    for _ in range(steps):
        e, jac, _ = _residuals(par, pose)
        f = e - rho2
        try:
            step = np.linalg.solve(jac, -f)
        except np.linalg.LinAlgError:
            step = np.linalg.lstsq(jac, -f, rcond=None)[0]
        if not np.all(np.isfinite(step)):
            break
        pose = pose + step
        if np.max(np.abs(step)) < 1e-16 * (1.0 + np.max(np.abs(pose))):
            break
    return pose


def _positions(el, phi, rho0, size):
    """Candidates ``p`` for a root ``phi``: ``N / D``, and where the linear system is nearly
    singular (``|D|`` below ``1e-3`` of the product of the row norms) also the line-circle
    fallback. Near such a root ``N`` and ``D`` both nearly vanish, ``F`` has a double root
    (the pose and its mirror image in the line share ``phi``), and ``N / D`` is inaccurate."""
    val = lambda c: _eval(c, phi)[0]
    M = np.array([[val(el["M"][i][j]) for j in range(2)] for i in range(2)])
    r = np.array([val(el["r"][0]), val(el["r"][1])])
    D = val(el["D"])
    rownorm = np.linalg.norm(M, axis=1)
    rel = abs(D) / max(rownorm[0] * rownorm[1], 1e-300)
    out = []
    if rel > 1e-8:
        out.append(np.array([val(el["N"][0]), val(el["N"][1])]) / D)
    if rel > 1e-3:
        return out
    k = int(np.argmax(rownorm))
    if rownorm[k] < 1e-14 * size:
        return out
    m = M[k] / rownorm[k]
    p0 = m * r[k] / rownorm[k]
    t_dir = np.array([-m[1], m[0]])
    q = p0 + np.array([val(el["v0"][0]), val(el["v0"][1])])
    bq = q @ t_dir
    disc = bq * bq - (q @ q - rho0**2)
    if disc < 0.0:
        disc = 0.0  # tangent up to rounding; Newton and the residual test decide
    s = np.sqrt(disc)
    return out + [p0 + (-bq + s) * t_dir, p0 + (-bq - s) * t_dir]


def forward_kinematics(par: RPR3, rho):
    """Every real assembly mode of the 3-RPR for leg lengths ``rho (3,)`` [m].

    Returns ``(k, 3)`` poses ``(x, y, phi)`` with ``phi`` wrapped to (-pi, pi], sorted by
    ``phi``; ``k`` is 0 to 6 (0 when ``rho`` is out of reach). Method: the univariate
    elimination in ``phi`` described in the module docstring (Gosselin, Sefrioui & Richard
    1992; Merlet 2006), roots by ``numpy.roots`` on the polynomial in ``z = e^{i phi}``,
    Newton refinement on the three loop equations, a residual test, de-duplication.
    """
    rho = np.asarray(rho, float).reshape(3)
    if np.any(rho < 0):
        raise ValueError("leg lengths must be non-negative")
    size = max(np.max(rho), np.max(np.abs(par.A)), np.max(np.abs(par.b)))
    el = _eliminant(par, rho)
    F = el["F"]
    big = np.max(np.abs(F))
    if big == 0.0:
        return np.zeros((0, 3))
    while len(F) > 1 and max(abs(F[0]), abs(F[-1])) <= HARMONIC_TOL * big:
        F = F[1:-1]
    if len(F) == 1:
        return np.zeros((0, 3))
    z = np.roots(F[::-1])  # z^K F(z): coefficient of z^j is F[j]
    cand = z[np.abs(np.abs(z) - 1.0) < UNIT_CIRCLE_TOL]
    sols = []
    for phi in np.angle(cand):
        for p in _positions(el, phi, rho[0], size):
            pose = _newton(par, rho, [p[0], p[1], phi])
            _, _, w = _residuals(par, pose)
            if np.max(np.abs(np.linalg.norm(w, axis=0) - rho)) > RESIDUAL_TOL * size:
                continue
            pose[2] = wrap(pose[2])
            dup = any(np.max(np.abs(pose[:2] - s[:2])) < 1e-8 * size and abs(wrap(pose[2] - s[2])) < 1e-8
                      for s in sols)
            if not dup:
                sols.append(pose)
    if not sols:
        return np.zeros((0, 3))
    out = np.array(sols)
    return out[np.argsort(out[:, 2])]


def default_rpr3() -> RPR3:
    """A documented default (not a published design), deliberately without symmetry:
    base ``A = (0, 0), (0.8, 0.05), (0.3, 0.7)`` m (sides 0.80, 0.82, 0.76 m); platform, in
    the platform frame, ``b = (-0.22, 0.03), (0.14, -0.19), (0.14, 0.15)`` m (sides 0.42, 0.34,
    0.38 m). At :data:`DEFAULT_POSE` the legs are ``rho = (0.3087, 0.3102, 0.3551)`` m and
    these leg lengths have two real assembly modes: the home pose and
    ``(0.3795, 0.1807, 1.3751)``."""
    return RPR3(A=[[0.0, 0.0], [0.8, 0.05], [0.3, 0.7]],
                b=[[-0.22, 0.03], [0.14, -0.19], [0.14, 0.15]])


DEFAULT_POSE = np.array([0.35, 0.25, 0.0])
"""A regular home pose of :func:`default_rpr3` ``(x, y, phi)`` [m, m, rad], near the base
triangle's centroid; the inverse Jacobian's smallest singular value there is 0.344."""

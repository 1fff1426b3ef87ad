"""Self-tests of the frame finite-element oracle against textbook closed forms.

Every expected value is a closed form of linear beam theory (Timoshenko & Gere; McGuire,
Gallagher & Ziemian 2000), written out here: cantilever flexibilities, a guided beam, a beam
with a midspan hinge, portal frames with a rigid girder (fixed and pinned bases, with and
without the girder rotation that column stretching allows), pin-jointed trusses and springs in
series / parallel. The solver is exact in arithmetic for all of them (cubic elements are
nodally exact for end loads), so the tolerance 1e-9 is only a round-off margin.
"""

from __future__ import annotations

import numpy as np
import pytest

from oracles.frame_fe import ALL_DOFS, ROTATIONS, TRANSLATIONS, Frame, MechanismError

E, G = 2.1e11, 8.1e10
SEC = dict(E=E, G=G, A=4e-3, Iy=3e-6, Iz=5e-6, J=6e-6)
A, IY, IZ, J = SEC["A"], SEC["Iy"], SEC["Iz"], SEC["J"]
RTOL = 1e-9


def assert_close(actual, expected, rtol=RTOL, what=""):
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    scale = max(np.max(np.abs(expected)), 1e-300)
    err = np.max(np.abs(actual - expected))
    assert err <= rtol * scale, f"{what}: max err {err:.3e} > {rtol:.1e} * {scale:.3e}"


def cantilever_compliance(L):
    """Tip compliance of a cantilever along local x (load order Fx Fy Fz Mx My Mz)."""
    C = np.zeros((6, 6))
    C[0, 0] = L / (E * A)
    C[3, 3] = L / (G * J)
    # x-y plane: v = F L^3/3EI + M L^2/2EI, th_z = F L^2/2EI + M L/EI
    C[np.ix_([1, 5], [1, 5])] = np.array([[L**3 / 3, L**2 / 2], [L**2 / 2, L]]) / (E * IZ)
    # x-z plane, th_y = -dw/dx: the coupling terms change sign
    C[np.ix_([2, 4], [2, 4])] = np.array([[L**3 / 3, -(L**2) / 2], [-(L**2) / 2, L]]) / (E * IY)
    return C


def rotation(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def cantilever(L=1.5, segments=1, Q=np.eye(3), origin=(0.0, 0.0, 0.0)):
    f = Frame()
    o = np.asarray(origin, float)
    a = f.add_node(o)
    b = f.add_node(o + Q @ [L, 0, 0])
    chain = f.add_beam(a, b, **SEC, up=Q @ [0, 0, 1], segments=segments)
    f.support(a, ALL_DOFS)
    return f, a, b, chain


@pytest.mark.parametrize("L", [0.7, 1.5])
def test_cantilever_closed_forms(L):
    f, _, b, _ = cantilever(L)
    P, M, T = 1234.0, 56.0, 78.0
    u = f.solve({b: [0, P, 0, 0, 0, 0]})[b]
    assert_close(u[1], P * L**3 / (3 * E * IZ), what="tip deflection PL^3/3EI")
    assert_close(u[5], P * L**2 / (2 * E * IZ), what="tip rotation PL^2/2EI")
    u = f.solve({b: [0, 0, P, 0, 0, 0]})[b]
    assert_close(u[[2, 4]], [P * L**3 / (3 * E * IY), -P * L**2 / (2 * E * IY)], what="x-z plane")
    u = f.solve({b: [0, 0, 0, 0, 0, M]})[b]
    assert_close(u[5], M * L / (E * IZ), what="tip moment ML/EI")
    assert_close(u[1], M * L**2 / (2 * E * IZ), what="tip moment deflection")
    assert_close(f.solve({b: [P, 0, 0, 0, 0, 0]})[b][0], P * L / (E * A), what="axial PL/EA")
    assert_close(f.solve({b: [0, 0, 0, T, 0, 0]})[b][3], T * L / (G * J), what="torsion TL/GJ")
    assert_close(f.compliance(b), cantilever_compliance(L), what="6x6 compliance")


@pytest.mark.parametrize("segments", [2, 3, 7])
def test_subdivision_invariance_and_elastic_line(segments):
    L, P = 1.5, 900.0
    f1, _, b1, _ = cantilever(L, 1)
    f, _, b, chain = cantilever(L, segments)
    assert len(chain) == segments + 1
    assert_close(f.compliance(b), f1.compliance(b1), what="subdivided tip compliance")
    assert_close(f.compliance(b), cantilever_compliance(L), what="closed form")
    u = f.solve({b: [0, P, 0, 0, 0, 0]})
    for n in chain:
        x = f.nodes[n][0]
        assert_close(u[n][1], P * x**2 * (3 * L - x) / (6 * E * IZ), what=f"v(x={x})")
        assert_close(u[n][5], P * x * (2 * L - x) / (2 * E * IZ), what=f"slope(x={x})")


@pytest.mark.parametrize("segments", [1, 4])
def test_oriented_cantilever(segments):
    L = 1.1
    Q = rotation([0.3, -0.8, 0.5], 1.234) @ rotation([0, 0, 1], 0.4)
    f, _, b, _ = cantilever(L, segments, Q, origin=(0.2, -0.5, 1.3))
    Qb = np.kron(np.eye(2), Q)
    assert_close(f.compliance(b), Qb @ cantilever_compliance(L) @ Qb.T, what="rotated compliance")
    load_local = np.array([300.0, -200.0, 150.0, 40.0, -25.0, 60.0])
    u = f.solve({b: Qb @ load_local})[b]
    assert_close(Qb.T @ u, cantilever_compliance(L) @ load_local, what="rotated solve")


def test_default_up_vertical_beam():
    f = Frame()
    a, b = f.add_node([0, 0, 0]), f.add_node([0, 0, 2.0])
    f.add_beam(a, b, **SEC)  # documented default: up = global y, so local y = global x
    f.support(a)
    assert_close(f.compliance(b)[0, 0], 8.0 / (3 * E * IZ), what="x uses Iz")
    assert_close(f.compliance(b)[1, 1], 8.0 / (3 * E * IY), what="y uses Iy")
    with pytest.raises(ValueError):
        f.add_beam(a, b, **SEC, up=[0, 0, 5.0])


def test_guided_beam_sway_stiffness():
    L = 1.3
    f = Frame()
    a, b = f.add_node([0, 0, 0]), f.add_node([L, 0, 0])
    f.add_beam(a, b, **SEC, segments=3)
    f.support(a)
    f.support(b, [0, 2, 3, 4, 5])  # guided: only u_y free, no end rotation
    assert_close(1.0 / f.compliance(b)[1, 1], 12 * E * IZ / L**3, what="12EI/L^3")


def test_fixed_fixed_beam_with_and_without_midspan_hinge():
    L = 2.0
    for hinge, expected in [(False, 192 * E * IZ / L**3), (True, 2 * 3 * E * IZ / (L / 2) ** 3)]:
        f = Frame()
        a, m1, b = f.add_node([0, 0, 0]), f.add_node([L / 2, 0, 0]), f.add_node([L, 0, 0])
        m2 = f.add_node([L / 2, 0, 0]) if hinge else m1
        f.add_beam(a, m1, **SEC, segments=2)
        f.add_beam(m2, b, **SEC)
        if hinge:
            f.couple(m1, m2, [0, 1, 2, 3, 4])  # revolute about global z
        f.support(a)
        f.support(b)
        assert_close(1.0 / f.compliance(m1)[1, 1], expected, what=f"midspan, hinge={hinge}")


def portal(h, b, base, restrain_girder):
    """Two columns (up = y: sway along x bends about local z, Iz) with a rigid girder."""
    f = Frame()
    tops = []
    for x in (0.0, b):
        bot, top = f.add_node([x, 0, 0]), f.add_node([x, 0, h])
        f.add_beam(bot, top, **SEC, up=[0, 1, 0], segments=2)
        if base == "fixed":
            f.support(bot)
        elif base == "spherical":
            f.support(bot, TRANSLATIONS)
        else:  # revolute hinge about global y between the column and a grounded node
            g = f.add_node([x, 0, 0])
            f.support(g)
            f.couple(g, bot, [0, 1, 2, 3, 5])
        tops.append(top)
    f.add_rigid(tops[0], tops[1])
    # out-of-plane guide: with spherical bases the frame could sway along y freely (a
    # mechanism); the in-plane (x-z) answer does not depend on it
    f.support(tops[0], [1])
    if restrain_girder:
        f.support(tops[0], [4])
    return f, tops[0]


@pytest.mark.parametrize("base", ["fixed", "spherical", "hinge"])
@pytest.mark.parametrize("restrain_girder", [True, False])
def test_portal_frame_rigid_girder(base, restrain_girder):
    h, b, H = 1.5, 2.0, 1000.0
    f, top = portal(h, b, base, restrain_girder)
    # one column's top stiffness on (sway, top rotation th_y = du/dz)
    if base == "fixed":
        kc = E * IZ * np.array([[12 / h**3, -6 / h**2], [-6 / h**2, 4 / h]])
    else:
        kc = 3 * E * IZ / h**3 * np.array([[1.0, -h], [-h, h**2]])
    k_sway = 2 * kc[0, 0]  # 24EI/h^3 (fixed) or 6EI/h^3 (pinned)
    if not restrain_girder:
        # girder rotation phi stretches one column and shortens the other by phi b / 2
        k_phi = 2 * kc[1, 1] + (E * A / h) * b**2 / 2
        k_sway -= (2 * kc[0, 1]) ** 2 / k_phi
    u = f.solve({top: [H, 0, 0, 0, 0, 0]})[top]
    assert_close(H / u[0], k_sway, what="lateral stiffness")
    textbook = (24 if base == "fixed" else 6) * E * IZ / h**3
    if restrain_girder:
        assert_close(H / u[0], textbook, what="24EI/h^3 or 6EI/h^3")
    else:  # column stretching lets the girder tilt: measurably softer than the textbook value
        assert H / u[0] < textbook * (1 - 1e-4)


def truss(bases, apex, k_y=None):
    """Pin-jointed bars from each base to a common apex; returns (frame, apex node, K_truss)."""
    f = Frame()
    apex = np.asarray(apex, float)
    ends, K = [], np.zeros((3, 3))
    for i, base in enumerate(bases):
        base = np.asarray(base, float)
        nb, ne = f.add_node(base), f.add_node(apex)
        d = apex - base
        u = d / np.linalg.norm(d)
        area = A * (1 + 0.5 * i)
        f.add_beam(nb, ne, E=E, G=G, A=area, Iy=IY, Iz=IZ, J=J, segments=1 + i)
        # spherical base; one global rotation with u_k != 0 stops the free spin about the bar
        f.support(nb, list(TRANSLATIONS) + [3 + int(np.argmax(np.abs(u)))])
        K += E * area / np.linalg.norm(d) * np.outer(u, u)
        if ends:
            f.couple(ends[0], ne, TRANSLATIONS)
        ends.append(ne)
    if k_y is not None:
        f.spring(ends[0], 1, k_y)
        K[1, 1] += k_y
    return f, ends[0], K


def test_two_bar_truss_with_out_of_plane_spring():
    f, top, K = truss([[0, 0, 0], [2.0, 0, 0.3]], [0.8, 0, 1.2], k_y=3.0e6)
    assert_close(f.compliance(top)[:3, :3], np.linalg.inv(K), what="sum EA/L u u^T")


def test_tripod_truss():
    f, top, K = truss([[0, 0, 0], [1.5, 0.2, 0], [0.4, 1.3, -0.1]], [0.6, 0.5, 1.1])
    assert_close(f.compliance(top)[:3, :3], np.linalg.inv(K), what="sum EA/L u u^T")
    F = np.array([100.0, -50.0, 30.0])
    u = f.solve({top: np.r_[F, 0, 0, 0]})
    for n in range(len(f.nodes)):
        if np.allclose(f.nodes[n], f.nodes[top]):
            assert_close(u[n][:3], np.linalg.solve(K, F), what="coupled apex translations")


def test_two_bar_truss_without_restraint_is_a_mechanism():
    f, top, _ = truss([[0, 0, 0], [2.0, 0, 0.3]], [0.8, 0, 1.2])
    with pytest.raises(MechanismError, match="mechanism"):
        f.compliance(top)
    with pytest.raises(MechanismError):
        f.solve({top: [0, 0, 1.0, 0, 0, 0]})


def test_free_spin_and_loose_node_are_mechanisms():
    f = Frame()
    a, b = f.add_node([0, 0, 0]), f.add_node([1, 0, 0])
    f.add_beam(a, b, **SEC)
    f.support(a, TRANSLATIONS)
    f.support(b, TRANSLATIONS)  # the bar may spin about its axis
    with pytest.raises(MechanismError):
        f.compliance(b)
    f.support(a, [3])
    assert np.all(np.isfinite(f.compliance(b)))
    f.add_node([5, 5, 5])
    with pytest.raises(MechanismError):
        f.compliance(b)


@pytest.mark.parametrize("direction", [[1, 0, 0], [0, 1, 0], [0.6, 0.0, 0.8]])
def test_spring_in_series_with_cantilever(direction):
    """Actuator spring k along n from the tip to a node held sideways by soft springs k_t."""
    L, k, k_t, P = 1.5, 2.0e6, 3.0e5, 700.0
    n = np.asarray(direction, float) / np.linalg.norm(direction)
    f, _, tip, _ = cantilever(L)
    end = f.add_node(f.nodes[tip] + 0.4 * n)
    f.spring_between(tip, end, n, k)
    f.support(end, ROTATIONS)
    g = f.add_node(f.nodes[end])
    f.support(g)
    t1 = np.cross(n, [0.0, 0.0, 1.0]) if abs(n[2]) < 0.9 else np.cross(n, [1.0, 0.0, 0.0])
    t1 /= np.linalg.norm(t1)
    for t in (t1, np.cross(n, t1)):
        f.spring_between(g, end, t, k_t)
    # series: 1/k_s = 1/k + n^T C_tip n; sideways only k_t (the spring carries no shear)
    k_s = 1.0 / (1.0 / k + n @ cantilever_compliance(L)[:3, :3] @ n)
    K_end = k_t * (np.eye(3) - np.outer(n, n)) + k_s * np.outer(n, n)
    assert_close(f.compliance(end)[:3, :3], np.linalg.inv(K_end), what="end compliance")
    u = f.solve({end: np.r_[P * n, 0, 0, 0]})
    assert_close(u[end][:3], P / k_s * n, what="series compliance along n")


def test_grounded_spring_in_parallel_and_rigid_offset():
    L, k, a, F = 1.5, 4.0e5, 0.3, 500.0
    f, _, tip, _ = cantilever(L)
    f.spring(tip, 1, k)
    assert_close(1.0 / f.compliance(tip)[1, 1], 3 * E * IZ / L**3 + k, what="parallel spring")
    f, _, tip, _ = cantilever(L)
    arm = f.add_node(f.nodes[tip] + [0, 0, a])
    f.add_rigid(tip, arm)
    u = f.solve({arm: [F, 0, 0, 0, 0, 0]})  # equals F and M_y = a F at the tip
    th = a * F * L / (E * IY)
    assert_close(u[tip][[0, 2, 4]], [F * L / (E * A), -a * F * L**2 / (2 * E * IY), th], what="tip")
    assert_close(u[arm], u[tip] + np.r_[a * th, 0, 0, 0, 0, 0], what="rigid arm follows")

"""Test oracle: the hand-derived Newton-Euler dynamics of the PDM's 14 bodies and its unique
joint reactions (Eq. 49-83 of the PDM paper), on the hand-derived kinematics of
:mod:`pkmdyn.machines.pdm4.kinematics` (Eq. 2-48); nothing of the generic engine. The product
computes the same quantities with the engine on the PDM's description (``pkmdyn pdm run``).

Every body ``b`` obeys (Eq. 49-51, 55, 57, 61 written once for all bodies, base frame A)

    sum_j  s_jb W_j  =  D_b,    D_b = ( m_b (a_b - g),  I_b wd_b + w_b x I_b w_b + c_b x m_b (a_b - g) ),

where ``W_j = (f_j, n_j)`` is the wrench that joint j's ``body_a`` exerts on its ``body_b``
(force, and moment about the base origin; files give the moment about the joint point),
``s_jb = +1`` if b is ``body_b``, ``-1`` if b is ``body_a``, ``c_b`` the centre of mass and
``I_b = R_b I_b' R_b^T`` the inertia about it in the base frame (Eq. 52). The joint
reactions have 93 unknown components (R: force and the two moments normal to the axis, 5 each,
11 joints; P: full wrench, the axial force being the actuator force, 6 each, 4 joints; S: force,
3 each, 2 joints; U: force and the torque along ``U_j3 = U_j1 x U_j2`` (Eq. 28), 4 each, 2 joints)
for 6 x 14 = 84 equations: the paper's "84 equations, 93 unknowns", which checks n = 14 and
R = 11. The nine missing equations are the compatibility conditions of Eq. 83 (module
:mod:`pkmdyn.analysis.compliance`).

Fast route (used by :func:`inverse_dynamics` and :func:`actuator_forces`). The joints form a
spanning tree rooted at the ground (every body's parent joint has it as ``body_b``) plus five
cut joints: R21' (crank 1 - piston 1), R22' (crank 2 - piston 2), R32 (coupler 2 - output link),
U23 and U24. The wrench of a tree joint is the sum of ``D_b`` over the bodies beyond it plus the
cut wrenches that enter that subtree, so every equilibrium equation holds by construction and
what remains are the free directions of the tree joints (a revolute transmits no moment about
its axis, a spherical joint none at all): 8 + 6 = 14 equations for the 14 in-plane cut
components (f_x, f_y at R21', R22', R32; force and torque at U23, U24). The nine out-of-plane
components (f_z, m_x, m_y) of R21', R22', R32 - the directions of Eq. 70, the paper's Fig. 22 -
enter none of these equations and none of the actuator forces: they are the redundants, fixed by
minimising the complementary energy of the elastic links (Eq. 63-69), which is Eq. 83.

Correspondence with the paper's module-by-module equations (slips corrected, docs/pdm4.md):
Eq. 49 is the crank row of the system, Eq. 50 the platform row, Eq. 51/54-56 the RPR limb
(cylinder + piston about R4i, and the piston along s_i), Eq. 57-62 the SPU limb (moments about
S2j, Eq. 58 its component along s_j, which gives the U-joint torque).

Shapes: ``n`` samples; every vector in the base frame; bodies in ``BODY_NAMES`` order, joints
in ``JOINTS`` order.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from pkmdyn.analysis.compliance import beam_flexibility, circular_section, segment_wrenches, solve_redundants
from pkmdyn.errors import SingularityError
from pkmdyn.machines.pdm4.inertia import ELASTIC_BODIES
from pkmdyn.machines.pdm4.kinematics import BODY_NAMES, PdmKinematics, joint_points
from pkmdyn.machines.pdm4.paper import JOINTS, REDUNDANT_LABELS
from pkmdyn.machines.pdm4.params import PdmModel
from pkmdyn.spatial import cross

__all__ = [
    "JOINTS",
    "REDUNDANT_LABELS",
    "PdmReactions",
    "body_loads",
    "joint_points",
    "actuator_forces",
    "inverse_dynamics",
    "equilibrium_system",
    "compliance_system",
    "wrench_to_components",
    "compatibility_deflections",
]

Array = NDArray[np.float64]

_JN = [j[0] for j in JOINTS]
_NJ = len(JOINTS)
_NB = len(BODY_NAMES)
_B = {name: k for k, name in enumerate(BODY_NAMES)}
_CUTS = ("R21'", "R22'", "R32", "U23", "U24")
_CUT_IDX = [_JN.index(c) for c in _CUTS]
_P_IDX = [_JN.index(p) for p in ("P11", "P12", "P23", "P24")]
_U_IDX = [_JN.index("U23"), _JN.index("U24")]
_COMPONENTS = {"R": 5, "P": 6, "S": 3, "U": 4}
_EZ = np.array([0.0, 0.0, 1.0])


def _tree() -> tuple[Array, Array]:
    """Constant maps of the spanning tree: ``sub`` (19, 14), 1 where body b lies beyond tree
    joint j; ``cut`` (19, 5), the sign with which cut c's wrench enters joint j's wrench."""
    parent = {}
    for j, (name, _, a, b) in enumerate(JOINTS):
        if name not in _CUTS:
            parent[b] = (j, a)

    def beyond(body: str) -> set[str]:
        out = {body}
        for child, (_, a) in parent.items():
            if a == body:
                out |= beyond(child)
        return out

    sub = np.zeros((_NJ, _NB))
    cut = np.zeros((_NJ, len(_CUTS)))
    for body, (j, _) in parent.items():
        bodies = beyond(body)
        for b in bodies:
            sub[j, _B[b]] = 1.0
        for c, ci in enumerate(_CUT_IDX):
            _, _, a, b = JOINTS[ci]
            cut[j, c] = (a in bodies and b not in bodies) - (b in bodies and a not in bodies)
    for c, ci in enumerate(_CUT_IDX):
        cut[ci, c] = 1.0
    return sub, cut


_SUB, _CUT_SIGN = _tree()


@dataclass(frozen=True)
class PdmReactions:
    """Actuator forces and every joint reaction of the PDM for a motion.

    ``t`` (n,) [s]; ``force`` (n, 4) [N] actuator forces in the order l11, l12, l23, l24, the
    axial force that each cylinder exerts on its piston along ``u`` (fixed -> moving joint; a
    positive force pushes the limb longer); ``joint_point`` (n, 19, 3) [m]; ``joint_force``
    (n, 19, 3) [N] and ``joint_moment`` (n, 19, 3) [N m] about ``joint_point``: the wrench that
    ``body_a`` exerts on ``body_b`` of each joint in ``JOINTS``, base frame; ``redundant``
    (n, 9) the components named by ``REDUNDANT_LABELS``; ``u_joint_torque`` (n, 2) [N m]
    the constraint torque of U23, U24 along ``U_j3`` (Eq. 28, 58).
    """

    t: Array
    force: Array
    joint_point: Array
    joint_force: Array
    joint_moment: Array
    redundant: Array
    u_joint_torque: Array


# ----------------------------------------------------------------------------- loads, points
def _inertia_base(model: PdmModel, kin: PdmKinematics) -> Array:
    """``I_b = R_b I_b' R_b^T`` (n, 14, 3, 3) [kg m^2], Eq. 52."""
    R = np.stack([b.R for b in kin.bodies], axis=1)
    return R @ model.inertia[None] @ np.swapaxes(R, -1, -2)


def body_loads(model: PdmModel, kin: PdmKinematics) -> Array:
    """``D_b`` (n, 14, 6): the wrench [N, N m about the base origin] that the joints must apply
    to each body, ``(m (a - g), I wd + w x I w + c x m (a - g))``."""
    p = np.stack([b.p for b in kin.bodies], axis=1)
    a = np.stack([b.a for b in kin.bodies], axis=1)
    w = np.stack([b.w for b in kin.bodies], axis=1)
    wd = np.stack([b.wd for b in kin.bodies], axis=1)
    I = _inertia_base(model, kin)
    f = model.mass[None, :, None] * (a - model.gravity)
    m = (I @ wd[..., None])[..., 0] + cross(w, (I @ w[..., None])[..., 0]) + cross(p, f)
    return np.concatenate([f, m], axis=-1)


def _axes(kin: PdmKinematics) -> Array:
    """Revolute axes (n, 19, 3): base z for the six-bar and the RPR limbs, platform x for R4."""
    n = kin.q.shape[0]
    ax = np.zeros((n, _NJ, 3))
    ax[..., 2] = 1.0
    ax[:, _JN.index("R4")] = kin.pos.T[:, :, 0]
    return ax


def _unit_wrenches(point: Array, direction: Array) -> Array:
    """Wrench about the origin (…, 6) of a unit force ``direction`` through ``point``."""
    return np.concatenate([direction, cross(point, direction)], axis=-1)


def _couple(direction: Array) -> Array:
    return np.concatenate([np.zeros_like(direction), direction], axis=-1)


# ----------------------------------------------------------------------------- fast route
def _cut_columns(kin: PdmKinematics, pts: Array) -> tuple[Array, Array]:
    """Unit wrenches of the 23 cut components: 14 in-plane then the 9 redundants.

    Returns ``cols`` (n, 23, 6) and the cut index of every column (23,)."""
    n = pts.shape[0]
    E = np.broadcast_to(np.eye(3), (n, 3, 3))
    cols, owner = [], []
    for c, ci in enumerate(_CUT_IDX[:3]):  # R21', R22', R32: fx, fy
        for k in range(2):
            cols.append(_unit_wrenches(pts[:, ci], E[:, k]))
            owner.append(c)
    for c, ci in enumerate(_CUT_IDX[3:]):  # U23, U24: force and torque along U3
        for k in range(3):
            cols.append(_unit_wrenches(pts[:, ci], E[:, k]))
            owner.append(3 + c)
        cols.append(_couple(kin.U3[:, c]))
        owner.append(3 + c)
    for c, ci in enumerate(_CUT_IDX[:3]):  # redundants: fz, mx, my
        cols.append(_unit_wrenches(pts[:, ci], E[:, 2]))
        cols.append(_couple(E[:, 0]))
        cols.append(_couple(E[:, 1]))
        owner += [c, c, c]
    return np.stack(cols, axis=1), np.array(owner)


def _free_twists(kin: PdmKinematics, pts: Array) -> tuple[Array, Array]:
    """Twists (n, 14, 6) = (omega, v at the origin) of the free motions of the tree joints
    (one per revolute, three per spherical joint) and the joint index of each row."""
    ax = _axes(kin)
    rows, owner = [], []
    for j, (name, typ, _, _) in enumerate(JOINTS):
        if name in _CUTS:
            continue
        if typ == "R":
            e = ax[:, j]
            rows.append(np.concatenate([e, cross(pts[:, j], e)], axis=-1))
            owner.append(j)
        elif typ == "S":
            for k in range(3):
                e = np.broadcast_to(np.eye(3)[k], pts[:, j].shape)
                rows.append(np.concatenate([e, cross(pts[:, j], e)], axis=-1))
                owner.append(j)
    return np.stack(rows, axis=1), np.array(owner)


def _power(twist: Array, wrench: Array) -> Array:
    """Reciprocal product ``omega . n + v . f`` over the last axis (twist (…, 6), wrench (…, 6))."""
    return (twist[..., :3] * wrench[..., 3:]).sum(-1) + (twist[..., 3:] * wrench[..., :3]).sum(-1)


def _solve_cuts(model: PdmModel, kin: PdmKinematics, with_redundants: bool, u_torque: bool = True
                ) -> tuple[Array, Array, Array, Array, Array]:
    """Tree-joint wrenches at zero redundants, and their derivative with respect to them.

    Returns ``D`` (n, 14, 6), ``pts`` (n, 19, 3), ``W0`` (n, 19, 6) all joint wrenches about the
    origin with the redundants zero, ``Wx`` (n, 19, 6, 9) (None unless ``with_redundants``)
    and ``cols`` (n, 23, 6). ``u_torque=False`` neglects the U-joint torque (Fig. 23): the
    torque columns are dropped and so are the components of the S-joint equations along the
    limb (Eq. 58), leaving the paper's Eq. 60 with ``M_uj = 0``.
    """
    D = body_loads(model, kin)
    pts = joint_points(model, kin)
    cols, owner = _cut_columns(kin, pts)
    xi, row_joint = _free_twists(kin, pts)
    P = np.einsum("jb,nbk->njk", _SUB, D)
    coef = _CUT_SIGN[row_joint][:, owner]  # (14, 23)
    M = coef * _power(xi[:, :, None, :], cols[:, None, :, :])  # (n, 14, 23)
    rhs = -_power(xi, P[:, row_joint])
    if not u_torque:
        keep_cols = np.array([k for k in range(14) if k not in (9, 13)])
        M, rhs = _drop_spin_rows(kin, M, rhs, row_joint)
        Mn = M[:, :, keep_cols]
    else:
        keep_cols = np.arange(14)
        Mn = M[:, :, :14]
    try:
        if with_redundants:
            sol = np.linalg.solve(Mn, np.concatenate([rhs[..., None], -M[:, :, 14:]], axis=-1))
        else:
            sol = np.linalg.solve(Mn, rhs[..., None])
    except np.linalg.LinAlgError:
        raise SingularityError("the PDM's equilibrium equations are singular at some sample "
                               "(a limb or the six-bar at a singular configuration)") from None
    z0 = np.zeros((D.shape[0], 23))
    z0[:, keep_cols] = sol[..., 0]
    cut0 = np.einsum("nc,nck->nck", z0, cols)
    cutw0 = np.zeros((D.shape[0], len(_CUTS), 6))
    _accumulate(cutw0, owner, cut0)
    W0 = P + np.einsum("jc,nck->njk", _CUT_SIGN, cutw0)
    Wx = None
    if with_redundants:
        zx = np.zeros((D.shape[0], 23, 9))
        zx[:, keep_cols] = sol[..., 1:]
        zx[:, 14:] += np.eye(9)
        cutx = np.zeros((D.shape[0], len(_CUTS), 6, 9))
        for c in range(len(_CUTS)):
            sel = np.flatnonzero(owner == c)
            cutx[:, c] = np.einsum("ncr,nck->nkr", zx[:, sel], cols[:, sel])
        Wx = np.einsum("jc,nckr->njkr", _CUT_SIGN, cutx)
    return D, pts, W0, Wx, cols


def _accumulate(out: Array, owner: Array, parts: Array) -> None:
    for c in range(out.shape[1]):
        out[:, c] = parts[:, owner == c].sum(axis=1)


def _drop_spin_rows(kin: PdmKinematics, M: Array, rhs: Array, row_joint: Array) -> tuple[Array, Array]:
    """Replace the three S-joint rows of each SPU limb by their two components normal to the limb."""
    M, rhs = M.copy(), rhs.copy()
    keep = []
    for j, name in enumerate(("S23", "S24")):
        rows = np.flatnonzero(row_joint == _JN.index(name))
        u = kin.u[:, 2 + j]
        a = np.cross(u, np.where(np.abs(u[:, :1]) < 0.9, [[1.0, 0, 0]], [[0, 1.0, 0]]))
        a /= np.linalg.norm(a, axis=1, keepdims=True)
        b = np.cross(u, a)
        Ms, rs = M[:, rows].copy(), rhs[:, rows].copy()
        for k, d in enumerate((a, b)):
            M[:, rows[k]] = np.einsum("nr,nrc->nc", d, Ms)
            rhs[:, rows[k]] = np.einsum("nr,nr->n", d, rs)
        keep += list(rows[:2])
    others = [r for r in range(M.shape[1]) if row_joint[r] not in (_JN.index("S23"), _JN.index("S24"))]
    sel = np.array(sorted(others + keep))
    return M[:, sel], rhs[:, sel]


@lru_cache(maxsize=1)
def _tables() -> dict[str, Array]:
    """Sample-independent tables of the compiled kernel (``_kernel.ne_kernel``)."""
    row_joint, row_dir = [], []
    for j, (name, typ, _, _) in enumerate(JOINTS):
        if name in _CUTS:
            continue
        if typ == "R":
            row_joint.append(j)
            row_dir.append(-1)
        elif typ == "S":
            row_joint += [j, j, j]
            row_dir += [0, 1, 2]
    col_joint, col_kind, col_dir, col_owner = [], [], [], []
    for c, ci in enumerate(_CUT_IDX[:3]):
        for k in range(2):
            col_joint.append(ci), col_kind.append(0), col_dir.append(k), col_owner.append(c)
    for c, ci in enumerate(_CUT_IDX[3:]):
        for k in range(3):
            col_joint.append(ci), col_kind.append(0), col_dir.append(k), col_owner.append(3 + c)
        col_joint.append(ci), col_kind.append(2), col_dir.append(c), col_owner.append(3 + c)
    for c, ci in enumerate(_CUT_IDX[:3]):
        col_joint += [ci] * 3
        col_kind += [0, 1, 1]
        col_dir += [2, 0, 1]
        col_owner += [c] * 3
    el_joint = np.zeros((len(ELASTIC_BODIES), 4), np.int64)
    el_sign = np.zeros((len(ELASTIC_BODIES), 4))
    el_count = np.zeros(len(ELASTIC_BODIES), np.int64)
    for e, body in enumerate(ELASTIC_BODIES):
        nodes = _body_nodes(body)
        el_count[e] = len(nodes)
        for i, (j, sg) in enumerate(nodes):
            el_joint[e, i], el_sign[e, i] = j, sg
    i64 = np.int64
    return {
        "row_joint": np.array(row_joint, i64), "row_dir": np.array(row_dir, i64),
        "col_joint": np.array(col_joint, i64), "col_kind": np.array(col_kind, i64),
        "col_dir": np.array(col_dir, i64), "col_owner": np.array(col_owner, i64),
        "el_body": np.array([_B[b] for b in ELASTIC_BODIES], i64),
        "el_joint": el_joint, "el_sign": el_sign, "el_count": el_count,
    }



def _fast(model: PdmModel, kin: PdmKinematics, compliance: bool) -> tuple[Array, Array, Array]:
    """Joint wrenches (n, 19, 6) about the origin, redundants (n, 9) and joint points (n, 19, 3)
    from the compiled kernel (same computation as ``_solve_cuts`` + ``_segments``)."""
    from ._pdm_ne_kernel import ne_kernel

    pts = joint_points(model, kin)
    n = pts.shape[0]
    st = {k: np.stack([getattr(b, k) for b in kin.bodies], axis=0)
          for k in ("p", "a", "w", "wd", "R")}
    secs = _sections(model)
    # the compatibility equations are homogeneous in the compliances: divide every stiffness by
    # the (common) E, which changes no reaction and keeps the numbers O(1) for any valid E
    E = model.youngs_modulus_Pa
    EI = np.array([secs[b].E * secs[b].Iy for b in ELASTIC_BODIES]) / E  # type: ignore[attr-defined]
    GJ = np.array([secs[b].G * secs[b].Ip for b in ELASTIC_BODIES]) / E  # type: ignore[attr-defined]
    W = np.empty((n, _NJ, 6))
    X = np.zeros((n, 9))
    tb = _tables()
    bad = ne_kernel(st["p"], st["a"], st["w"], st["wd"], st["R"], model.mass, model.inertia, model.gravity,
                    pts, np.ascontiguousarray(_axes(kin)), np.ascontiguousarray(kin.U3), _SUB, _CUT_SIGN,
                    tb["row_joint"], tb["row_dir"], tb["col_joint"], tb["col_kind"], tb["col_dir"],
                    tb["col_owner"], 14, tb["el_body"], tb["el_joint"], tb["el_sign"], tb["el_count"],
                    EI, GJ, compliance, W, X)
    if bad >= 0:
        raise SingularityError(f"t = {kin.t[bad]:.6g} s: the PDM's equilibrium equations are singular "
                               "(a limb or the six-bar at a singular configuration)")
    return W, X, pts


def actuator_forces(model: PdmModel, kin: PdmKinematics, u_joint_torque: bool = True) -> Array:
    """The four actuator forces (n, 4) [N], Newton-Euler (Eq. 49-62), order l11, l12, l23, l24.

    ``u_joint_torque=False`` neglects the constraint torque of the U joints (the comparison of
    Fig. 23). The nine redundant reactions do not enter the actuator forces.
    """
    if u_joint_torque:
        W, _, _ = _fast(model, kin, compliance=False)
    else:
        _, _, W, _, _ = _solve_cuts(model, kin, with_redundants=False, u_torque=False)
    return np.einsum("nkc,nkc->nk", W[:, _P_IDX, :3], kin.u)


# ----------------------------------------------------------------------------- compliance
def _sections(model: PdmModel) -> dict[str, object]:
    return {b: circular_section(model.youngs_modulus_Pa, model.poisson_ratio,
                                float(model.section_outer[_B[b]]), float(model.section_inner[_B[b]]))
            for b in ELASTIC_BODIES}


def _body_nodes(body: str) -> list[tuple[int, float]]:
    """(joint index, sign) of every joint acting on ``body``: +1 as body_b, -1 as body_a."""
    out = []
    for j, (_, _, a, b) in enumerate(JOINTS):
        if b == body:
            out.append((j, 1.0))
        elif a == body:
            out.append((j, -1.0))
    return out


def _beam_loads(kin: PdmKinematics, pts: Array, W: Array, D: Array | None, body: str
                ) -> tuple[Array, Array]:
    """Node positions (n, N) along the body's x axis and node loads (n, N, 6, *cols) in the body
    frame, moment about the node (a point on the axis): the joint wrenches acting on the body
    and, at the centre of mass, ``-D_b`` (gravity and d'Alembert load; zero when ``D`` is None)."""
    bs = kin.body(body)
    c, R = bs.p, bs.R
    x = R[:, :, 0]
    extra = W.ndim - 3
    s_list, L_list = [], []
    for j, sign in _body_nodes(body):
        s = np.einsum("nk,nk->n", pts[:, j] - c, x)
        node = c + s[:, None] * x
        w = sign * W[:, j]
        f, n0 = w[:, :3], w[:, 3:]
        m = n0 - _cross_e(node, f, extra)
        s_list.append(s)
        L_list.append(np.concatenate([_rotT(R, f, extra), _rotT(R, m, extra)], axis=1))
    s_list.append(np.zeros(c.shape[0]))
    if D is not None:
        d = -D[:, _B[body]]
        L_list.append(np.concatenate([_rotT(R, d[:, :3], 0), _rotT(R, d[:, 3:] - np.cross(c, d[:, :3]), 0)], axis=1))
    else:
        L_list.append(np.zeros_like(L_list[0]))
    return np.stack(s_list, axis=1), np.stack(L_list, axis=1)


def _cross_e(p: Array, f: Array, extra: int) -> Array:
    """``p x f`` with ``p`` (n, 3) and ``f`` (n, 3, *cols)."""
    p = p.reshape(p.shape + (1,) * extra)
    return np.stack([p[:, 1] * f[:, 2] - p[:, 2] * f[:, 1],
                     p[:, 2] * f[:, 0] - p[:, 0] * f[:, 2],
                     p[:, 0] * f[:, 1] - p[:, 1] * f[:, 0]], axis=1)


def _rotT(R: Array, v: Array, extra: int) -> Array:
    """``R^T v`` with ``v`` (n, 3, *cols)."""
    if extra == 0:
        return np.einsum("nab,na->nb", R, v)
    return np.einsum("nab,na...->nb...", R, v)


def _segments(model: PdmModel, kin: PdmKinematics, pts: Array, W: Array, D: Array | None
              ) -> tuple[Array, Array]:
    """Internal wrenches (n, S, 6, *cols) and flexibilities (n, S, 6, 6) of every segment of
    every elastic link (``inertia.ELASTIC_BODIES``)."""
    secs = _sections(model)
    F, C = [], []
    for body in ELASTIC_BODIES:
        s, loads = _beam_loads(kin, pts, W, D, body)
        length, f = segment_wrenches(s, loads)
        F.append(f)
        C.append(beam_flexibility(length, secs[body]))  # type: ignore[arg-type]
    return np.concatenate(F, axis=1), np.concatenate(C, axis=1)


def inverse_dynamics(model: PdmModel, kin: PdmKinematics) -> PdmReactions:
    """Actuator forces and every joint reaction, unique through link compliance (Eq. 49-83).

    Solves the 14 free-direction equations of the spanning tree (module docstring), then the
    nine redundants from the compatibility equations (Eq. 83) in the form of
    :func:`pkmdyn.analysis.compliance.solve_redundants`, and assembles all 19 joint wrenches.
    """
    W, _, pts = _fast(model, kin, compliance=True)
    f = W[..., :3]
    m = W[..., 3:] - cross(pts, f)
    red = np.stack([np.stack([f[:, j, 2], m[:, j, 0], m[:, j, 1]], axis=-1) for j in _CUT_IDX[:3]], axis=1)
    return PdmReactions(
        t=kin.t, force=np.einsum("nkc,nkc->nk", f[:, _P_IDX], kin.u),
        joint_point=pts, joint_force=f, joint_moment=m, redundant=red.reshape(-1, 9),
        u_joint_torque=np.einsum("njc,njc->nj", m[:, _U_IDX], kin.U3),
    )


# ----------------------------------------------------------------------------- general route
def _bases(kin: PdmKinematics, pts: Array) -> list[Array]:
    """Per joint, the unit wrenches about the origin (n, 6, c_j) of its reaction components:
    R: f_x, f_y, f_z and the moments about two axes normal to the joint axis (base x, y for
    the z axes; platform y, z for R4); P: f and m (all six); S: f; U: f and the torque on U_j3."""
    n = pts.shape[0]
    E = np.broadcast_to(np.eye(3), (n, 3, 3))
    out = []
    for j, (name, typ, _, _) in enumerate(JOINTS):
        p = pts[:, j]
        cols = [_unit_wrenches(p, E[:, k]) for k in range(3)]
        if typ == "R":
            normals = (kin.pos.T[:, :, 1], kin.pos.T[:, :, 2]) if name == "R4" else (E[:, 0], E[:, 1])
            cols += [_couple(v) for v in normals]
        elif typ == "P":
            cols += [_couple(E[:, k]) for k in range(3)]
        elif typ == "U":
            cols.append(_couple(kin.U3[:, _U_IDX.index(j)]))
        out.append(np.stack(cols, axis=-1))
    return out


def equilibrium_system(model: PdmModel, kin: PdmKinematics) -> tuple[Array, Array, list[Array]]:
    """All 84 Newton-Euler equations in the 93 reaction components: ``A`` (n, 84, 93),
    ``b`` (n, 84) and the per-joint bases of :func:`_bases` (the columns of joint j are
    ``sum(c_0..c_{j-1}) .. + c_j``). Body rows in ``BODY_NAMES`` order, force then moment about
    the origin."""
    pts = joint_points(model, kin)
    bases = _bases(kin, pts)
    n = pts.shape[0]
    width = sum(_COMPONENTS[t] for _, t, _, _ in JOINTS)
    A = np.zeros((n, 6 * _NB, width))
    col = 0
    for j, (_, typ, a, b) in enumerate(JOINTS):
        c = _COMPONENTS[typ]
        if b != "ground":
            A[:, 6 * _B[b]:6 * _B[b] + 6, col:col + c] += bases[j]
        if a != "ground":
            A[:, 6 * _B[a]:6 * _B[a] + 6, col:col + c] -= bases[j]
        col += c
    return A, body_loads(model, kin).reshape(n, -1), bases


def _lambda_wrenches(bases: list[Array]) -> Array:
    """Joint wrenches (n, 19, 6, 93) of unit reaction components (block structure)."""
    n = bases[0].shape[0]
    width = sum(b.shape[-1] for b in bases)
    W = np.zeros((n, _NJ, 6, width))
    col = 0
    for j, B in enumerate(bases):
        W[:, j, :, col:col + B.shape[-1]] = B
        col += B.shape[-1]
    return W


def compliance_system(model: PdmModel, kin: PdmKinematics) -> tuple[Array, Array, Array]:
    """Segment maps for :func:`pkmdyn.analysis.compliance.unique_reactions`: ``G`` (n, S, 6, 93),
    ``w0`` (n, S, 6) and ``C`` (n, S, 6, 6), in the unknowns of :func:`equilibrium_system`."""
    pts = joint_points(model, kin)
    D = body_loads(model, kin)
    G, C = _segments(model, kin, pts, _lambda_wrenches(_bases(kin, pts)), None)
    w0, _ = _segments(model, kin, pts, np.zeros((pts.shape[0], _NJ, 6)), D)
    return G, w0, C


def wrench_to_components(reac: PdmReactions, kin: PdmKinematics) -> Array:
    """The 93 reaction components (n, 93) of :func:`equilibrium_system` from a result."""
    out = []
    for j, (name, typ, _, _) in enumerate(JOINTS):
        f, m = reac.joint_force[:, j], reac.joint_moment[:, j]
        out.append(f)
        if typ == "R":
            if name == "R4":
                out.append(np.stack([(m * kin.pos.T[:, :, 1]).sum(-1), (m * kin.pos.T[:, :, 2]).sum(-1)], axis=-1))
            else:
                out.append(m[:, :2])
        elif typ == "P":
            out.append(m)
        elif typ == "U":
            out.append(reac.u_joint_torque[:, _U_IDX.index(j)][:, None])
    return np.concatenate(out, axis=1)


# ----------------------------------------------------------------------------- Eq. 83 by paths
_PATHS = {
    "R32": ((("crank1", "R11", "R21"), ("coupler1", "R21", "R31"), ("link4", "R31", "R32")),
            (("crank2", "R12", "R22"), ("coupler2", "R22", "R32"))),
    "R21'": ((("cylinder1", "R41", "P11"), ("piston1", "P11", "R21'")), (("crank1", "R11", "R21'"),)),
    "R22'": ((("cylinder2", "R42", "P12"), ("piston2", "P12", "R22'")), (("crank2", "R12", "R22'"),)),
}


def compatibility_deflections(model: PdmModel, kin: PdmKinematics, reac: PdmReactions) -> Array:
    """Elastic deflection of the cut joints R32, R21', R22' reached from each side, Eq. 71-83.

    Module by module as in the paper: each elastic link on a path from the ground is a
    cantilever clamped where the path enters it (Eq. 67); every load on it beyond the clamp
    (joint wrenches and its own gravity and d'Alembert load at the centre of mass) deflects it
    by ``C(a) F`` at the load's abscissa ``a`` (capped at the exit point, Eq. 64), carried
    rigidly to the cut joint (Eq. 66, 68); the sum over the path is Eq. 69. Returns
    (n, 3, 2, 3): cut (R32, R21', R22'), side (the paper's limb 1/3/5, limb 2/4/6), component
    (dz [m], theta_x, theta_y [rad]) in the base frame. Eq. 83 says the two sides agree.
    """
    D = body_loads(model, kin)
    W = np.concatenate([reac.joint_force, reac.joint_moment + cross(reac.joint_point, reac.joint_force)], axis=-1)
    pts = reac.joint_point
    secs = _sections(model)
    n = pts.shape[0]
    out = np.zeros((n, 3, 2, 3))
    for c, cut in enumerate(("R32", "R21'", "R22'")):
        Q = pts[:, _JN.index(cut)]
        for side, path in enumerate(_PATHS[cut]):
            theta = np.zeros((n, 3))
            disp = np.zeros((n, 3))
            for body, enter, leave in path:
                bs = kin.body(body)
                x = bs.R[:, :, 0]
                s, loads = _beam_loads(kin, pts, W, D, body)
                se = np.einsum("nk,nk->n", pts[:, _JN.index(enter)] - bs.p, x)
                sx = np.einsum("nk,nk->n", pts[:, _JN.index(leave)] - bs.p, x)
                sig = np.sign(sx - se)
                flip = np.stack([sig, sig, np.ones(n)], axis=-1)
                Rl = bs.R * flip[:, None, :]  # local frame: x from the entry towards the exit
                span = np.abs(sx - se)
                for i in range(s.shape[1]):
                    xi = sig * (s[:, i] - se)
                    a = np.clip(xi, 0.0, span)
                    active = xi > 0
                    f_loc = loads[:, i, :3] * flip
                    m_loc = loads[:, i, 3:] * flip
                    # move the load from xi to a along the local x axis: m += (xi - a) e_x x f
                    d = xi - a
                    m_loc = m_loc + np.stack([np.zeros(n), -d * f_loc[:, 2], d * f_loc[:, 1]], axis=-1)
                    Ca = beam_flexibility(a, secs[body])  # type: ignore[arg-type]
                    X = np.einsum("nab,nb->na", Ca, np.concatenate([f_loc, m_loc], axis=-1))
                    X *= active[:, None]
                    dp = np.einsum("nab,nb->na", Rl, X[:, :3])
                    th = np.einsum("nab,nb->na", Rl, X[:, 3:])
                    point = bs.p + (se + sig * a)[:, None] * x
                    theta += th
                    disp += dp + np.cross(th, Q - point)
            out[:, c, side] = np.stack([disp[:, 2], theta[:, 0], theta[:, 1]], axis=-1)
    return out

"""Unique joint reactions of an over-constrained described mechanism from link compliance.

The rigid equilibrium equations ``A z = b`` of :func:`pkmdyn.multibody.dynamics.newton_euler.equilibrium_system` leave
``t = k - rank A`` self-stress states of the joint wrenches ``z`` undetermined. Every body
that carries a ``section`` and a ``material`` in the description is an elastic straight beam;
the reactions are the admissible ones of least complementary energy (Menabrea), solved by the
general dense solver :func:`pkmdyn.analysis.compliance.unique_reactions`, the one the PDM uses.

Beam model of body b (the PDM's, section 4.2 and Eq. 63-64, generalised): the beam axis is
the line through the two joint centres of the body that lie farthest apart (at the sample's
pose), or with ``section.beam_axis = "body_x"`` the body frame's x axis through the centre of
mass (the PDM's choice); the nodes are every joint centre on the body and its centre of mass, projected onto
that axis (a joint's node on a body is the joint frame's origin fixed in that body: one point
but for a joint that slides, whose node on the cylinder is the cylinder's point and on the
piston the piston's point that was there at the reference configuration, so each tube keeps
its own length whichever body the description names the joint's parent; a joint's
``bearing`` puts both nodes at the point fixed in the body it names, e.g. a cylinder's mouth) (a body that is no beam, with one joint or all its joints at one point, is refused when the description is read); the loads at the nodes are the joint wrenches acting on the body (``+W_j`` as the
child, ``-W_j`` as the parent) and, at the centre of mass, the gravity and d'Alembert load
``-W_b`` (Eq. 1 of :mod:`pkmdyn.multibody.dynamics.newton_euler`), each reduced to its node (moment transported along the
offset from the axis). Each segment between consecutive nodes is a cantilever of uniform
circular section (tension, torsion, bending; shear neglected, Eq. 64) carrying the resultant
of the loads beyond it. Bending, torsion and tension of the links strain, and the joints that
the description gives springs (``[joints.stiffness]`` ``force_N_m``, ``moment_Nm_rad``: their
reaction force and moment, :func:`joint_spring_terms`); the other joints are rigid. The compatibility equations are homogeneous in the compliances, so the reactions do
not change when every Young's modulus is scaled by one factor (tested).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ....analysis.compliance import (
    beam_flexibility,
    circular_section,
    segment_wrenches,
    unique_reactions,
    unique_reactions_energy,
)
from ....errors import ParameterError, SingularityError
from ....spatial import skew
from ...description.joint_types import JOINT_TYPES
from ...kinematics.inverse import MechanismKinematics, joint_frame
from ...model.compiler import MechanismModel
from ._compliance_kernels import beam_energy_batch

__all__ = ["elastic_bodies", "compliant_reactions", "ComplianceDataMissing", "beam_terms", "joint_spring_terms",
           "compliance_terms"]

Array = NDArray[np.float64]


class ComplianceDataMissing(ParameterError):
    """An over-constrained mechanism whose bodies lack the section and material that would make
    its reactions unique."""


def elastic_bodies(model: MechanismModel) -> list[int]:
    """Indices of the bodies with both a ``section`` and a ``material``."""
    return [b for b, ex in enumerate(model.body_extra) if ex.get("section") and ex.get("material")]


def _section(model: MechanismModel, b: int):
    sec, mat = model.body_extra[b]["section"], model.body_extra[b]["material"]
    return circular_section(float(mat["youngs_modulus_Pa"]), float(mat["poisson_ratio"]),
                            float(sec["outer_diameter_m"]), float(sec.get("inner_diameter_m", 0.0) or 0.0))


def _beam_frame(axis: Array) -> Array:
    """A rotation (n, 3, 3) whose x column is ``axis`` (n, 3) (unit)."""
    x = axis / np.linalg.norm(axis, axis=1, keepdims=True)
    helper = np.zeros_like(x)
    pick = np.argmin(np.abs(x), axis=1)
    helper[np.arange(len(x)), pick] = 1.0
    y = np.cross(x, helper)
    y /= np.linalg.norm(y, axis=1, keepdims=True)
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=2)


def _node_point(model: MechanismModel, kin: MechanismKinematics, j: int, sign: float) -> Array:
    """Joint j's node on the body it joins as the child (``sign`` +1) or the parent (-1), base
    frame (n, 3): the joint frame's origin fixed in that body, or in the joint's ``bearing`` body
    where the description names one. The frame's origins on the two bodies coincide but for a
    joint that slides: by default each tube keeps its own length (a prismatic joint's node on
    the cylinder is the cylinder's point, on the piston the piston's); with ``bearing`` the
    cylinder, both nodes are at its mouth and the stroke changes the piston's free length.
    Either way a body's nodes do not depend on which body the description names the parent."""
    side = int(model.joint_bearing[j]) if len(model.joint_bearing) else -1
    child = sign > 0 if side < 0 else side == 1
    b, p = (model.joint_child[j], model.joint_p_child[j]) if child else (model.joint_parent[j],
                                                                         model.joint_p_parent[j])
    if b < 0:
        return np.broadcast_to(p, (len(kin), 3))
    return kin.origin[:, b] + np.einsum("nij,j->ni", kin.R[:, b], p)


def _beam_bodies(model: MechanismModel, kin: MechanismKinematics, elastic: list[int]) -> list[tuple]:
    """The elastic bodies that are beams (module docstring): ``(body, [(joint, sign), ...], mode,
    (i0, i1))``, mode 0 for the body's x axis, 1 for the line from node i0 to node i1 (the two
    joint centres farthest apart at the first sample); a body with fewer than two joints, or
    with every joint at one point, is left out (it stays rigid)."""
    nj = len(model.joint_names)
    out = []
    for bi in elastic:
        joints = [(j, 1.0) for j in range(nj) if model.joint_child[j] == bi]
        joints += [(j, -1.0) for j in range(nj) if model.joint_parent[j] == bi]
        if len(joints) < 2:
            continue
        if model.body_extra[bi]["section"].get("beam_axis", "joints") == "body_x":
            out.append((bi, joints, 0, (0, 0)))
            continue
        pts = np.stack([_node_point(model, kin, j, sg)[0] for j, sg in joints])
        d = np.linalg.norm(pts[:, None] - pts[None], axis=-1)
        i0, i1 = np.unravel_index(int(np.argmax(d)), d.shape)
        if d[i0, i1] <= 1e-9 * model.length_scale:
            continue
        out.append((bi, joints, 1, (int(i0), int(i1))))
    return out


def _compiled_energy(model: MechanismModel, kin: MechanismKinematics, W: Array, elastic: list[int],
                     affine: tuple[Array, Array]) -> tuple[Array, Array, int] | None:
    """``(H, h, segments)`` of the elastic bodies in the unknowns ``lam`` of ``affine`` by the
    compiled pass (:mod:`pkmdyn.multibody.dynamics.compliance._compliance_kernels`), or None where the joints carry springs (their
    terms: :func:`compliance_terms`)."""
    if any(st and ("force_N_m" in st or "moment_Nm_rad" in st) for st in model.joint_stiffness):
        return None
    beams = _beam_bodies(model, kin, elastic)
    z0, Z = affine
    n, K = Z.shape[0], Z.shape[2]
    if not beams:
        return np.zeros((n, K, K)), np.zeros((n, K)), 0
    secs = [_section(model, bi) for bi, *_ in beams]
    start = np.cumsum([0] + [len(js) for _, js, _, _ in beams]).astype(np.int64)
    H, h = np.empty((n, K, K)), np.empty((n, K))
    beam_energy_batch(np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.origin), np.ascontiguousarray(kin.p),
                      np.ascontiguousarray(W), np.ascontiguousarray(z0), np.ascontiguousarray(Z),
                      np.array([bi for bi, *_ in beams], dtype=np.int64),
                      np.array([md for _, _, md, _ in beams], dtype=np.int64),
                      np.array([ends for *_, ends in beams], dtype=np.int64).reshape(-1, 2), start,
                      np.array([j for _, js, _, _ in beams for j, _ in js], dtype=np.int64),
                      np.array([sg for _, js, _, _ in beams for _, sg in js]),
                      np.ascontiguousarray(np.stack([_node_point(model, kin, j, sg) for _, js, _, _ in beams
                                                     for j, sg in js], axis=1)),
                      np.array([sc.E * sc.A for sc in secs]), np.array([sc.E * sc.Iy for sc in secs]),
                      np.array([sc.E * sc.Iz for sc in secs]), np.array([sc.G * sc.Ip for sc in secs]), H, h)
    return H, h, int(sum(len(js) for _, js, _, _ in beams))


def compliant_reactions(model: MechanismModel, kin: MechanismKinematics, A: Array, b: Array, rank: int,
                        W: Array | None = None, affine: tuple[Array, Array] | None = None) -> tuple[Array, int]:
    """Joint wrenches ``z (n, 6 nj)`` (Plücker at the origin, see :mod:`pkmdyn.multibody.dynamics.newton_euler`) solving
    ``A z = b`` with least complementary energy of the elastic bodies (module docstring).

    ``W`` (n, nb, 6): the required body wrenches (``b``'s first ``6 nb`` entries when omitted).
    ``affine = (z0, Z)``: the equations are in other unknowns ``lam`` (the cut joints'
    constraint-wrench components) with ``z = z0 + Z lam``; the energy is then written in them.
    Returns ``z`` and the number of self-stress states.
    Raises :class:`~pkmdyn.errors.ParameterError` when the mechanism is over-constrained and
    the bodies that would decide the self-stress carry no section or material."""
    n = A.shape[0]
    nb, nj = model.nb, len(model.joint_names)
    k = 6 * nj
    if W is None:
        W = b[:, : 6 * nb].reshape(n, nb, 6)
    elastic = elastic_bodies(model)
    t = (A.shape[2] - rank) if rank >= 0 else int(model.topology.overconstraints)
    if not elastic and not any(st and ("force_N_m" in st or "moment_Nm_rad" in st) for st in model.joint_stiffness):
        names = ", ".join(model.body_names[:4]) + (", ..." if len(model.body_names) > 4 else "")
        raise ComplianceDataMissing(f"mechanism {model.name!r} is over-constrained ({t} self-stress states) and no "
                                    f"body carries a section and a material ({names}): the joint reactions cannot be "
                                    "made unique (give [[bodies]] section and material)")
    energy = _compiled_energy(model, kin, W, elastic, affine) if affine is not None else None
    if energy is None:
        G, w0, C = compliance_terms(model, kin, W, elastic, affine)
        segments = G.shape[1]
    else:
        segments = energy[2]
    if segments == 0:
        raise ComplianceDataMissing(f"mechanism {model.name!r} is over-constrained ({t} self-stress states) and no "
                                    "elastic body joins two joints: the joint reactions cannot be made unique")
    if energy is None:
        # the compatibility equations are homogeneous in the flexibilities: normalise them (no
        # change in the result, O(1) numbers for any modulus)
        C = C / np.abs(C).max()
    if affine is not None:  # G and w0 (or the energy) are already in the unknowns lam
        scale = np.ones(A.shape[2])
    else:
        scale = np.ones((nj, 6))
        scale[:, :3] = model.length_scale
        scale = np.concatenate([scale.reshape(-1), np.ones(A.shape[2] - k)])
        if A.shape[2] > k:  # the idle freedoms' holding forces (dynamics.idle_holding) strain no body
            G = np.concatenate([G, np.zeros(G.shape[:3] + (A.shape[2] - k,))], axis=3)
    try:
        if energy is None:
            res = unique_reactions(A * scale, b, G * scale, w0, C)
        else:
            res = unique_reactions_energy(A, b, energy[0], energy[1])
    except SingularityError:
        missing = [model.body_names[i] for i in range(nb) if i not in elastic]
        raise ComplianceDataMissing(f"mechanism {model.name!r}: a self-stress state strains no elastic body; give a section "
                             f"and a material to the bodies of the over-constrained loops (without: "
                             f"{', '.join(missing[:8])}{' ...' if len(missing) > 8 else ''})") from None
    lam = res.lam * scale
    t = int(A.shape[2] - res.rank.min())
    if affine is not None:
        return affine[0] + np.einsum("nkl,nl->nk", affine[1], lam), t
    return lam[:, :k], t


def beam_terms(model: MechanismModel, kin: MechanismKinematics, W: Array, elastic: list[int] | None = None,
               affine: tuple[Array, Array] | None = None) -> tuple[Array, Array, Array]:
    """The elastic bodies' beam segments (module docstring): ``G (n, S, 6, 6 nj)`` and
    ``w0 (n, S, 6)`` with the internal wrench of segment s at its far end ``G_s z + w0_s``
    (beam frame) for the joint wrenches ``z`` and the required body wrenches ``W (n, nb, 6)``,
    and its flexibility ``C (n, S, 6, 6)`` (Eq. 64).

    ``affine = (z0, Z)`` with ``z = z0 + Z lam`` (``Z (n, 6 nj, l)``): ``G`` and ``w0`` in the
    unknowns ``lam`` instead, ``G Z (n, S, 6, l)`` and ``w0 + G z0``. A body's segments depend on
    the wrenches of its own joints only: they are formed in those columns and never as the
    full ``6 nj`` columns when ``affine`` is given."""
    n = len(kin)
    nj = len(model.joint_names)
    k = 6 * nj
    if elastic is None:
        elastic = elastic_bodies(model)
    G_list, w0_list, C_list = [], [], []
    for bi, joints, mode, (i0, i1) in _beam_bodies(model, kin, elastic):
        pts = np.stack([_node_point(model, kin, j, sg) for j, sg in joints], axis=1)  # (n, N, 3)
        if mode == 0:
            Rb = kin.R[:, bi]
            origin = kin.p[:, bi]
        else:
            Rb = _beam_frame(pts[:, i1] - pts[:, i0])
            origin = pts[:, i0]
        nodes = np.concatenate([pts, kin.p[:, bi][:, None]], axis=1)  # (n, N+1, 3)
        s = np.einsum("nmi,ni->nm", nodes - origin[:, None], Rb[:, :, 0])
        on_axis = origin[:, None] + s[..., None] * Rb[:, None, :, 0]
        N = nodes.shape[1]
        cols = np.array([6 * j + c for j, _ in joints for c in range(6)])
        L = np.zeros((n, N, 6, len(cols)))
        L0 = np.zeros((n, N, 6))
        RbT = np.swapaxes(Rb, 1, 2)
        for m_, (j, sg) in enumerate(joints):
            # wrench sg W_j about O -> [f; moment about the node on the axis], beam frame:
            # a unit moment e_c (c < 3) gives R^T e_c; a unit force e_c gives f' = R^T e_c and
            # the moment R^T (-x e_c) about the node x
            L[:, m_, 3:, 6 * m_:6 * m_ + 3] = sg * RbT
            L[:, m_, :3, 6 * m_ + 3:6 * m_ + 6] = sg * RbT
            L[:, m_, 3:, 6 * m_ + 3:6 * m_ + 6] = -sg * (RbT @ skew(on_axis[:, m_]))
        f0 = -W[:, bi, 3:]
        m0 = -W[:, bi, :3] - np.cross(on_axis[:, -1], f0)
        L0[:, -1, :3] = np.einsum("nji,nj->ni", Rb, f0)
        L0[:, -1, 3:] = np.einsum("nji,nj->ni", Rb, m0)
        lengths, Gs = segment_wrenches(s, L)
        _, w0 = segment_wrenches(s, L0)
        C = beam_flexibility(lengths, _section(model, bi))
        nS = Gs.shape[1]
        if affine is None:
            full = np.zeros((n, nS, 6, k))
            full[..., cols] = Gs
            G_list.append(full)
        else:
            Gf = Gs.reshape(n, 6 * nS, len(cols))
            w0 = w0 + (Gf @ affine[0][:, cols, None]).reshape(n, nS, 6)
            G_list.append((Gf @ affine[1][:, cols]).reshape(n, nS, 6, affine[1].shape[2]))
        w0_list.append(w0)
        C_list.append(C)
    if not G_list:
        width = k if affine is None else affine[1].shape[2]
        return np.zeros((n, 0, 6, width)), np.zeros((n, 0, 6)), np.zeros((n, 0, 6, 6))
    return np.concatenate(G_list, axis=1), np.concatenate(w0_list, axis=1), np.concatenate(C_list, axis=1)


def joint_spring_terms(model: MechanismModel, kin: MechanismKinematics) -> tuple[Array, Array]:
    """The joints' springs (``[joints.stiffness]`` ``force_N_m``, ``moment_Nm_rad``): ``P (n, s, 6,
    6 nj)`` giving each sprung joint's reaction ``[f; m]`` (force, moment about the joint
    point, along the axes of its frame on the parent) from the joint wrenches ``z``, and the
    flexibility ``C (n, s, 6, 6)`` (diagonal, ``1/k``; zero along a rigid direction and along an
    actuated joint's driven axis, whose load its drive carries: ``drive_N_m``/``drive_Nm_rad``)."""
    n, nj = len(kin), len(model.joint_names)
    P_list, C_list = [], []
    for j, st in enumerate(model.joint_stiffness):
        if not st or not ("force_N_m" in st or "moment_Nm_rad" in st):
            continue
        RP, _ = joint_frame(model, kin, j, child=False)
        pt = kin.joint_point[:, j]
        P = np.zeros((n, 1, 6, 6 * nj))
        # W_j = [n_O; f]: f' = R^T f, m' = R^T (n_O - p x f)
        RT = np.swapaxes(RP, 1, 2)
        P[:, 0, :3, 6 * j + 3:6 * j + 6] = RT
        P[:, 0, 3:, 6 * j:6 * j + 3] = RT
        P[:, 0, 3:, 6 * j + 3:6 * j + 6] = -RT @ skew(pt)
        c = np.zeros(6)
        if "force_N_m" in st:
            c[:3] = 1.0 / np.asarray(st["force_N_m"], dtype=float)
        if "moment_Nm_rad" in st:
            c[3:] = 1.0 / np.asarray(st["moment_Nm_rad"], dtype=float)
        if model.joint_actuated[j]:  # along the driven axis (the joint frame's z) the drive carries the load
            c[2 if JOINT_TYPES[model.joint_type[j]].units[0] == "m" else 5] = 0.0
        P_list.append(P)
        C_list.append(np.broadcast_to(np.diag(c), (n, 1, 6, 6)))
    if not P_list:
        return np.zeros((n, 0, 6, 6 * nj)), np.zeros((n, 0, 6, 6))
    return np.concatenate(P_list, axis=1), np.concatenate(C_list, axis=1)


def compliance_terms(model: MechanismModel, kin: MechanismKinematics, W: Array, elastic: list[int] | None = None,
                     affine: tuple[Array, Array] | None = None) -> tuple[Array, Array, Array]:
    """Every compliant member's internal wrench ``G_s z + w0_s`` and flexibility ``C_s``: the
    elastic bodies' beam segments (:func:`beam_terms`), then the joints' springs
    (:func:`joint_spring_terms`, ``w0 = 0``); with ``affine = (z0, Z)`` in the unknowns ``lam`` of
    ``z = z0 + Z lam`` (:func:`beam_terms`)."""
    Gb, w0b, Cb = beam_terms(model, kin, W, elastic, affine)
    Pj, Cj = joint_spring_terms(model, kin)
    if affine is not None and Pj.shape[1]:
        nP = Pj.shape[1]
        Pf = Pj.reshape(n := len(kin), 6 * nP, -1)
        return (np.concatenate([Gb, (Pf @ affine[1]).reshape(n, nP, 6, -1)], axis=1),
                np.concatenate([w0b, (Pf @ affine[0][..., None]).reshape(n, nP, 6)], axis=1),
                np.concatenate([Cb, Cj], axis=1))
    if affine is not None:
        return Gb, w0b, Cb
    return (np.concatenate([Gb, Pj], axis=1), np.concatenate([w0b, np.zeros(Pj.shape[:3])], axis=1),
            np.concatenate([Cb, Cj], axis=1))

"""Inverse dynamics and joint reactions of any described mechanism, batched over samples.

Notation (base frame, SI). Spatial vectors are Plücker coordinates at the base origin O: a
twist ``V = [w; v_O]`` (angular velocity, velocity of the body point at O) and a wrench
``W = [n_O; f]`` (moment about O, force); power is ``V . W``. ``S_c`` (6,) is the unit
twist of tree coordinate c (the kernels' ``forward_positions``), so that body b moves with
``V_b = sum_{c in anc(b)} S_c qd_c`` (Featherstone 2008, Eq. 3.40 in world coordinates).

**Required body wrench** (Newton-Euler, what the joints must supply to body b so that it
follows the motion):

    f_b   = m_b (a_b - g) - sum_loads F
    n_O,b = I_b wd_b + w_b x I_b w_b + p_b x m_b (a_b - g) - sum_loads (M + r x F)       (1)

with ``a_b, p_b`` the centre of mass's acceleration and position, ``I_b = R_b I'_b R_b^T``.

**Actuator efforts** (natural orthogonal complement; Featherstone's gamma_q form,
``IDgq``): the generalised tree forces are ``Q_c = S_c . sum_{b: c in anc(b)} W_b`` (2);
the loop closure gives the tree rates as ``qd = G xd`` (``G`` from the kinematics), so by
virtual work the actuator efforts ``u`` satisfy

    J_ax^T u = G^T (Q + Q_f)                                                                 (3)

(``J_ax = dq_a/dx``, ``Q_f`` the friction's generalised forces, zero here). With as many
actuators as task coordinates (3) is square; a redundantly actuated mechanism shares the
efforts by its ``[actuation]`` distribution (:mod:`pkmdyn.multibody.dynamics.distribution`; by
default the minimum-norm ``u = pinv(J_ax^T) G^T Q``).

**Joint reactions.** Unknown: the wrench ``W_j = [n_O; f]`` (6,) that joint j's parent
exerts on its child, every joint (tree and cut). Equations, per sample:

    sum_{j: child b} W_j - sum_{j: parent b} W_j = W_b               (6 per body, Eq. 1)
    s_j T_i . W_j = e_i          for every free twist T_i of joint j (power balance of the joint)

with ``e_i`` the actuator effort of an actuated coordinate and zero otherwise (``s_j = -1``
for a tree joint traversed from its child, whose twist is the parent's relative to the
child). For a tree joint ``T_i = S_c``; for a cut joint the free twists are those of its
type at its frames (rotation axes through the child frame's origin; the last elementary
motion about the child frame's axis, the others about the parent frame's). The solution is
unique when the mechanism is not over-constrained; otherwise ``t`` self-stress states remain
(the null space of the matrix), which :mod:`pkmdyn.multibody.dynamics.compliance.reactions` fixes by link compliance.
Reported as ``joint_force`` (n, nj, 3) [N] and ``joint_moment`` (n, nj, 3) [N m] about the
joint point (``kin.joint_point``), the PDM's schema.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError, SingularityError, at_sample
from ..description.joint_types import JOINT_TYPES, MOTION_CODES, type_code
from ..kinematics.inverse import MechanismKinematics, joint_frame
from ..model.compiler import MechanismModel
from ._dyn_kernels import (
    apply_loads,
    body_wrench_batch,
    generalised_batch,
    square_efforts_batch,
    task_mass_batch,
    twists_batch,
    twists_from_poses,
)
from ._reaction_kernels import cut_reactions_batch
from .distribution import distribute, least_norm_map
from .friction import JointFriction, friction_diverges, known_friction
from .loads import load_forces, named_magnitudes
from .compliance.reactions import compliant_reactions

__all__ = ["body_wrenches", "spring_wrenches", "named_magnitudes", "load_forces", "coordinate_twists", "generalised_forces", "actuator_efforts",
           "InverseDynamics", "inverse_dynamics", "idle_holding", "EffortShares", "effort_shares", "effort_unit", "free_twists", "equilibrium_system",
           "JointReactions", "joint_reactions", "energies", "SINGULAR_ACTUATION", "inertia_factors",
           "task_mass_matrix"]

Array = NDArray[np.float64]

#: the actuator map is singular on a sample where the rows of ``J_ax^T`` (columns scaled) are
#: nearly dependent: its Hadamard ratio ``|det| / prod |rows|`` (0 singular, 1 orthogonal rows)
#: falls below this, and the smallest singular value is below this times the largest (the
#: SVD confirms the flagged samples; rows of very different size but independent directions
#: are not a singularity)
SINGULAR_ACTUATION = 1e-9


def inertia_factors(model: MechanismModel) -> Array:
    """``L (nb, 3, 3)`` with ``I' = L L^T`` for each body's inertia about its centre of mass in
    its frame (``L = V diag(sqrt(lambda))`` from the eigenvectors ``V`` and principal moments
    ``lambda``, which the description's check keeps non-negative; a rounding excursion below
    zero counts as zero): the mass matrix kernels build ``w^T I w`` as ``|L^T w|^2``."""
    lam, vec = np.linalg.eigh(np.asarray(model.inertia, dtype=float))
    return np.ascontiguousarray(vec * np.sqrt(np.clip(lam, 0.0, None))[:, None, :])


def _cross(a: Array, b: Array) -> Array:
    """``a x b`` over the last axis (length 3), broadcast (numpy's ``cross`` without its axis
    handling)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def task_mass_matrix(model: MechanismModel, kin: MechanismKinematics, S: Array, factors: Array | None = None,
                     rotors: bool = True) -> Array:
    """``M(x) (n, nt, nt)``: every body's inertia in task coordinates (``S`` the coordinate
    twists, ``factors`` :func:`inertia_factors`, computed when not given) and, with ``rotors``,
    the drives' rotor inertia ``k^2 I_r`` along each actuator's row of ``J_ax``."""
    M = np.empty((len(kin), model.nt, model.nt))
    task_mass_batch(np.ascontiguousarray(S), np.ascontiguousarray(kin.G), model.body_parent, model.body_joint,
                    model.joint_q0, model.joint_nq, np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.p),
                    model.mass, inertia_factors(model) if factors is None else factors, M)
    if rotors and np.any(model.drive_rotor):
        M += np.einsum("nat,a,nas->nts", kin.J_ax, model.drive_rotor * model.drive_ratio ** 2, kin.J_ax)
    return M


def coordinate_twists(model: MechanismModel, q: Array, kin: MechanismKinematics | None = None) -> Array:
    """World unit twists ``S (n, nq, 6)`` ``[w; v_O]`` of every tree coordinate at ``q (n, nq)``;
    from the solved body poses of ``kin`` when given (fewer angles to turn; same values)."""

    q = np.ascontiguousarray(np.atleast_2d(np.asarray(q, dtype=float)))
    S = np.empty((q.shape[0], model.nq, 6))
    if kin is not None:
        twists_from_poses(q, np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.origin), model.body_parent,
                          model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion, model.coord_offset,
                          model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
                          model.tree_p_child, S)
        return S
    twists_batch(q, model.body_parent, model.body_joint, model.joint_q0, model.joint_nq, model.coord_motion,
                 model.coord_offset, model.coord_sign, model.tree_R_parent, model.tree_p_parent, model.tree_R_child,
                 model.tree_p_child, S)
    return S


def body_wrenches(model: MechanismModel, kin: MechanismKinematics, loads: dict | None = None,
                  named: Mapping[str, object] | None = None) -> Array:
    """Required wrench ``W (n, nb, 6)`` ``[n_O; f]`` [N m, N] of every body, Eq. (1).

    ``loads``: optional extra external loads per sample, ``{body name: (F (n, 3) [N],
    M (n, 3) [N m] about the centre of mass)}``, base frame, on top of the description's
    ``[[loads]]`` (base frame, at their point; a named load's magnitude per sample from
    ``named``, :func:`named_magnitudes`)."""
    Wr = np.empty(kin.p.shape[:2] + (6,))
    body_wrench_batch(np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.w), np.ascontiguousarray(kin.wd),
                      np.ascontiguousarray(kin.p), np.ascontiguousarray(kin.a), model.mass, model.inertia,
                      model.gravity, Wr)
    n_O, f = Wr[..., :3], Wr[..., 3:]
    if len(model.load_body):
        LF, LM = load_forces(model, len(kin), named)
        apply_loads(np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.origin), model.load_body,
                    np.ascontiguousarray(model.load_point), LF, LM, Wr)
    if any(sp is not None for sp in model.joint_spring):
        spring_wrenches(model, kin, Wr)
    for name, (F, M) in (loads or {}).items():
        b = model.body_index(name)
        F = np.broadcast_to(np.asarray(F, dtype=float), f[:, b].shape)
        M = np.broadcast_to(np.asarray(M, dtype=float), f[:, b].shape)
        f[:, b] -= F
        n_O[:, b] -= M + _cross(kin.p[:, b], F)
    return Wr


def spring_wrenches(model: MechanismModel, kin: MechanismKinematics, W: Array) -> None:
    """Take the joint springs' loads out of the required wrenches ``W (n, nb, 6)`` in place: a
    spring ``(k, q_s)`` on joint j (a tree joint of one coordinate ``q``, the description's) pulls
    with ``tau = -k (q - q_s)`` along the joint frame's z axis ``a`` (base frame, on the parent):
    for a revolute joint the couple ``tau a`` on the child and ``-tau a`` on the parent, for a
    prismatic one the force ``tau a`` at the joint centre on the child and its opposite on the
    parent, so that the generalised force on ``q`` is ``tau`` (virtual work) whichever way the
    tree traverses the joint. The joint's own reaction then carries no part of it."""
    n_O, f = W[..., :3], W[..., 3:]
    for j, sp in enumerate(model.joint_spring):
        if sp is None:
            continue
        k, q_s = sp
        tau = -k * (kin.q[:, int(model.joint_q0[j])] - q_s)
        par, ch = int(model.joint_parent[j]), int(model.joint_child[j])
        Ra = np.eye(3) if par < 0 else kin.R[:, par]
        a = (Ra @ model.joint_R_parent[j][:, 2]).reshape(-1, 3)
        if JOINT_TYPES[model.joint_type[j]].units[0] == "rad":
            load_f, load_n = np.zeros_like(a), tau[:, None] * a
        else:
            load_f = tau[:, None] * a
            load_n = _cross(kin.joint_point[:, j], load_f)
        for b, sign in ((ch, 1.0), (par, -1.0)):
            if b >= 0:  # the required wrench less the external load (Eq. 1)
                f[:, b] -= sign * load_f
                n_O[:, b] -= sign * load_n


def generalised_forces(model: MechanismModel, S: Array, W: Array) -> Array:
    """``Q (n, nq)``, Eq. (2): ``Q_c = S_c . sum of W_b over the bodies that coordinate c moves``."""
    Q = np.empty(S.shape[:2])
    generalised_batch(np.ascontiguousarray(S), np.ascontiguousarray(W), model.ancestor_list, Q)
    return Q


def actuator_efforts(model: MechanismModel, kin: MechanismKinematics, Q: Array, rhs_task: Array | None = None,
                     sample_offset: int = 0, consistent: bool = False) -> Array:
    """Efforts ``u (n, na)`` [N or N m] from the generalised tree forces ``Q (n, nq)``, Eq. (3)
    (or from the task-space forces ``rhs_task = G^T Q (n, nt)`` when given). With
    ``consistent``, an under-actuated mechanism's motion must be dynamically consistent
    (:func:`check_consistent`; the least-squares efforts otherwise).

    Raises :class:`~pkmdyn.errors.SingularityError` naming the first sample where the
    actuator map ``J_ax`` is singular (the actuators cannot move the mechanism there; its
    number in a longer motion: ``sample_offset`` + its index here)."""
    JT = np.swapaxes(kin.J_ax, 1, 2)  # (n, nt, na)
    scale = np.maximum(np.abs(JT).max(axis=(0, 1)), 1e-300)
    u_fast = None
    if model.na == model.nt and model.na and rhs_task is None:
        # compiled: G^T Q, LU solve and the Hadamard ratio |det A| / prod |a_k| (<= 1, zero when
        # singular) as a cheap screen; the SVD ratio decides on the samples it flags
        had = np.empty(JT.shape[0])
        u_fast = np.empty((JT.shape[0], model.na))
        square_efforts_batch(np.ascontiguousarray(kin.G), np.ascontiguousarray(Q), np.ascontiguousarray(JT),
                             scale, had, u_fast)
        rhs = None
    else:
        rhs = (np.swapaxes(kin.G, 1, 2) @ Q[..., None])[..., 0] if rhs_task is None else rhs_task
    if u_fast is not None:
        cand = np.flatnonzero(~(had > SINGULAR_ACTUATION))
        A = JT[cand] / scale
    elif model.na == model.nt and model.na:
        A = JT / scale
        norms = np.prod(np.linalg.norm(A, axis=1), axis=1)
        had = np.abs(np.linalg.det(A)) / np.where(norms > 0.0, norms, np.inf)
        cand = np.flatnonzero(~(had > SINGULAR_ACTUATION))
    else:
        A = JT / scale
        cand = np.arange(A.shape[0])
    if u_fast is None:
        A = A[cand]
    ratio = np.ones(JT.shape[0])
    if cand.size and A.shape[1] and A.shape[2]:
        sv = np.linalg.svd(A, compute_uv=False)
        ratio[cand] = sv[:, -1] / np.maximum(sv[:, 0], 1e-300)
    bad = np.flatnonzero(~(ratio > SINGULAR_ACTUATION))
    if bad.size:
        s = int(bad[0])
        raise SingularityError(f"{at_sample(s, kin.t, sample_offset)}: the actuator map is singular (smallest/largest singular value "
                               f"{ratio[s]:.3g}): the actuators {', '.join(model.actuator_names)} cannot move "
                               f"mechanism {model.name!r} there")
    if u_fast is not None:
        return u_fast
    if model.na == model.nt:
        return np.linalg.solve(JT, rhs[..., None])[..., 0]
    if model.na > model.nt:  # redundant actuation: the description's distribution
        return distribute(model, JT, rhs, kin.t, sample_offset)
    u = np.einsum("nat,nt->na", np.linalg.pinv(JT), rhs)
    if consistent and model.na < model.nt:
        check_consistent(model, kin, JT, u, rhs, sample_offset)
    return u


#: an under-actuated mechanism's motion is dynamically consistent where the generalised force
#: the actuators cannot give is at most this share of the largest generalised force
UNDERACTUATED_TOLERANCE = 1e-8
#: ... each sample's generalised force, or this share of the motion's largest where larger
FLOOR = 1e-6


def unactuated_share(JT: Array, u: Array, rhs: Array) -> Array:
    """``(n,)`` the share of each sample's generalised force along freedoms no actuator moves
    (an under-actuated mechanism, :func:`check_consistent`): the residual of Eq. 3 in the
    least-squares sense, ``|J_ax^T u - G^T Q|`` over ``max(|G^T Q|, |J_ax^T| |u|)`` (task
    coordinates of mixed units compared as written), that scale at least :data:`FLOOR` of its
    largest over the samples given. Zero where the motion is dynamically consistent."""
    r = np.linalg.norm(np.einsum("nta,na->nt", JT, u) - rhs, axis=1)
    scale = np.maximum(np.linalg.norm(rhs, axis=1), np.linalg.norm(JT, axis=(1, 2)) * np.linalg.norm(u, axis=1))
    # a sample whose generalised force is round-off (a pendulum hanging still under a cart moving
    # at constant speed) is measured against the motion's largest one, not its own
    return r / np.maximum(np.maximum(scale, FLOOR * float(scale.max(initial=0.0))), 1e-300)


def check_consistent(model: MechanismModel, kin: MechanismKinematics, JT: Array, u: Array, rhs: Array,
                     sample_offset: int = 0) -> None:
    """Refuse an under-actuated mechanism's motion (fewer actuators than degrees of freedom)
    where it is not dynamically consistent, naming the first such sample: where
    :func:`unactuated_share` is above :data:`UNDERACTUATED_TOLERANCE`, generalised force lies
    along freedoms no actuator moves and no efforts of its actuators make the motion."""
    res = unactuated_share(JT, u, rhs)
    bad = np.flatnonzero(~(res <= UNDERACTUATED_TOLERANCE))
    if bad.size:
        s = int(bad[0])
        raise MotionError(f"{at_sample(s, kin.t, sample_offset)}: mechanism {model.name!r} is under-actuated ({model.na} actuators for {model.nt} "
                          f"degrees of freedom) and the motion is not dynamically consistent there: "
                          f"{res[s]:.3g} of the generalised force lies along freedoms no actuator moves, so no efforts "
                          "of its actuators make this motion")


@dataclass(frozen=True)
class InverseDynamics:
    """``u`` (n, na) actuator efforts [N (prismatic) or N m (revolute)], order of
    ``model.actuator_names``; ``Q`` (n, nq) generalised tree forces of Eq. (2); ``W`` (n, nb,
    6) required body wrenches of Eq. (1); ``S`` (n, nq, 6) coordinate twists; ``kin``: the
    kinematics they hold for (idle freedoms held, :func:`idle_holding`)."""

    u: Array
    Q: Array
    W: Array
    S: Array
    kin: MechanismKinematics


def inverse_dynamics(model: MechanismModel, kin: MechanismKinematics, loads: dict | None = None,
                     named: Mapping[str, object] | None = None, friction: bool = True) -> InverseDynamics:
    """Actuator efforts along a solved motion (module docstring, Eq. 1-3), with the joints'
    friction when the description gives any and ``friction`` is true: Coulomb, viscous and
    the friction named loads drive directly (``Q`` then includes the friction's generalised
    forces); friction that depends on the joints' own reactions through
    :func:`joint_reactions` (``Q`` is then the rigid-body part alone).

    Idle freedoms are held as the kinematics hold them (:func:`idle_holding`): the efforts
    balance the held motion's energy exactly."""
    S = coordinate_twists(model, kin.q, kin)
    Qf = None
    if friction and fr_any(model):
        if any(f and f.get("coefficient", 0.0) for f in model.joint_friction):
            r = joint_reactions(model, kin, loads, named=named)
            W = body_wrenches(model, kin, loads, named)
            return InverseDynamics(u=r.u, Q=generalised_forces(model, S, W), W=W, S=S, kin=kin)

        Qf = known_friction(model, kin, S, named)
    W = body_wrenches(model, kin, loads, named)
    Q = generalised_forces(model, S, W)
    if Qf is not None:
        Q = Q + Qf
    u = actuator_efforts(model, kin, Q, consistent=True)
    return InverseDynamics(u=u, Q=Q, W=W, S=S, kin=kin)


def idle_holding(model: MechanismModel) -> Array:
    """``H (nq, k)``: the generalised-force directions of the rules that hold the idle freedoms.

    **Convention.** An idle freedom (a rod's spin between two spherical joints: a motion that
    moves no joint centre and no task coordinate) is held by its rule ``n_k . (q - q_ref) = 0``
    (``model.solver_idle``), an ideal constraint: positions, rates and accelerations are those
    of the held motion, each the exact time derivative of the one before, and the rule's
    reaction ``H mu`` (``mu (k,)``) is the generalised force that holds it, carried by the
    tree joints whose coordinates the rule involves (the rod's own joint), in their free
    directions. It does no work (``n_k . qd = 0``), so the efforts are those of the held
    motion (``G^T H = 0``) and every body's balance holds with it. Its size is the rod's
    spin inertia times the held spin acceleration (and the spin's friction): small, and
    reported (:attr:`JointReactions.holding`)."""
    return np.ascontiguousarray(np.asarray(model.solver_idle, dtype=float).T)


def free_twists(model: MechanismModel, kin: MechanismKinematics, S: Array, j: int) -> tuple[Array, Array]:
    """Free twists ``T (n, f, 6)`` of joint j (child relative to parent, description sense)
    and the index of its tree coordinate for each (-1 for a cut joint)."""
    jt = JOINT_TYPES[model.joint_type[j]]
    f = jt.freedoms
    if not model.joint_cut[j]:
        q0 = model.joint_q0[j]
        sign = -1.0 if model.joint_flipped[j] else 1.0
        return sign * S[:, q0:q0 + f], np.arange(q0, q0 + f)
    n = len(kin)
    T = np.zeros((n, f, 6))
    if not f:
        return T, np.full(0, -1)
    # unit twist of each elementary motion: a rotation about the axis through the child frame's
    # origin or a translation along it; the axis is the parent frame's, the last one the child
    # frame's (all the parent's for a spherical joint)
    RP, _ = joint_frame(model, kin, j, child=False)
    RC, oC = joint_frame(model, kin, j, child=True)
    for k, mname in enumerate(jt.motions):
        frame = RC if (k == f - 1 and jt.name != "spherical") else RP
        axis = frame[..., "XYZ".index(mname[1])]
        if mname[0] == "R":
            T[:, k, :3] = axis
            T[:, k, 3:] = _cross(oC, axis)
        else:
            T[:, k, 3:] = axis
    return T, np.full(f, -1)


def free_blocks(model: MechanismModel, kin: MechanismKinematics, S: Array) -> list[tuple[int, Array, Array]]:
    """``(joint, T (n, f, 6), coordinates (f,))`` for every joint with freedoms (:func:`free_twists`)."""
    out = []
    for j in range(len(model.joint_names)):
        T, coords = free_twists(model, kin, S, j)
        if T.shape[1]:
            out.append((j, T, coords))
    return out


def equilibrium_matrix(model: MechanismModel, blocks: list) -> Array:
    """``A (n, 6 nb + nf, 6 nj + k)`` of the joint-wrench equations (module docstring): the body
    rows, then each joint's free-twist rows in the order of ``blocks``; the last ``k`` columns
    are the idle freedoms' holding forces ``mu`` (:func:`idle_holding`), which enter the
    free-twist rows of the tree coordinates their rules involve: ``T_i . W_j - (H mu)_c = e_c - F_c``."""
    n = blocks[0][1].shape[0] if blocks else 1
    nb, nj = model.nb, len(model.joint_names)
    nf = sum(T.shape[1] for _, T, _ in blocks)
    H = idle_holding(model)
    A = np.zeros((n, 6 * nb + nf, 6 * nj + H.shape[1]))
    eye = np.eye(6)
    for j in range(nj):
        c, p = model.joint_child[j], model.joint_parent[j]
        if c >= 0:
            A[:, 6 * c:6 * c + 6, 6 * j:6 * j + 6] += eye
        if p >= 0:
            A[:, 6 * p:6 * p + 6, 6 * j:6 * j + 6] -= eye
    row = 6 * nb
    for j, T, coords in blocks:
        A[:, row:row + T.shape[1], 6 * j:6 * j + 6] = T
        for i, c in enumerate(coords):
            if c >= 0 and H.shape[1]:
                A[:, row + i, 6 * nj:] = -H[c]
        row += T.shape[1]
    return A


def equilibrium_rhs(model: MechanismModel, blocks: list, W: Array, coord_effort: Array,
                    friction: dict | None = None) -> Array:
    """``b (n, 6 nb + nf)``: the required body wrenches ``W (n, nb, 6)``, then per free twist
    the effort along it: ``coord_effort (n, nq)`` for a tree coordinate, less the friction
    ``friction[j] (n, f)`` (generalised resisting forces of joint j along its free twists)."""
    n = W.shape[0]
    parts = [W.reshape(n, -1)]
    for j, T, coords in blocks:
        e = np.zeros((n, T.shape[1]))
        for i, c in enumerate(coords):
            if c >= 0:
                e[:, i] = coord_effort[:, c]
        if friction is not None and j in friction:
            e = e - friction[j]
        parts.append(e)
    return np.concatenate(parts, axis=1)


def equilibrium_system(model: MechanismModel, kin: MechanismKinematics, W: Array, S: Array,
                       coord_effort: Array) -> tuple[Array, Array]:
    """The linear equations ``A z = b`` of the joint wrenches ``z (n, 6 nj)`` (module docstring):
    ``A (n, 6 nb + nf, 6 nj)``, ``b (n, 6 nb + nf)``; ``coord_effort (n, nq)`` the effort along
    each tree coordinate (actuators; zero for passive coordinates); no friction."""
    blocks = free_blocks(model, kin, S)
    return equilibrium_matrix(model, blocks), equilibrium_rhs(model, blocks, W, coord_effort)


@dataclass(frozen=True)
class JointReactions:
    """Actuator efforts and every joint's reaction along a motion.

    ``u`` (n, na) actuator efforts; ``joint_point`` (n, nj, 3) [m]; ``joint_force`` (n, nj,
    3) [N] and ``joint_moment`` (n, nj, 3) [N m] about ``joint_point``: the wrench that each
    joint's parent body exerts on its child body (order of ``model.joint_names``; a joint on
    the ground: the ground is the parent or the child as described), base frame;
    ``residual`` (n,) the largest equilibrium residual [N, N m]; ``self_stress`` the number
    of self-stress states (over-constraints) made unique by compliance (0 when rigid
    equilibrium decides them); ``method``: ``"rigid"`` or ``"compliance"``."""

    u: Array
    joint_point: Array
    joint_force: Array
    joint_moment: Array
    residual: Array
    self_stress: int
    method: str
    kin: MechanismKinematics
    friction: dict
    iterations: int
    dissipation: Array
    #: (n, nq): the generalised force holding the idle freedoms, ``H mu`` (:func:`idle_holding`;
    #: zero without idle freedoms) [N or N m per tree coordinate]
    holding: Array | None = None
    #: with ``split``: the efforts' shares (:func:`effort_shares`), else None
    shares: "EffortShares | None" = None
    #: (n,) an under-actuated mechanism's :func:`unactuated_share` per sample (at most
    #: :data:`UNDERACTUATED_TOLERANCE`: larger is refused); None with as many actuators as freedoms or more
    unactuated: Array | None = None


def joint_reactions(model: MechanismModel, kin: MechanismKinematics, loads: dict | None = None,
                    rtol: float = 1e-10, friction: bool = True, tol: float = 1e-11,
                    max_iter: int = 100, solver: str = "auto", overconstrained: str = "compliance",
                    named: Mapping[str, object] | None = None, split: bool = False,
                    sample_offset: int = 0) -> JointReactions:
    """Actuator efforts (Eq. 3) and every joint reaction (module docstring), with the joints'
    friction (:mod:`pkmdyn.multibody.dynamics.friction`) when the description gives any and ``friction`` is true.

    An over-constrained mechanism's reactions are made unique by link compliance
    (:func:`pkmdyn.multibody.dynamics.compliance.reactions.compliant_reactions`, from the bodies' ``section`` and
    ``material``); raises :class:`~pkmdyn.errors.ParameterError` naming the bodies when that
    data is missing. Load-dependent friction couples the reactions and the efforts: solved by
    fixed-point iteration (friction from the last reactions, then efforts and reactions again)
    until the friction changes by at most ``tol`` times its scale; a
    :class:`~pkmdyn.errors.ParameterError` names the joint and sample where it diverges or does
    not settle within ``max_iter`` iterations (friction that locks the mechanism).

    ``solver="auto"`` takes the cut-wrench route (:class:`_CutRoute`) where the cut joints'
    reactions are determined by the tree's equations, else (over-constrained) the dense
    equations of every joint wrench; ``"dense"`` always the latter (the two agree, tested).
    ``overconstrained="minimum-norm"``: an over-constrained mechanism's reactions are the
    minimum-norm solution of the rigid equations (moments scaled by the length scale) instead
    of the compliance-unique ones: they balance every body but are one choice among the
    self-stress states (``method = "minimum-norm"``).

    Idle freedoms are held by their rules (:func:`idle_holding`); ``holding`` gives the
    generalised force that holds them. ``split``: also the efforts' shares of every body group
    and joint's friction (:func:`effort_shares`). ``sample_offset``: the first sample's number
    in the whole motion, for messages (a motion processed in chunks)."""
    if solver not in ("auto", "dense"):
        raise ParameterError(f"solver: {solver!r} is not 'auto' or 'dense'")
    if overconstrained not in ("compliance", "minimum-norm"):
        raise ParameterError(f"overconstrained: {overconstrained!r} is not 'compliance' or 'minimum-norm'")
    if overconstrained == "minimum-norm":
        solver = "dense"

    S = coordinate_twists(model, kin.q, kin)
    n = len(kin)
    scale = _column_scale(model)
    k = 6 * len(model.joint_names)
    fast = over = False
    cuts = None
    if solver != "dense":  # the rank is the topology's: checked on the first, middle and last samples
        probe = _CutRoute(model, kin, S, rtol, samples=np.unique([0, n // 2, n - 1]))
        fast = probe.full_rank
        over = not fast and model.topology is not None and model.topology.overconstraints > 0 and \
            probe.A.shape[2] > 0
        if over:  # compliance in the cut joints' unknowns (no dense SVD)
            cuts = _CutRoute(model, kin, S, rtol, tab=probe.tab)
    fr_on = friction and fr_any(model)
    blocks = free_blocks(model, kin, S) if not fast or fr_on else []
    A = None
    if over:
        r = -1
    elif not fast:
        A = equilibrium_matrix(model, blocks)
        U, sv, Vt = np.linalg.svd(A * scale[None, None, :], full_matrices=False)
        ranks = (sv > rtol * sv[:, :1]).sum(axis=1)
        r = int(ranks.min())
    else:
        r = k
    fr = JointFriction(model, kin, S, blocks, named) if fr_on else None
    F: dict | None = fr.initial() if fr is not None else None
    Qf = fr.generalised(F) if fr is not None else None
    history: list[float] = []
    it = 0
    W = body_wrenches(model, kin, loads, named)
    Q = generalised_forces(model, S, W)
    while True:
        F_u = F  # the friction these efforts and reactions hold with (the split's, below)
        Q_u = Q if Qf is None else Q + Qf  # the generalised force these efforts hold
        u = actuator_efforts(model, kin, Q_u, sample_offset=sample_offset, consistent=True)
        eff = np.zeros((n, model.nq))
        eff[:, model.act_coord] = u
        b = None if fast else equilibrium_rhs(model, blocks, W, eff, F)
        mu = None  # the idle freedoms' holding forces where the solve gives them
        if over:
            z0, Z = cuts.affine(model, W, F)
            z, t = compliant_reactions(model, kin, cuts.A, Q_u - eff, -1, W,
                                       affine=(z0, Z))
            method = "compliance"
        elif fast:
            z, mu, res = _cut_solve(model, probe.tab, kin, S, W, Q_u - eff, eff, F)
            method, t = "rigid", 0
        elif r < A.shape[2] and overconstrained == "minimum-norm":
            coef = np.einsum("nmr,nm->nr", U[:, :, :r], b) / sv[:, :r]
            z = np.einsum("nrk,nr->nk", Vt[:, :r], coef) * scale[None, :]
            z, mu = z[:, :k], z[:, k:]
            method, t = "minimum-norm", A.shape[2] - r
        elif r < A.shape[2]:
            z, t = compliant_reactions(model, kin, A, b, r, W)
            method = "compliance"
        else:
            coef = np.einsum("nmr,nm->nr", U, b) / sv
            z = np.einsum("nrk,nr->nk", Vt, coef) * scale[None, :]
            z, mu = z[:, :k], z[:, k:]
            method, t = "rigid", 0
        if fr is None:
            break
        F_new = fr.forces(z.reshape(n, -1, 6))
        change, worst_joint, worst_sample = fr.change(F, F_new)
        size = max(fr.scale(F_new), float(np.abs(u).max()), 1e-12)
        history.append(change / size)
        F = F_new
        Qf = fr.generalised(F)
        it += 1
        if history[-1] <= tol:
            break
        if it >= max_iter or friction_diverges(history):
            raise ParameterError(f"joint {model.joint_names[worst_joint]}: the load-dependent friction does not "
                                 f"converge at {at_sample(worst_sample, kin.t, sample_offset)} (relative change {history[-1]:.3g} after {it} iterations): "
                                 "the friction coefficients lock the mechanism")
    if fast:
        hold = mu @ probe.tab.H.T
    else:
        res, hold = _residual(model, blocks, z, b, mu)
    Wj = z.reshape(n, -1, 6)
    pts = kin.joint_point
    force = Wj[..., 3:]
    moment = Wj[..., :3] - _cross(pts, force)
    shares = effort_shares(model, kin, S, W, fr, F_u) if split else None
    if shares is not None:
        shares = EffortShares(shares.groups, shares.friction,
                              u - shares.groups.sum(axis=2) - shares.friction.sum(axis=2))
    unactuated = None
    if model.na < model.nt:
        unactuated = unactuated_share(np.swapaxes(kin.J_ax, 1, 2), u,
                                      (np.swapaxes(kin.G, 1, 2) @ Q_u[..., None])[..., 0])
    # the friction the efforts and reactions hold with (within the iteration's tolerance of the
    # law at these reactions), so that the efforts, dissipation and split agree to rounding
    return JointReactions(u=u, joint_point=pts, joint_force=force, joint_moment=moment, residual=res,
                          self_stress=t, method=method, kin=kin, friction=F_u or {}, iterations=it,
                          dissipation=fr.dissipation(F_u) if fr is not None else np.zeros(n), holding=hold,
                          shares=shares, unactuated=unactuated)


@dataclass(frozen=True)
class EffortShares:
    """The actuator efforts split by what they drive (efforts are linear in the bodies' required
    wrenches and in the joints' friction, Eq. 1-3, so every share is exact): ``groups`` (n, na,
    ng) the share of each body group (``model.group_names``: its bodies' inertia, gravity and
    loads), ``friction`` (n, na, nj) each joint's friction share (zero for a joint without
    friction); ``internal`` (n, na) a redundantly actuated mechanism's internal force (what its
    distribution's bounds, least peak or preload add to the (weighted) least-norm efforts: it
    moves nothing; round-off otherwise); ``sum(groups) + sum(friction) + internal = u`` to
    rounding. Joint-side units [N or N m]."""

    groups: Array
    friction: Array
    internal: Array | None = None


def effort_shares(model: MechanismModel, kin: MechanismKinematics, S: Array, W: Array, fr,
                  F: dict | None) -> EffortShares:
    """:class:`EffortShares` from the required body wrenches ``W (n, nb, 6)`` and the joints'
    friction ``F`` (``fr``: the :class:`~pkmdyn.multibody.dynamics.friction.JointFriction` that made it, or None):
    ``u_part = (J_ax^T)^-1 G^T Q_part`` for ``Q_part`` the generalised forces (Eq. 2) of one
    group's wrenches or of one joint's friction."""
    n, nq = S.shape[0], model.nq
    ng, nj = len(model.group_names), len(model.joint_names)
    rubbing = list(fr.joints) if fr is not None and F else []  # the joints with friction
    rhs = np.zeros((n, nq, ng + len(rubbing)))
    for g in range(ng):
        Wg = np.where((model.body_group == g)[None, :, None], W, 0.0)
        rhs[:, :, g] = generalised_forces(model, S, Wg)
    for i, jd in enumerate(rubbing):
        Qj = np.zeros((n, nq))
        fr.add_generalised(Qj, jd, F[jd["j"]])
        rhs[:, :, ng + i] = Qj
    task = np.swapaxes(kin.G, 1, 2) @ rhs  # G^T Q_part, a batched product (einsum's loop: 18 times slower)
    JT = np.swapaxes(kin.J_ax, 1, 2)
    if model.na == model.nt:
        parts = np.linalg.solve(JT, task)
    elif model.na > model.nt:  # the distribution's linear part; the rest is its internal force
        parts = least_norm_map(model, JT) @ task
    else:
        parts = np.linalg.pinv(JT) @ task
    friction = np.zeros((n, model.na, nj))
    friction[:, :, [jd["j"] for jd in rubbing]] = parts[:, :, ng:]
    return EffortShares(groups=parts[:, :, :ng], friction=friction)


def _residual(model: MechanismModel, blocks: list, z: Array, b: Array, mu: Array | None = None
              ) -> tuple[Array, Array]:
    """``max |A [z; mu] - b|`` per sample (n,) without forming ``A`` (:func:`equilibrium_matrix`)
    and the idle freedoms' holding force ``H mu (n, nq)`` (:func:`idle_holding`): ``mu (n, k)``
    as the solve gave it, or, where it gives none (the compliance route), the least-squares
    ``mu`` of the free-twist rows."""
    n, nb = z.shape[0], model.nb
    nj = len(model.joint_names)
    Wj = z.reshape(n, nj, 6)
    E = np.zeros((nb, nj))  # body b's equations: + the joints of which it is the child, - the parent
    for j in range(nj):
        if model.joint_child[j] >= 0:
            E[model.joint_child[j], j] += 1.0
        if model.joint_parent[j] >= 0:
            E[model.joint_parent[j], j] -= 1.0
    r = np.abs((E @ Wj).reshape(n, -1) - b[:, :6 * nb]).max(axis=1)
    hold = np.zeros((n, model.nq))
    if blocks:
        T = np.concatenate([T for _, T, _ in blocks], axis=1)
        rows = np.concatenate([np.full(T.shape[1], j) for j, T, _ in blocks])
        coords = np.concatenate([c for _, _, c in blocks])
        rt = (T * Wj[:, rows]).sum(axis=2) - b[:, 6 * nb:]
        H = idle_holding(model)
        if H.shape[1]:
            Hr = np.where((coords >= 0)[:, None], H[np.maximum(coords, 0)], 0.0)  # (nf, k)
            if mu is None:
                mu = rt @ np.linalg.pinv(Hr).T
            rt = rt - mu @ Hr.T
            hold = mu @ H.T
        r = np.maximum(r, np.abs(rt).max(axis=1))
    return r, hold


@dataclass(frozen=True)
class _CutTable:
    """The cut joints of a model as the compiled route takes them (:mod:`pkmdyn.multibody.dynamics._reaction_kernels`):
    ``cut_j`` each cut joint (those with freedoms, then the fixed ones), ``cut_f`` its freedoms,
    ``cut_pos`` its first multiplier (``6 - f`` each), ``cut_sign (nc, nq)`` +1 on the tree
    coordinates that move its child and not its parent, -1 on the reverse; ``joint_cut_index``
    (nj,) each joint's place in ``cut_j`` (-1 for a tree joint); ``type_motion`` (types, 3) the
    elementary motions of each joint type (:data:`pkmdyn.multibody.description.joint_types.MOTION_CODES`); ``H`` the idle
    freedoms' holding directions (:func:`idle_holding`), whose forces follow the multipliers."""

    cut_j: NDArray[np.int64]
    cut_f: NDArray[np.int64]
    cut_pos: NDArray[np.int64]
    cut_sign: Array
    joint_cut_index: NDArray[np.int64]
    type_motion: NDArray[np.int64]
    spherical: int
    H: Array

    @property
    def n_cut(self) -> int:
        return int(np.sum(6 - self.cut_f))

    @property
    def K(self) -> int:
        return self.n_cut + self.H.shape[1]


def cut_table(model: MechanismModel) -> _CutTable:
    """The :class:`_CutTable` of ``model``."""
    nj, nq = len(model.joint_names), model.nq
    free = [j for j in range(nj) if model.joint_cut[j] and JOINT_TYPES[model.joint_type[j]].freedoms]
    fixed = [j for j in range(nj) if model.joint_cut[j] and not JOINT_TYPES[model.joint_type[j]].freedoms]
    cut_j = np.array(free + fixed, dtype=np.int64)
    cut_f = np.array([JOINT_TYPES[model.joint_type[j]].freedoms for j in cut_j], dtype=np.int64)
    anc = model.ancestors.astype(float)
    sign = np.zeros((cut_j.size, nq))
    for i, j in enumerate(cut_j):
        c, p = model.joint_child[j], model.joint_parent[j]
        sign[i] = (anc[c] if c >= 0 else 0.0) - (anc[p] if p >= 0 else 0.0)
    where = np.full(nj, -1, dtype=np.int64)
    where[cut_j] = np.arange(cut_j.size)
    motion = np.zeros((len(JOINT_TYPES), 3), dtype=np.int64)
    for t, jt in enumerate(JOINT_TYPES):
        motion[t, :jt.freedoms] = [MOTION_CODES[mn] for mn in jt.motions]
    return _CutTable(cut_j=cut_j, cut_f=cut_f, cut_pos=np.concatenate([[0], np.cumsum(6 - cut_f)[:-1]]).astype(np.int64),
                     cut_sign=sign, joint_cut_index=where, type_motion=motion, spherical=type_code("spherical"),
                     H=idle_holding(model))


def _full_rank(A: Array, rtol: float) -> bool:
    """Whether the columns of every ``A (n, m, K)`` are independent (QR, relative ``100 rtol``)."""
    if A.shape[2] > A.shape[1]:
        return False
    if not A.shape[2]:
        return True
    _, R = np.linalg.qr(A)
    d = np.abs(np.diagonal(R, axis1=1, axis2=2))
    colmax = np.abs(A).max(axis=(1, 2))
    return bool(np.all(d > rtol * 1e2 * np.maximum(colmax[:, None], 1e-300)))


class _CutRoute:
    """Reactions through the cut joints' constraint wrenches (Featherstone's loop-closure form).

    Each cut joint j carries ``W_j = C_j lambda_j - D_j F_j``: ``C_j (6, 6 - f)`` spans the
    wrenches that do no work in its free twists (``T_j^T C_j = 0``), ``D_j = T_j (T_j^T T_j)^-1``
    puts its friction ``F_j`` along them. The tree's equations, one per tree coordinate,

        sum_j (J_c,j - J_p,j)^T C_j lambda_j + H mu = Q + Q_f - E_a u

    (``H mu`` the idle freedoms' holding forces, :func:`idle_holding`)
    (``J_c,j``, ``J_p,j`` the child's and parent's twist Jacobians, ``E_a u`` the actuator
    efforts on their coordinates) give the ``lambda`` by least squares (normal equations; the
    system is consistent where the efforts come from Eq. 3; its full column rank is checked by
    QR on three samples); every tree joint's wrench then follows leaves first,
    ``W_tree(b) = W_b + sum_children W_tree(child) - (cut wrenches on b)``
    (:func:`pkmdyn.multibody.dynamics._reaction_kernels.cut_reactions_batch`, :func:`_cut_solve`). When the columns are
    rank deficient (an over-constrained mechanism) ``full_rank`` is false and the dense
    equations or the compliance decide. This class holds the matrix ``A`` (n, nq, K) of the
    samples ``samples`` (default all) and assembles the wrenches in numpy for the compliance
    and stiffness routes; ``tab`` the model's :func:`cut_table`, where the caller has it."""

    def __init__(self, model: MechanismModel, kin: MechanismKinematics, S: Array, rtol: float,
                 samples: Array | None = None, tab: _CutTable | None = None) -> None:
        tab = cut_table(model) if tab is None else tab
        pick = (lambda a: np.ascontiguousarray(a)) if samples is None else (lambda a: np.ascontiguousarray(a[samples]))
        R, origin, Ss = pick(kin.R), pick(kin.origin), pick(S)
        n, nc = R.shape[0], tab.cut_j.size
        T, C = np.zeros((n, nc, 3, 6)), np.zeros((n, nc, 6, 6))
        self.tab = tab
        self.A = np.empty((n, model.nq, tab.K))
        _cut_kernel(model, tab, R, origin, Ss, setup=(T, C, self.A))
        self.cut = [(int(j), C[:, i, :, :6 - f], T[:, i, :f]) for i, (j, f) in enumerate(zip(tab.cut_j, tab.cut_f))]
        self.n_cut = tab.n_cut
        self._D: dict[int, Array] = {}
        self.full_rank = _full_rank(self.A[np.unique([0, n // 2, n - 1])] if n else self.A, rtol)

    def _friction_map(self, j: int, T: Array) -> Array:
        """``D_j = T_j (T_j^T T_j)^-1`` (n, 6, f) of cut joint j (class docstring), on first use."""
        if j not in self._D:
            Tc = np.swapaxes(T, 1, 2)
            self._D[j] = Tc @ np.linalg.inv(T @ Tc)
        return self._D[j]

    def assemble(self, model: MechanismModel, W: Array, lam: Array, F: dict | None) -> Array:
        """Every joint wrench ``z (n, 6 nj)`` from the cut joints' ``lam (n, K)``: the cut wrenches,
        then the tree joints' leaves first (linear in ``W``, ``lam`` and ``F`` together)."""
        n = W.shape[0]
        nj = len(model.joint_names)
        z = np.zeros((n, nj, 6))
        pos = 0
        onbody = np.zeros((n, model.nb, 6))  # sum of cut wrenches acting on each body
        for j, C, T in self.cut:
            m_ = C.shape[2]
            Wc = (C @ lam[:, pos:pos + m_, None])[..., 0]
            pos += m_
            if F is not None and j in F and T.shape[1]:
                Wc = Wc - (self._friction_map(j, T) @ F[j][..., None])[..., 0]
            z[:, j] = Wc
            if model.joint_child[j] >= 0:
                onbody[:, model.joint_child[j]] += Wc
            if model.joint_parent[j] >= 0:
                onbody[:, model.joint_parent[j]] -= Wc
        _leaves_first(model, W - onbody, z)
        return z.reshape(n, -1)

    def affine(self, model: MechanismModel, W: Array, F: dict | None) -> tuple[Array, Array]:
        """``z = z0 + Z lam``: ``z0 (n, 6 nj)`` (the loads and friction, ``lam = 0``) and
        ``Z (n, 6 nj, K)`` (one column per cut-wrench component)."""
        n, K = W.shape[0], self.A.shape[2]
        z0 = self.assemble(model, W, np.zeros((n, K)), F)
        # Z: assemble's cut part and tree sums for every unit lam at once (a trailing column axis)
        nj = len(model.joint_names)
        Z = np.zeros((n, nj, 6, K))
        onbody = np.zeros((n, model.nb, 6, K))
        pos = 0
        for j, C, _ in self.cut:
            m_ = C.shape[2]
            Z[:, j, :, pos:pos + m_] = C
            if model.joint_child[j] >= 0:
                onbody[:, model.joint_child[j], :, pos:pos + m_] += C
            if model.joint_parent[j] >= 0:
                onbody[:, model.joint_parent[j], :, pos:pos + m_] -= C
            pos += m_
        _leaves_first(model, -onbody, Z)
        return z0, Z.reshape(n, 6 * nj, K)


def _leaves_first(model: MechanismModel, Wt: Array, z: Array) -> None:
    """Every tree joint's wrench into ``z (n, nj, 6, ...)``: the wrench that body b requires
    beyond what its cut joints give, ``Wt (n, nb, 6, ...)`` (summed in place), accumulated
    from the leaves towards the ground (any trailing axes ride along)."""
    for b in range(model.nb - 1, -1, -1):
        par = model.body_parent[b]
        if par >= 0:
            Wt[:, par] += Wt[:, b]
        k = model.body_joint[b]
        z[:, k] = -Wt[:, b] if model.joint_flipped[k] else Wt[:, b]


def _cut_kernel(model: MechanismModel, tab: _CutTable, R: Array, origin: Array, S: Array, W: Array | None = None,
                rhs: Array | None = None, eff: Array | None = None, F: Array | None = None,
                given: Array | None = None, lam: Array | None = None, out: tuple | None = None,
                setup: tuple | None = None) -> None:
    """One call of :func:`pkmdyn.multibody.dynamics._reaction_kernels.cut_reactions_batch` (contiguous arrays): the
    solve into ``out = (z, res, ok)``, or with ``setup = (T, C, A)`` the cut joints' twists,
    wrench bases and the tree equations' matrix alone (the solve's arrays left out)."""
    n = R.shape[0]
    if setup is not None:
        e1, e2 = np.empty((n, 0)), np.empty((n, 0, 0))
        W, rhs, eff, F, lam, given = e2, e1, e1, np.empty((n, 0, 0)), e1, np.empty(n, dtype=np.bool_)
        out = (np.empty((n, 0, 0)), np.empty(n), np.empty(n, dtype=np.bool_))
        T, C, A = setup
    else:
        T, C, A = np.empty((0, 0, 0, 0)), np.empty((0, 0, 0, 0)), np.empty((0, 0, 0))
    cuts = (tab.cut_j, tab.cut_f, tab.cut_pos, tab.cut_sign, tab.joint_cut_index, tab.type_motion, tab.spherical,
            tab.H)
    joints = (model.joint_type, model.joint_child, model.joint_parent, model.joint_q0, model.joint_nq,
              model.joint_flipped, model.joint_R_child, model.joint_p_child, model.joint_R_parent, model.joint_p_parent,
              model.body_parent, model.body_joint)
    cut_reactions_batch((R, origin, S), (W, rhs, eff, F, given, lam), cuts, joints, tuple(out), setup is not None,
                        (T, C, A))


def _cut_solve(model: MechanismModel, tab: _CutTable, kin: MechanismKinematics, S: Array, W: Array, rhs: Array,
               eff: Array, F: dict | None) -> tuple[Array, Array, Array]:
    """Every joint wrench ``z (n, 6 nj)`` by the cut-wrench route (:class:`_CutRoute`, full
    column rank), the idle freedoms' holding forces ``mu (n, k)`` and the largest equilibrium
    residual (n,), in one compiled pass (:func:`pkmdyn.multibody.dynamics._reaction_kernels.cut_reactions_batch`):
    ``rhs = Q + Q_f - E_a u`` (n, nq), ``eff`` (n, nq) the efforts along the tree coordinates,
    ``F`` each joint's friction along its free twists. Where the columns are dependent at a
    sample (a constraint singularity) the multipliers are the minimum-norm least-squares ones,
    which balance every body but are one choice of many (``tab``: :func:`cut_table`)."""
    n, nj = W.shape[0], len(model.joint_names)
    Fa = np.zeros((n, nj, 3))
    for j, Fj in (F or {}).items():
        Fa[:, j, :Fj.shape[1]] = Fj
    R, origin = np.ascontiguousarray(kin.R), np.ascontiguousarray(kin.origin)
    S, W, rhs, eff = (np.ascontiguousarray(a) for a in (S, W, rhs, eff))
    lam = np.zeros((n, tab.K))

    def run(idx: Array | slice, given: Array, lam_: Array) -> tuple[Array, Array, Array]:
        z_, r_, ok_ = np.zeros((lam_.shape[0], nj, 6)), np.zeros(lam_.shape[0]), np.ones(lam_.shape[0], np.bool_)
        _cut_kernel(model, tab, R[idx], origin[idx], S[idx], W[idx], rhs[idx], eff[idx], Fa[idx], given, lam_,
                    (z_, r_, ok_))
        return z_, r_, ok_

    z, res, ok = run(slice(None), np.zeros(n, dtype=np.bool_), lam)
    bad = np.flatnonzero(~ok)
    if bad.size:
        A = _CutRoute(model, kin, S, 0.0, samples=bad, tab=tab).A
        lb = np.stack([np.linalg.lstsq(A[i], rhs[s], rcond=None)[0] for i, s in enumerate(bad)])
        z[bad], res[bad], _ = run(bad, np.ones(bad.size, dtype=np.bool_), lb)
        lam[bad] = lb
    return z.reshape(n, -1), lam[:, tab.n_cut:], res


def fr_any(model: MechanismModel) -> bool:
    """Whether any joint of the description has friction data."""
    return any(f is not None and any(v for v in f.values()) for f in model.joint_friction)


def _column_scale(model: MechanismModel) -> Array:
    """Column scaling of the joint-wrench unknowns (moments about O divided by the length
    scale), then of the idle freedoms' holding forces (1)."""
    s = np.ones((len(model.joint_names), 6))
    s[:, :3] = model.length_scale
    return np.concatenate([s.reshape(-1), np.ones(model.solver_idle.shape[0])])


def energies(model: MechanismModel, kin: MechanismKinematics) -> tuple[Array, Array]:
    """Kinetic energy ``T (n,)`` and potential energy ``V (n,)`` [J] of all bodies, from their
    poses and velocities alone: ``T = sum 1/2 m v.v + 1/2 w.(R I' R^T) w``, ``V = -sum m g . p``
    plus every joint spring's ``1/2 k (q - q_s)^2``."""
    Iw = np.einsum("nbij,bjk,nblk->nbil", kin.R, model.inertia, kin.R)
    T = 0.5 * np.einsum("b,nbi,nbi->n", model.mass, kin.v, kin.v) + 0.5 * np.einsum(
        "nbi,nbij,nbj->n", kin.w, Iw, kin.w)
    V = -np.einsum("b,i,nbi->n", model.mass, model.gravity, kin.p)
    for j, sp in enumerate(model.joint_spring):  # and the joint springs' 1/2 k (q - q_s)^2
        if sp is not None:
            V = V + 0.5 * sp[0] * (kin.q[:, int(model.joint_q0[j])] - sp[1]) ** 2
    return T, V


def effort_unit(model: MechanismModel, i: int) -> str:
    """Unit of actuator i's effort: ``N`` (prismatic) or ``Nm`` (revolute)."""
    return "N" if model.actuator_units[i] == "m" else "Nm"

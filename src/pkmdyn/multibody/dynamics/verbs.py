"""Any described mechanism as a machine: the verbs of :class:`pkmdyn.machine_protocol.MachineDynamics`
in its task coordinates.

Coordinates ``q (n, nt)`` are the task coordinates of the description (``x_m`` ...,
``euler1_rad`` ...), ``qd, qdd`` their rates; efforts ``u (n, na)`` the motor efforts of the
drives (``[[actuators]]``: torque [N m] of a rotary motor, force [N] of a linear one) and the
joint efforts of actuated joints without one (forces [N] or torques [N m]), order of
``model.actuator_names``. With ``G = dq_tree/dx`` and ``J_ax = dq_a/dx`` from the kinematics,
the body twists per task rate ``T_b = sum_{c in anc(b)} S_c G_c`` (6, nt) and the drives'
ratios ``k`` (``K = diag k``, 1 without a drive), rotor inertias ``I_r`` and motor friction
``tau_f`` (:mod:`pkmdyn.multibody.dynamics.actuators`, Eq. A1):

    M(x) = sum_b T_b^T I_b T_b + J_ax^T K I_r K J_ax      (kinetic energy of bodies and rotors)
    h(x, xd) = G^T (Q + Q_f) + J_ax^T K (I_r K qdd_a,bias + tau_f)   at xdd = 0 (Eq. 2-3 of .dynamics)
    B(x) = J_ax^T K                                       (virtual work of the motors)

so that ``M xdd + h = B u`` is the equation of motion projected on the task coordinates (the
idle freedoms held, as the kinematics hold them). The friction in ``h`` is Coulomb and
viscous; load-dependent friction is evaluated with the reactions of the state at ``xdd = 0``
(its exact coupled value along a motion is :func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`). The
description's constant ``[[loads]]`` are always applied; ``load`` gives the magnitudes [N] of
its named loads (``model.named_loads``): ``(n,)`` (or one value per call of a ``*_one`` verb)
for a mechanism with one named load, ``(n, k)`` (``(k,)``) for k; None takes the
description's ``magnitude_N``. A mechanism without named loads takes None (or zeros).

Redundantly actuated mechanisms (``na > nt``) share ``M xdd + h`` among their actuators by
their ``[actuation]`` distribution (:mod:`pkmdyn.multibody.dynamics.distribution`; by default
the minimum-norm ``u = B^+ (M xdd + h)``); their direct kinematics (:func:`direct_one`) reads
the square subset of their actuators (:func:`pkmdyn.multibody.kinematics.direct.square_subset`).

The verbs are free functions over ``(model, data)``: ``model`` the compiled mechanism (never
changed), ``data`` a :class:`MechanismData` made from it, which holds everything a call leaves
for the next (the last solved configuration each solve starts from, the compiled single-sample
path's buffers, the direct kinematics' and the encoders' warm starts), as Pinocchio's
``Model``/``Data`` and MuJoCo's ``mjModel``/``mjData`` split them::

    data = MechanismData(model)
    xdd = forward_dynamics_one(model, data, x, xd, u)

Two loops on one model keep two ``data``. :class:`MechanismVerbs` is the
:class:`pkmdyn.machine_protocol.MachineDynamics` face of the same functions (what
:mod:`pkmdyn.simulate` and :mod:`pkmdyn.control` call): one ``data`` per model it serves, the
controller's and the plant's apart.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError, SingularityError, as_array
from ..kinematics import _direct_kernels as D
from ..kinematics import _solve_kernels as K
from ..kinematics.direct import (
    direct_kinematics,
    one_state,
    pack_one,
    pack_task,
    prime_one,
    prime_task,
    square_subset,
    task_state,
)
from ..kinematics.inverse import MechanismKinematics, _assemble, _run, solve_kinematics
from ..model.compiler import MechanismModel
from ..model.legs import place
from . import _sample_kernels as _one
from .actuators import motor_effort_unit, motor_efforts
from .friction import known_friction
from .newton_euler import (
    actuator_efforts,
    body_wrenches,
    coordinate_twists,
    effort_unit,
    fr_any,
    generalised_forces,
    inertia_factors,
    joint_reactions,
    task_mass_matrix,
)

__all__ = ["MechanismData", "MechanismVerbs", "machine_verbs", "mass_matrix",
           "actuator_map", "actuator_accelerations", "bias_forces", "inverse_dynamics", "forward_dynamics",
           "one_sample_kernels", "inverse_dynamics_one", "forward_dynamics_one", "drive_ratios",
           "actuator_coordinates_one", "prime_direct", "encoder_buffers", "direct_task_buffers", "direct_one"]

Array = NDArray[np.float64]

#: poses from which :meth:`MechanismVerbs.actuator_map` takes the single-sample kernel's loop
MAP_SAMPLES = 16

#: the error of a single-sample direct kinematics call whose actuators crossed a singularity
_CROSSING = "the actuator coordinates crossed a singularity of the direct kinematics"


def _vector(a: object) -> Array:
    """``a`` as a contiguous float array: itself where it already is one (the common case of a
    loop's calls), without numpy's conversion call."""
    if type(a) is np.ndarray and a.dtype == np.float64 and a.flags.c_contiguous:
        return a
    return np.ascontiguousarray(a, dtype=float)


def _load_dependent(model: MechanismModel) -> bool:
    return any(f is not None and f.get("coefficient", 0.0) for f in model.joint_friction)


class MechanismData:
    """What the verbs keep of one model between calls (module docstring): its last solved tree
    coordinates (the next solve's start), the mass matrix's constant factors, the compiled
    single-sample path's buffer (:mod:`pkmdyn.multibody.dynamics._sample_kernels`; None where
    that path does not answer for the model), the batched actuator map's, the direct
    kinematics' and the encoders' buffers and warm starts."""

    def __init__(self, model: MechanismModel) -> None:
        self.one = _one  # the single-sample kernels, bound once (an import in a call costs a microsecond)
        self.q_last: Array | None = None
        self.inertia_factors = inertia_factors(model)
        self.pk = _one.pack(model) if _one.supported(model) else None
        # the kernel itself and its inverse and forward modes (:meth:`MechanismVerbs._kernel`)
        self.dynamics, self.modes = _one._dynamics, (_one.INVERSE, _one.FORWARD)
        # the named load's default magnitude (the single-sample verbs' load where the call gives
        # none), None without a named load
        self.default_load: float | None = (
            float(model.load_magnitude[list(model.load_name).index(model.named_loads[0])]) if model.named_loads
            else None)
        self.map_pk: Any = None  # the batched actuator map's own buffer (:meth:`MechanismVerbs._maps`)
        # the direct kinematics' warm start (:meth:`MechanismVerbs.direct_one`): its buffer, output
        # and kernel
        self.direct: Any = None
        # the task-space route's model, state, output and kernel (False where it does not answer)
        self.direct_task: Any = None
        self.encoder_q: Array | None = None  # the last reading's tree coordinates (``actuator_coordinates_one``)
        # the readings' own compiled path (a buffer of its own: its state is the last reading)
        self.encoder_pk = _one.pack(model) if self.pk is not None else None
        self.encoder_out = np.zeros(model.na)
        # that path's solution (a view) and its copy before each call (the start of the checked
        # route where the call cannot answer)
        self.encoder_view = _one.state(self.encoder_pk)[1:1 + model.nq] if self.encoder_pk is not None else None
        self.encoder_prev = np.zeros(model.nq)

    def last_q(self) -> Array | None:
        """The last solved tree coordinates: the compiled path's when it holds a solution (it
        advances without this object), else the general route's."""
        q = _one.solution(self.pk) if self.pk is not None else None
        return q if q is not None else self.q_last

    def remember(self, kin: MechanismKinematics) -> None:
        """The last solved sample: the next solve's start, and the compiled path's state."""
        self.q_last = kin.q[-1].copy()
        if self.pk is not None:
            _one.prime(self.pk, kin.q[-1], kin.x[-1], kin.G[-1])


def _x(model: MechanismModel, q: object, name: str = "q") -> Array:
    return np.atleast_2d(as_array(q, (None, model.nt) if np.ndim(q) == 2 else (model.nt,), name,
                                  MotionError))


def _kin(model: MechanismModel, data: MechanismData, x: Array, xd: Array | None = None) -> MechanismKinematics:
    kin = solve_kinematics(model, x, xd, None, q_start=data.last_q())
    data.remember(kin)
    return kin


def _named(model: MechanismModel, load: object, n: int) -> dict | None:
    """The named loads' magnitudes ``{name: (n,)}`` from the verbs' ``load`` (module docstring)."""
    names = model.named_loads
    if load is None:
        return None
    v = np.asarray(load, dtype=float)
    if not names:
        if np.any(v != 0.0):
            raise ParameterError(f"mechanism {model.name!r} has no named load ([[loads]] with a name); "
                                 "load must be None")
        return None
    k = len(names)
    if v.ndim == 0 and k == 1:
        v = np.full((n, 1), float(v))
    elif v.ndim == 1 and k == 1 and v.shape[0] == n:
        v = v[:, None]
    elif v.ndim == 1 and v.shape[0] == k and n == 1:
        v = v[None]
    if v.shape != (n, k):
        raise ParameterError(f"load: expected the magnitudes of {', '.join(names)} for {n} samples "
                             f"({'(n,)' if k == 1 else '(n, %d)' % k}), got shape {np.shape(load)}")
    return {nm: v[:, i] for i, nm in enumerate(names)}


def _state_one(model: MechanismModel, data: MechanismData, x: Array, xd: Array) -> MechanismKinematics:
    """One sample's kinematics straight from the compiled solver, warm-started (the checked,
    bridging route when that solve does not converge or nothing is known yet)."""

    q_last = data.last_q()
    if q_last is None:
        return _kin(model, data, x[None], xd[None])
    x1 = np.ascontiguousarray(x, dtype=float).reshape(1, -1)
    xd1 = np.ascontiguousarray(xd, dtype=float).reshape(1, -1)
    zero = np.zeros_like(x1)
    out = _run(model, x1, xd1, zero, q_last)
    if out["status"][0] != K.OK or not (np.all(np.isfinite(x1)) and np.all(np.isfinite(xd1))):
        return _kin(model, data, x1, xd1)
    kin = _assemble(model, None, x1, xd1, zero, out)
    data.remember(kin)
    return kin


def _mass(model: MechanismModel, data: MechanismData, kin: MechanismKinematics, S: Array) -> Array:
    return task_mass_matrix(model, kin, S, data.inertia_factors)


def _bias(model: MechanismModel, kin: MechanismKinematics, S: Array, named: dict | None = None) -> Array:
    if _load_dependent(model):
        u = joint_reactions(model, kin, named=named).u
        h = np.einsum("nat,na->nt", kin.J_ax, u)
    else:
        W = body_wrenches(model, kin, named=named)
        Q = generalised_forces(model, S, W)
        if fr_any(model):
            Q = Q + known_friction(model, kin, S, named)
        h = np.einsum("nct,nc->nt", kin.G, Q)
    if model.has_drives:  # the motors' bias (rotor at the bias acceleration, friction), Eq. A1
        mot = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, np.zeros_like(kin.act_q))
        h = h + np.einsum("nat,na->nt", kin.J_ax, model.drive_ratio * (mot.rotor + mot.friction))
    return h


def mass_matrix(model: MechanismModel, data: MechanismData, q: Array) -> Array:
    """``M(x) (n, nt, nt)``."""
    x = _x(model, q)
    kin = _kin(model, data, x)
    return _mass(model, data, kin, coordinate_twists(model, kin.q, kin))


def actuator_map(model: MechanismModel, data: MechanismData, q: Array) -> Array:
    """``B(x) = J_ax^T k (n, nt, na)`` (``k`` the drives' transmission ratios, 1 without a drive).
    Along a motion of :data:`MAP_SAMPLES` poses or more, the single-sample kernel in one
    compiled loop (:func:`pkmdyn.multibody.dynamics._sample_kernels.actuator_maps`: the same solver and tolerances, each pose
    from the last), the first pose by the checked route."""
    x = _x(model, q)
    J = _maps(model, data, x) if x.shape[0] >= MAP_SAMPLES else None
    if J is None:
        J = _kin(model, data, x).J_ax
    return np.swapaxes(J, 1, 2) * model.drive_ratio


def _maps(model: MechanismModel, data: MechanismData, x: Array) -> Array | None:
    """``J_ax (n, na, nt)`` along the poses ``x`` by :func:`pkmdyn.multibody.dynamics._sample_kernels.actuator_maps` where the
    kernel answers for ``model`` (else None): the first pose by the checked route (from the
    last solved sample, as :func:`_kin` starts), every later one by the kernel from the one
    before, the rest by the checked route from the first it does not solve; the last
    solved sample remembered, as :func:`_kin` does."""
    if data.pk is None or not np.all(np.isfinite(x)):
        return None
    _one = data.one
    first = _kin(model, data, x[:1])
    if data.map_pk is None:
        data.map_pk = _one.pack(model)
    n, nt, na = x.shape[0], model.nt, model.na
    out = np.empty((n, na * nt))
    out[0] = first.J_ax[0].ravel()
    _one.prime(data.map_pk, first.q[0], first.x[0], first.G[0])
    # the poses' steps as their rates (per sample): the predictor's second order along the motion
    xd = np.empty_like(x)
    xd[0] = 0.0
    d = np.diff(x, axis=0)
    ang = model.task_kind == 1
    d[:, ang] = (d[:, ang] + np.pi) % (2 * np.pi) - np.pi
    xd[1:] = d
    done = 1 + _one.actuator_maps(data.map_pk, x[1:], xd[1:], out[1:])
    if done < n:  # the checked route names what is wrong, or solves the rest
        q_prev = _one.solution(data.map_pk)
        rest = solve_kinematics(model, x[done:], q_start=q_prev if q_prev is not None else first.q[0],
                                sample_offset=done)
        out[done:] = rest.J_ax.reshape(n - done, na * nt)
        data.remember(rest)
    else:
        sol = _one.state(data.map_pk)
        nq = model.nq
        q_end = sol[1:1 + nq].copy()
        data.q_last = q_end
        _one.prime(data.pk, q_end, x[-1], sol[1 + nq + nt:1 + nq + nt + nq * nt].reshape(nq, nt))
    return out.reshape(n, na, nt)


def actuator_accelerations(model: MechanismModel, data: MechanismData, q: Array, qd: Array, qdd: Array) -> Array:
    """The drives' accelerations ``k qdd_a (n, na)`` (motor side, ``k`` as in :func:`actuator_map`)
    along task poses ``q``, rates ``qd`` and accelerations ``qdd``, from the kinematics'
    second-order solution: exact, where a difference of :func:`actuator_map` in time would
    carry the solver's round-off divided by the step."""
    kin = solve_kinematics(model, _x(model, q), _x(model, qd, "qd"), _x(model, qdd, "qdd"), q_start=data.last_q())
    data.remember(kin)
    return kin.act_qdd * model.drive_ratio


def bias_forces(model: MechanismModel, data: MechanismData, q: Array, qd: Array, load: Array | None = None) -> Array:
    """``h(x, xd) (n, nt)``."""
    x = _x(model, q)
    kin = _kin(model, data, x, _x(model, qd, "qd"))
    return _bias(model, kin, coordinate_twists(model, kin.q, kin), _named(model, load, len(kin)))


def _all(model: MechanismModel, data: MechanismData, q: Array, qd: Array, load: object, one: bool = False
         ) -> tuple[Array, Array, Array, MechanismKinematics]:
    if one:
        kin = _state_one(model, data, np.asarray(q, dtype=float), np.asarray(qd, dtype=float))
    else:
        kin = _kin(model, data, _x(model, q), _x(model, qd, "qd"))
    named = _named(model, load, len(kin))
    S = coordinate_twists(model, kin.q, kin)
    B = np.swapaxes(kin.J_ax, 1, 2) * model.drive_ratio
    return _mass(model, data, kin, S), _bias(model, kin, S, named), B, kin


def inverse_dynamics(model: MechanismModel, data: MechanismData, q: Array, qd: Array, qdd: Array,
                     load: Array | None = None) -> Array:
    """Efforts ``u (n, na)`` with ``B u = M xdd + h`` (more actuators than task coordinates:
    the minimum-norm joint efforts, each divided by its drive's ratio)."""
    M, h, B, kin = _all(model, data, q, qd, load)
    rhs = np.einsum("nij,nj->ni", M, _x(model, qdd, "qdd")) + h
    # actuator_efforts checks the actuator map's rank and names the sample; J_ax^T (k tau) = rhs
    return actuator_efforts(model, kin, np.zeros((len(kin), 0)), rhs_task=rhs) / model.drive_ratio


def forward_dynamics(model: MechanismModel, data: MechanismData, q: Array, qd: Array, u: Array,
                     load: Array | None = None) -> Array:
    """Accelerations ``xdd (n, nt)`` with ``M xdd = B u - h``."""
    M, h, B, _ = _all(model, data, q, qd, load)
    uu = np.atleast_2d(as_array(u, (None, model.na) if np.ndim(u) == 2 else (model.na,), "u", MotionError))
    return np.linalg.solve(M, (np.einsum("nta,na->nt", B, uu) - h)[..., None])[..., 0]


def one_sample_kernels(model: MechanismModel, data: MechanismData) -> tuple[NDArray[np.int64], object, object] | None:
    """``(p, inverse, forward)``: the compiled single-sample kernels (:mod:`pkmdyn.multibody.dynamics._sample_kernels`) for
    callers in a loop (``pkmdyn.machine_protocol``; ``load`` the named load's magnitude), or None
    where they do not answer for this mechanism (friction that depends on the reactions,
    several named loads, redundant actuation, a named load with a nonzero default
    magnitude): the ``*_one`` verbs then take the general route."""
    pk = data.pk
    if pk is None or np.any(model.load_magnitude != 0.0):
        return None  # (a caller without a load passes 0.0: right only for a zero default magnitude)
    return pk, _one.inverse_one, _one.forward_one


def _kernel(model: MechanismModel, data: MechanismData, forward: bool, q: object, qd: object, v: object,
            load: object) -> Array | None:
    """The compiled path's answer, or None (then the general route answers and primes it)."""
    pk = data.pk
    if pk is None:
        return None
    if data.default_load is not None:
        if type(load) is float and math.isfinite(load):  # a loop's own value: no array to make
            magnitude = load
        else:
            lv = np.asarray(data.default_load if load is None else load, dtype=float)
            if lv.size != 1 or not np.isfinite(lv).all():
                return None  # the general route names what is wrong
            magnitude = float(lv.reshape(()))
    elif load is not None and np.any(np.asarray(load) != 0.0):
        return None
    else:
        magnitude = 0.0
    x, xd, vv = _vector(q), _vector(qd), _vector(v)
    nt = model.nt
    if x.shape != (nt,) or xd.shape != (nt,) or vv.shape != (nt,):
        return None  # the general route names what is wrong (the kernel refuses non-finite input)
    out = np.empty(nt)
    status = data.dynamics(pk, x, xd, vv, magnitude, data.modes[forward], out)
    return out if status == 0 else None


def inverse_dynamics_one(model: MechanismModel, data: MechanismData, q: Array, qd: Array, qdd: Array,
                         load: float | None = None) -> Array:
    """One sample of :func:`inverse_dynamics` (the single-sample path: one compiled call
    where :mod:`pkmdyn.multibody.dynamics._sample_kernels` answers, else the compiled solver warm-started from the previous
    call, no batch checks)."""
    u = _kernel(model, data, False, q, qd, qdd, load)
    if u is not None:
        return u
    M, h, B, kin = _all(model, data, q, qd, load, one=True)
    rhs = M[0] @ np.asarray(qdd, dtype=float) + h[0]
    return actuator_efforts(model, kin, np.zeros((1, 0)), rhs_task=rhs[None])[0] / model.drive_ratio


def forward_dynamics_one(model: MechanismModel, data: MechanismData, q: Array, qd: Array, u: Array,
                         load: float | None = None) -> Array:
    """One sample of :func:`forward_dynamics` (the single-sample path)."""
    a = _kernel(model, data, True, q, qd, u, load)
    if a is not None:
        return a
    M, h, B, _ = _all(model, data, q, qd, load, one=True)
    return np.linalg.solve(M[0], B[0] @ np.asarray(u, dtype=float) - h[0])


def drive_ratios(model: MechanismModel, data: MechanismData) -> Array:
    """``(na,)`` the drives' transmission ratios (1 for an actuated joint without a drive):
    motor displacement per actuated joint displacement."""
    return np.asarray(model.drive_ratio, dtype=float).copy()


def actuator_coordinates_one(model: MechanismModel, data: MechanismData, q: Array, qd: Array, fresh: bool = False) -> Array:
    """The actuated joints' coordinates ``(na,)`` at task pose ``q`` (one sample of the
    inverse kinematics, warm-started from the last solved sample: the plant's encoders; with
    ``fresh``, reached from the reference configuration instead, the assembly of a run's
    first pose). ``qd``, the pose's rate, makes the start closer. One compiled call
    (:func:`pkmdyn.multibody.dynamics._sample_kernels.positions_one`) where it answers, else the checked route."""
    nt = model.nt
    _one = data.one
    if not fresh and data.encoder_q is not None and data.encoder_pk is not None:
        xa, xda = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float)
        if xa.shape == (nt,) and xda.shape == (nt,):
            np.copyto(data.encoder_prev, data.encoder_view)
            if _one.positions_one(data.encoder_pk, xa, xda, data.encoder_out) == _one.OK:
                return data.encoder_out.copy()
            data.encoder_q = data.encoder_prev.copy()  # the last reading's solution

    x1 = np.ascontiguousarray(_x(model, q))
    q_sol = G_sol = None
    if not fresh and data.encoder_q is not None and np.all(np.isfinite(x1)):
        # from the previous reading (near: one control cycle ago), not from whatever the
        # other verbs solved last, which may lie on another branch of a leg
        out = _run(model, x1, np.zeros_like(x1), np.zeros_like(x1), data.encoder_q)
        if out["status"][0] == K.OK:
            q_sol, G_sol = out["q"][0].copy(), out["G"][0].copy()
    if q_sol is None:
        kin = solve_kinematics(model, x1, q_start=None if fresh or data.encoder_q is None else data.encoder_q)
        q_sol, G_sol = kin.q[0].copy(), kin.G[0].copy()
    data.encoder_q = q_sol
    if data.encoder_pk is not None:
        _one.prime(data.encoder_pk, q_sol, x1[0], G_sol)
    return q_sol[model.act_coord].copy()


def prime_direct(model: MechanismModel, data: MechanismData, q: Array) -> None:
    """Let the next :func:`direct_one` call start from the task pose ``q`` whose actuated
    coordinates the last ``actuator_coordinates_one(model, q, qd, fresh=True)`` solved (its
    tree coordinates, kept as the encoders' solution): a controller that knows the pose its
    run starts from, instead of solving the direct kinematics from the reference
    configuration by the checked route (whose batched kernels a fresh install would compile
    for some seconds). The branch is that of ``q``; the sign of its determinant is taken
    from that next call. Nothing where no such solution is kept."""

    x = np.asarray(q, dtype=float).reshape(-1)
    if data.encoder_q is None or x.shape != (model.nt,) or not np.all(np.isfinite(x)):
        return
    if model.na > model.nt:  # redundant actuation: the square subset's direct kinematics
        model = square_subset(model)[0]
    qt = data.encoder_q.copy()
    a = qt[model.act_coord].copy()
    if data.direct is None:
        _pack_direct(model, data)
    prime_one(data.direct[0], qt, x, a, 0.0)
    if data.direct_task:
        prime_task(data.direct_task[1], qt, x, a)
        task_state(data.direct_task[1])[1] = 0.0


def encoder_buffers(model: MechanismModel, data: MechanismData) -> tuple[NDArray[np.int64], Array, Array, Array] | None:
    """``(pk, view, prev, out)``: what :func:`actuator_coordinates_one` hands its compiled call
    once a reading has been solved (``pk`` the packed buffer, ``view`` its solution, ``prev``
    where the call keeps the previous one, ``out (na,)`` the answer), for a caller that makes
    the same call in its own compiled loop (:mod:`pkmdyn.simulate`); None before."""
    if data.encoder_q is None or data.encoder_pk is None:
        return None
    return data.encoder_pk, data.encoder_view, data.encoder_prev, data.encoder_out


def direct_task_buffers(model: MechanismModel, data: MechanismData) -> tuple[NDArray[np.int64], NDArray[np.int64], Array,
                                                                int] | None:
    """``(pk, d, out, ok)``: what :func:`direct_one` hands :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one`
    once primed, where the mechanism takes the task-space route (``out (2 nt,)`` the pose
    and its rate, ``ok`` the status of an answer); None otherwise."""
    if not data.direct_task:
        return None
    pk1, d, out, _, ok, _ = data.direct_task
    return pk1, d, out, int(ok)


def direct_one(model: MechanismModel, data: MechanismData, a: Array, ad: Array) -> tuple[Array, Array]:
    """The task pose and rate ``(nt,), (nt,)`` at actuated joint coordinates ``a`` and rates
    ``ad`` by the direct kinematics (:mod:`pkmdyn.multibody.kinematics.direct`), warm-started from the previous call
    (the first from the reference configuration): the controller's pose from its encoders.
    One compiled call: in task space where every actuator belongs to a leg placed from the
    task alone (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one`: the Gough-Stewart platform, a 3PUS+S platform), else
    on the tree coordinates with a packed buffer (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_one`); where it
    cannot answer, the checked route. Raises where the actuators reach no pose or sit on a
    singularity."""
    a = np.ascontiguousarray(a, dtype=float)
    ad = np.ascontiguousarray(ad, dtype=float)
    if a.ndim != 1 or ad.ndim != 1:
        a, ad = a.reshape(-1), ad.reshape(-1)
    if model.na > model.nt and a.shape == ad.shape == (model.na,):
        # redundant actuation: the readings of the square subset's actuated joints (those best
        # conditioned at the reference; the plant's readings agree with them)
        model, keep = square_subset(model)
        a, ad = np.ascontiguousarray(a[keep]), np.ascontiguousarray(ad[keep])
    nt = model.nt
    fit = a.shape == ad.shape == (model.na,)
    status = -1
    if data.direct_task:  # (the kernels have run or been waited for: nothing to wait for)
        pk1, d, out, kernel, ok, _ = data.direct_task
        status = kernel(pk1, d, a, ad, out) if fit else ok - 1
        if status == ok:
            return out[:nt].copy(), out[nt:].copy()
    elif data.direct is not None:
        pk, out, kernel, ok = data.direct
        status = kernel(pk, a, ad, out) if fit else ok - 1
        if status == ok:
            return out[:nt].copy(), out[nt:].copy()
    if data.direct is None:  # the first call packs both routes
        return _direct_checked(model, data, a, ad, status)
    if data.direct_task:
        return _direct_task_on(model, data, a, ad, fit, status)
    return _direct_checked(model, data, a, ad, status)


def _pack_direct(model: MechanismModel, data: MechanismData) -> None:
    """Pack both single-sample routes of :func:`direct_one` into ``data`` (the task-space one
    where the mechanism takes it, else ``False``), neither primed."""

    data.direct = (pack_one(model), np.zeros(2 * model.nt), D.direct_one, D.OK)
    d = pack_task(model)
    data.direct_task = False
    if d is not None:  # (the task route only reads the model's arrays from a single-sample buffer)
        pk1 = data.pk if data.pk is not None else _one.pack(model)
        data.direct_task = (pk1, d, np.zeros(2 * model.nt), D.direct_task_one, D.OK, D.CROSSED)


def _direct_task_on(model: MechanismModel, data: MechanismData, a: Array, ad: Array, fit: bool,
                    status: int) -> tuple[Array, Array]:
    """:func:`direct_one` where the task-space call did not answer: a move too large for one
    call (or one it cannot solve) along the straight actuator path in 8, then 64 steps, else
    the checked route from the last solution; the branch checked by the sign of ``det A``
    against the last solution's. Raises on a crossing."""

    pk1, d, out, kernel, ok, crossed = data.direct_task
    nt = model.nt
    if fit and status == crossed:
        raise SingularityError(_CROSSING)
    f = d.view(np.float64)
    q_last, x_last = f[d[7]:d[7] + model.nq].copy(), f[d[1]:d[1] + nt].copy()
    s_last, det_last = f[d[2]:d[2] + model.na].copy(), float(task_state(d)[1])
    for steps in (8, 64) if fit and np.all(np.isfinite(a)) and np.all(np.isfinite(ad)) else ():
        prime_task(d, q_last, x_last, s_last)
        way = a - s_last
        for k in range(1, steps + 1):
            status = kernel(pk1, d, s_last + (k / steps) * way, ad if k == steps else way, out)
            if k == 1 and status == ok and det_last * float(task_state(d)[1]) < 0:
                status = crossed
            if status != ok:
                break
        if status == crossed:
            raise SingularityError(_CROSSING)
        if status == ok:
            return out[:nt].copy(), out[nt:].copy()
    # the legs' other coordinates at the last pose (the route by the actuated coordinates alone
    # places them every few calls only), for the checked route to start from
    q_last = place(model, q_last, x_last)
    dk = direct_kinematics(model, a[None], ad[None], q_start=q_last)
    prime_task(d, dk.q[0], dk.x[0], a)
    if kernel(pk1, d, a, ad, out) != ok:  # at its own solution: the task route's det A and rates
        raise SingularityError("the direct kinematics is singular at these actuator coordinates")
    if det_last * float(task_state(d)[1]) < 0:
        raise SingularityError(_CROSSING)
    return out[:nt].copy(), out[nt:].copy()


def _direct_checked(model: MechanismModel, data: MechanismData, a: Array, ad: Array,
                    status: int) -> tuple[Array, Array]:
    """:func:`direct_one` by the checked route: where the tree-space call did not answer
    (from its last solution; raises on a crossing), or on the first call (from the reference
    configuration), which packs both single-sample routes and primes them."""

    if data.direct is not None:
        if status == D.CROSSED:
            raise SingularityError(_CROSSING)
        prev = one_state(data.direct[0])
        q_prev, det_prev = prev[2:2 + model.nq].copy(), float(prev[1])
        dk = direct_kinematics(model, a[None], ad[None], q_start=q_prev)
        if dk.det[0] * det_prev < 0:  # the checked route names what is wrong otherwise
            raise SingularityError(_CROSSING)
    else:
        dk = direct_kinematics(model, a[None], ad[None])
        _pack_direct(model, data)
    prime_one(data.direct[0], dk.q[0], dk.x[0], a, float(dk.det[0]))
    if data.direct_task:
        prime_task(data.direct_task[1], dk.q[0], dk.x[0], a)
    return dk.x[0].copy(), dk.xd[0].copy()


class MechanismVerbs:
    """The machine verbs of one described mechanism (module docstring) as methods, for
    :class:`pkmdyn.machine_protocol.MachineDynamics`: each method is the free function of the same
    name with the :class:`MechanismData` of its model (made on the model's first call), so that
    solves are warm-started from the previous call's last configuration, as a control loop calls
    them."""

    def __init__(self, model: MechanismModel) -> None:
        self.model = model
        self.COORDINATES = tuple(f"{n}_{u}" for n, u in zip(model.task_names, model.task_units))
        # a drive's efforts are its motor's ([[actuators]]): <actuator>_Nm; a joint's own, <joint>_N or _Nm
        self.ACTUATORS = tuple(f"{model.drive_name[i]}_{motor_effort_unit(model, i)}" if model.drive_name[i] is not None
                               else f"{a}_{effort_unit(model, i)}" for i, a in enumerate(model.actuator_names))
        #: per model these verbs have served (the controller's and the plant's may differ): its
        #: warm-start state (:class:`MechanismData`), by ``id``, with the model held so the id stays its own
        self._states: dict[int, tuple[MechanismModel, MechanismData]] = {}
        self._state(model)

    def _state(self, model: MechanismModel) -> MechanismData:
        """The state of ``model``: made on its first call, for a model with the first one's task
        coordinates and actuators (the same machine with other numbers: a plant beside its
        controller's model)."""
        held = self._states.get(id(model))
        if held is not None and held[0] is model:
            return held[1]
        if not isinstance(model, MechanismModel):
            raise ParameterError(f"model: expected a MechanismModel, got {type(model).__name__}")
        first = self.model
        if (model.task_names, model.task_units, model.actuator_names, model.drive_name) != \
                (first.task_names, first.task_units, first.actuator_names, first.drive_name):
            raise ParameterError(f"these verbs belong to mechanism {first.name!r}: model {model.name!r} has other "
                                 "task coordinates or actuators")
        st = MechanismData(model)
        self._states[id(model)] = (model, st)
        return st

    def data(self, model: MechanismModel) -> MechanismData:
        """The :class:`MechanismData` these verbs keep for ``model`` (made on its first call)."""
        return self._state(model)

    def mass_matrix(self, model: MechanismModel, q: Array) -> Array:
        """:func:`mass_matrix` with this mechanism's data (the warm start of the model's last call)."""
        return mass_matrix(model, self._state(model), q)

    def actuator_map(self, model: MechanismModel, q: Array) -> Array:
        """:func:`actuator_map` with this mechanism's data (the warm start of the model's last call)."""
        return actuator_map(model, self._state(model), q)

    def actuator_accelerations(self, model: MechanismModel, q: Array, qd: Array, qdd: Array) -> Array:
        """:func:`actuator_accelerations` with this mechanism's data (the warm start of the model's last call)."""
        return actuator_accelerations(model, self._state(model), q, qd, qdd)

    def bias_forces(self, model: MechanismModel, q: Array, qd: Array, load: Array | None = None) -> Array:
        """:func:`bias_forces` with this mechanism's data (the warm start of the model's last call)."""
        return bias_forces(model, self._state(model), q, qd, load)

    def inverse_dynamics(self, model: MechanismModel, q: Array, qd: Array, qdd: Array,
                         load: Array | None = None) -> Array:
        """:func:`inverse_dynamics` with this mechanism's data (the warm start of the model's last call)."""
        return inverse_dynamics(model, self._state(model), q, qd, qdd, load)

    def forward_dynamics(self, model: MechanismModel, q: Array, qd: Array, u: Array,
                         load: Array | None = None) -> Array:
        """:func:`forward_dynamics` with this mechanism's data (the warm start of the model's last call)."""
        return forward_dynamics(model, self._state(model), q, qd, u, load)

    def one_sample_kernels(self, model: MechanismModel) -> tuple[NDArray[np.int64], object, object] | None:
        """:func:`one_sample_kernels` with this mechanism's data (the warm start of the model's last call)."""
        return one_sample_kernels(model, self._state(model))

    def inverse_dynamics_one(self, model: MechanismModel, q: Array, qd: Array, qdd: Array,
                             load: float | None = None) -> Array:
        """:func:`inverse_dynamics_one` with this mechanism's data (the warm start of the model's last call)."""
        return inverse_dynamics_one(model, self._state(model), q, qd, qdd, load)

    def forward_dynamics_one(self, model: MechanismModel, q: Array, qd: Array, u: Array,
                             load: float | None = None) -> Array:
        """:func:`forward_dynamics_one` with this mechanism's data (the warm start of the model's last call)."""
        return forward_dynamics_one(model, self._state(model), q, qd, u, load)

    def drive_ratios(self, model: MechanismModel) -> Array:
        """:func:`drive_ratios` with this mechanism's data (the warm start of the model's last call)."""
        return drive_ratios(model, self._state(model))

    def actuator_coordinates_one(self, model: MechanismModel, q: Array, qd: Array, fresh: bool = False) -> Array:
        """:func:`actuator_coordinates_one` with this mechanism's data (the warm start of the model's last call)."""
        return actuator_coordinates_one(model, self._state(model), q, qd, fresh)

    def prime_direct(self, model: MechanismModel, q: Array) -> None:
        """:func:`prime_direct` with this mechanism's data (the warm start of the model's last call)."""
        return prime_direct(model, self._state(model), q)

    def encoder_buffers(self, model: MechanismModel) -> tuple[NDArray[np.int64], Array, Array, Array] | None:
        """:func:`encoder_buffers` with this mechanism's data (the warm start of the model's last call)."""
        return encoder_buffers(model, self._state(model))

    def direct_task_buffers(self, model: MechanismModel) -> tuple[NDArray[np.int64], NDArray[np.int64], Array,
                                                                    int] | None:
        """:func:`direct_task_buffers` with this mechanism's data (the warm start of the model's last call)."""
        return direct_task_buffers(model, self._state(model))

    def direct_one(self, model: MechanismModel, a: Array, ad: Array) -> tuple[Array, Array]:
        """:func:`direct_one` with this mechanism's data (the warm start of the model's last call)."""
        return direct_one(model, self._state(model), a, ad)


def machine_verbs(model: MechanismModel) -> MechanismVerbs:
    """The :class:`pkmdyn.machine_protocol.MachineDynamics` verbs of a described mechanism."""
    return MechanismVerbs(model)

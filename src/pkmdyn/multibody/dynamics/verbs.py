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

Redundantly actuated mechanisms (``na > nt``, where the description allows it) take the
minimum-norm efforts ``u = B^+ (M xdd + h)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import MotionError, ParameterError, SingularityError, as_array
from ..kinematics import _direct_kernels as D
from ..kinematics import _solve_kernels as K
from ..kinematics.direct import direct_kinematics, one_state, pack_one, pack_task, prime_one, prime_task, task_state
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

__all__ = ["MechanismVerbs", "machine_verbs", "GeneratedModel", "RenamedVerbs"]

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


class _State:
    """What the verbs keep of one model between calls: its last solved tree coordinates (the
    next solve's start), the mass matrix's constant factors and the compiled single-sample
    path's buffer (:mod:`pkmdyn.multibody.dynamics._sample_kernels`; None where that path does not answer for the model)."""

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


class MechanismVerbs:
    """The machine verbs of one described mechanism (module docstring). Solves are warm-started
    from the previous call's last configuration, as a control loop calls them."""

    def __init__(self, model: MechanismModel) -> None:
        self.model = model
        self.COORDINATES = tuple(f"{n}_{u}" for n, u in zip(model.task_names, model.task_units))
        # a drive's efforts are its motor's ([[actuators]]): <actuator>_Nm; a joint's own, <joint>_N or _Nm
        self.ACTUATORS = tuple(f"{model.drive_name[i]}_{motor_effort_unit(model, i)}" if model.drive_name[i] is not None
                               else f"{a}_{effort_unit(model, i)}" for i, a in enumerate(model.actuator_names))
        #: per model these verbs have served (the controller's and the plant's may differ): its
        #: warm-start state (:class:`_State`), by ``id``, with the model held so the id stays its own
        self._states: dict[int, tuple[MechanismModel, _State]] = {}
        self._state(model)

    def _state(self, model: MechanismModel) -> _State:
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
        st = _State(model)
        self._states[id(model)] = (model, st)
        return st

    # ------------------------------------------------------------------ helpers
    def _x(self, q: object, name: str = "q") -> Array:
        return np.atleast_2d(as_array(q, (None, self.model.nt) if np.ndim(q) == 2 else (self.model.nt,), name,
                                      MotionError))

    def _kin(self, model: MechanismModel, x: Array, xd: Array | None = None) -> MechanismKinematics:
        st = self._state(model)
        kin = solve_kinematics(model, x, xd, None, q_start=st.last_q())
        st.remember(kin)
        return kin

    def _named(self, load: object, n: int) -> dict | None:
        """The named loads' magnitudes ``{name: (n,)}`` from the verbs' ``load`` (module docstring)."""
        names = self.model.named_loads
        if load is None:
            return None
        v = np.asarray(load, dtype=float)
        if not names:
            if np.any(v != 0.0):
                raise ParameterError(f"mechanism {self.model.name!r} has no named load ([[loads]] with a name); "
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

    def _state_one(self, model: MechanismModel, x: Array, xd: Array) -> MechanismKinematics:
        """One sample's kinematics straight from the compiled solver, warm-started (the checked,
        bridging route when that solve does not converge or nothing is known yet)."""

        st = self._state(model)
        q_last = st.last_q()
        if q_last is None:
            return self._kin(model, x[None], xd[None])
        x1 = np.ascontiguousarray(x, dtype=float).reshape(1, -1)
        xd1 = np.ascontiguousarray(xd, dtype=float).reshape(1, -1)
        zero = np.zeros_like(x1)
        out = _run(model, x1, xd1, zero, q_last)
        if out["status"][0] != K.OK or not (np.all(np.isfinite(x1)) and np.all(np.isfinite(xd1))):
            return self._kin(model, x1, xd1)
        kin = _assemble(model, None, x1, xd1, zero, out)
        st.remember(kin)
        return kin

    def _mass(self, model: MechanismModel, kin: MechanismKinematics, S: Array) -> Array:
        return task_mass_matrix(model, kin, S, self._state(model).inertia_factors)

    def _bias(self, model: MechanismModel, kin: MechanismKinematics, S: Array, named: dict | None = None) -> Array:
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

    # ------------------------------------------------------------------ verbs
    def mass_matrix(self, model: MechanismModel, q: Array) -> Array:
        """``M(x) (n, nt, nt)``."""
        x = self._x(q)
        kin = self._kin(model, x)
        return self._mass(model, kin, coordinate_twists(model, kin.q, kin))

    def actuator_map(self, model: MechanismModel, q: Array) -> Array:
        """``B(x) = J_ax^T k (n, nt, na)`` (``k`` the drives' transmission ratios, 1 without a drive).
        Along a motion of :data:`MAP_SAMPLES` poses or more, the single-sample kernel in one
        compiled loop (:func:`pkmdyn.multibody.dynamics._sample_kernels.actuator_maps`: the same solver and tolerances, each pose
        from the last), the first pose by the checked route."""
        x = self._x(q)
        J = self._maps(model, x) if x.shape[0] >= MAP_SAMPLES else None
        if J is None:
            J = self._kin(model, x).J_ax
        return np.swapaxes(J, 1, 2) * model.drive_ratio

    def _maps(self, model: MechanismModel, x: Array) -> Array | None:
        """``J_ax (n, na, nt)`` along the poses ``x`` by :func:`pkmdyn.multibody.dynamics._sample_kernels.actuator_maps` where the
        kernel answers for ``model`` (else None): the first pose by the checked route (from the
        last solved sample, as :meth:`_kin` starts), every later one by the kernel from the one
        before, the rest by the checked route from the first it does not solve; the last
        solved sample remembered, as :meth:`_kin` does."""
        st = self._state(model)
        if st.pk is None or not np.all(np.isfinite(x)):
            return None
        _one = st.one
        first = self._kin(model, x[:1])
        if st.map_pk is None:
            st.map_pk = _one.pack(model)
        n, nt, na = x.shape[0], model.nt, model.na
        out = np.empty((n, na * nt))
        out[0] = first.J_ax[0].ravel()
        _one.prime(st.map_pk, first.q[0], first.x[0], first.G[0])
        # the poses' steps as their rates (per sample): the predictor's second order along the motion
        xd = np.empty_like(x)
        xd[0] = 0.0
        d = np.diff(x, axis=0)
        ang = model.task_kind == 1
        d[:, ang] = (d[:, ang] + np.pi) % (2 * np.pi) - np.pi
        xd[1:] = d
        done = 1 + _one.actuator_maps(st.map_pk, x[1:], xd[1:], out[1:])
        if done < n:  # the checked route names what is wrong, or solves the rest
            q_prev = _one.solution(st.map_pk)
            rest = solve_kinematics(model, x[done:], q_start=q_prev if q_prev is not None else first.q[0],
                                    sample_offset=done)
            out[done:] = rest.J_ax.reshape(n - done, na * nt)
            st.remember(rest)
        else:
            sol = _one.state(st.map_pk)
            nq = model.nq
            q_end = sol[1:1 + nq].copy()
            st.q_last = q_end
            _one.prime(st.pk, q_end, x[-1], sol[1 + nq + nt:1 + nq + nt + nq * nt].reshape(nq, nt))
        return out.reshape(n, na, nt)

    def actuator_accelerations(self, model: MechanismModel, q: Array, qd: Array, qdd: Array) -> Array:
        """The drives' accelerations ``k qdd_a (n, na)`` (motor side, ``k`` as in :meth:`actuator_map`)
        along task poses ``q``, rates ``qd`` and accelerations ``qdd``, from the kinematics'
        second-order solution: exact, where a difference of :meth:`actuator_map` in time would
        carry the solver's round-off divided by the step."""
        st = self._state(model)
        kin = solve_kinematics(model, self._x(q), self._x(qd, "qd"), self._x(qdd, "qdd"), q_start=st.last_q())
        st.remember(kin)
        return kin.act_qdd * model.drive_ratio

    def bias_forces(self, model: MechanismModel, q: Array, qd: Array, load: Array | None = None) -> Array:
        """``h(x, xd) (n, nt)``."""
        x = self._x(q)
        kin = self._kin(model, x, self._x(qd, "qd"))
        return self._bias(model, kin, coordinate_twists(model, kin.q, kin), self._named(load, len(kin)))

    def _all(self, model: MechanismModel, q: Array, qd: Array, load: object, one: bool = False
             ) -> tuple[Array, Array, Array, MechanismKinematics]:
        if one:
            kin = self._state_one(model, np.asarray(q, dtype=float), np.asarray(qd, dtype=float))
        else:
            kin = self._kin(model, self._x(q), self._x(qd, "qd"))
        named = self._named(load, len(kin))
        S = coordinate_twists(model, kin.q, kin)
        B = np.swapaxes(kin.J_ax, 1, 2) * model.drive_ratio
        return self._mass(model, kin, S), self._bias(model, kin, S, named), B, kin

    def inverse_dynamics(self, model: MechanismModel, q: Array, qd: Array, qdd: Array,
                         load: Array | None = None) -> Array:
        """Efforts ``u (n, na)`` with ``B u = M xdd + h`` (more actuators than task coordinates:
        the minimum-norm joint efforts, each divided by its drive's ratio)."""
        M, h, B, kin = self._all(model, q, qd, load)
        rhs = np.einsum("nij,nj->ni", M, self._x(qdd, "qdd")) + h
        # actuator_efforts checks the actuator map's rank and names the sample; J_ax^T (k tau) = rhs
        return actuator_efforts(model, kin, np.zeros((len(kin), 0)), rhs_task=rhs) / model.drive_ratio

    def forward_dynamics(self, model: MechanismModel, q: Array, qd: Array, u: Array,
                         load: Array | None = None) -> Array:
        """Accelerations ``xdd (n, nt)`` with ``M xdd = B u - h``."""
        M, h, B, _ = self._all(model, q, qd, load)
        uu = np.atleast_2d(as_array(u, (None, model.na) if np.ndim(u) == 2 else (model.na,), "u", MotionError))
        return np.linalg.solve(M, (np.einsum("nta,na->nt", B, uu) - h)[..., None])[..., 0]

    def one_sample_kernels(self, model: MechanismModel) -> tuple[NDArray[np.int64], object, object] | None:
        """``(p, inverse, forward)``: the compiled single-sample kernels (:mod:`pkmdyn.multibody.dynamics._sample_kernels`) for
        callers in a loop (``pkmdyn.machine_protocol``; ``load`` the named load's magnitude), or None
        where they do not answer for this mechanism (friction that depends on the reactions,
        several named loads, redundant actuation, a named load with a nonzero default
        magnitude): the ``*_one`` verbs then take the general route."""
        pk = self._state(model).pk
        if pk is None or np.any(model.load_magnitude != 0.0):
            return None  # (a caller without a load passes 0.0: right only for a zero default magnitude)
        return pk, _one.inverse_one, _one.forward_one

    def _kernel(self, model: MechanismModel, forward: bool, q: object, qd: object, v: object,
                load: object) -> Array | None:
        """The compiled path's answer, or None (then the general route answers and primes it)."""
        st = self._state(model)
        pk = st.pk
        if pk is None:
            return None
        if st.default_load is not None:
            if type(load) is float and math.isfinite(load):  # a loop's own value: no array to make
                magnitude = load
            else:
                lv = np.asarray(st.default_load if load is None else load, dtype=float)
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
        status = st.dynamics(pk, x, xd, vv, magnitude, st.modes[forward], out)
        return out if status == 0 else None

    def inverse_dynamics_one(self, model: MechanismModel, q: Array, qd: Array, qdd: Array,
                             load: float | None = None) -> Array:
        """One sample of :meth:`inverse_dynamics` (the single-sample path: one compiled call
        where :mod:`pkmdyn.multibody.dynamics._sample_kernels` answers, else the compiled solver warm-started from the previous
        call, no batch checks)."""
        u = self._kernel(model, False, q, qd, qdd, load)
        if u is not None:
            return u
        M, h, B, kin = self._all(model, q, qd, load, one=True)
        rhs = M[0] @ np.asarray(qdd, dtype=float) + h[0]
        return actuator_efforts(model, kin, np.zeros((1, 0)), rhs_task=rhs[None])[0] / model.drive_ratio

    def forward_dynamics_one(self, model: MechanismModel, q: Array, qd: Array, u: Array,
                             load: float | None = None) -> Array:
        """One sample of :meth:`forward_dynamics` (the single-sample path)."""
        a = self._kernel(model, True, q, qd, u, load)
        if a is not None:
            return a
        M, h, B, _ = self._all(model, q, qd, load, one=True)
        return np.linalg.solve(M[0], B[0] @ np.asarray(u, dtype=float) - h[0])


    # ------------------------------------------------------------------ kinematics (exact encoders)
    def drive_ratios(self, model: MechanismModel) -> Array:
        """``(na,)`` the drives' transmission ratios (1 for an actuated joint without a drive):
        motor displacement per actuated joint displacement."""
        self._state(model)
        return np.asarray(model.drive_ratio, dtype=float).copy()

    def actuator_coordinates_one(self, model: MechanismModel, q: Array, qd: Array, fresh: bool = False) -> Array:
        """The actuated joints' coordinates ``(na,)`` at task pose ``q`` (one sample of the
        inverse kinematics, warm-started from the last solved sample: the plant's encoders; with
        ``fresh``, reached from the reference configuration instead, the assembly of a run's
        first pose). ``qd``, the pose's rate, makes the start closer. One compiled call
        (:func:`pkmdyn.multibody.dynamics._sample_kernels.positions_one`) where it answers, else the checked route."""
        st = self._state(model)
        nt = model.nt
        _one = st.one
        if not fresh and st.encoder_q is not None and st.encoder_pk is not None:
            xa, xda = np.ascontiguousarray(q, dtype=float), np.ascontiguousarray(qd, dtype=float)
            if xa.shape == (nt,) and xda.shape == (nt,):
                np.copyto(st.encoder_prev, st.encoder_view)
                if _one.positions_one(st.encoder_pk, xa, xda, st.encoder_out) == _one.OK:
                    return st.encoder_out.copy()
                st.encoder_q = st.encoder_prev.copy()  # the last reading's solution

        x1 = np.ascontiguousarray(self._x(q))
        q_sol = G_sol = None
        if not fresh and st.encoder_q is not None and np.all(np.isfinite(x1)):
            # from the previous reading (near: one control cycle ago), not from whatever the
            # other verbs solved last, which may lie on another branch of a leg
            out = _run(model, x1, np.zeros_like(x1), np.zeros_like(x1), st.encoder_q)
            if out["status"][0] == K.OK:
                q_sol, G_sol = out["q"][0].copy(), out["G"][0].copy()
        if q_sol is None:
            kin = solve_kinematics(model, x1, q_start=None if fresh or st.encoder_q is None else st.encoder_q)
            q_sol, G_sol = kin.q[0].copy(), kin.G[0].copy()
        st.encoder_q = q_sol
        if st.encoder_pk is not None:
            _one.prime(st.encoder_pk, q_sol, x1[0], G_sol)
        return q_sol[model.act_coord].copy()

    def prime_direct(self, model: MechanismModel, q: Array) -> None:
        """Let the next :meth:`direct_one` call start from the task pose ``q`` whose actuated
        coordinates the last ``actuator_coordinates_one(model, q, qd, fresh=True)`` solved (its
        tree coordinates, kept as the encoders' solution): a controller that knows the pose its
        run starts from, instead of solving the direct kinematics from the reference
        configuration by the checked route (whose batched kernels a fresh install would compile
        for some seconds). The branch is that of ``q``; the sign of its determinant is taken
        from that next call. Nothing where no such solution is kept."""

        st = self._state(model)
        x = np.asarray(q, dtype=float).reshape(-1)
        if st.encoder_q is None or x.shape != (model.nt,) or not np.all(np.isfinite(x)):
            return
        qt = st.encoder_q.copy()
        a = qt[model.act_coord].copy()
        if st.direct is None:
            self._pack_direct(model, st)
        prime_one(st.direct[0], qt, x, a, 0.0)
        if st.direct_task:
            prime_task(st.direct_task[1], qt, x, a)
            task_state(st.direct_task[1])[1] = 0.0

    def encoder_buffers(self, model: MechanismModel) -> tuple[NDArray[np.int64], Array, Array, Array] | None:
        """``(pk, view, prev, out)``: what :meth:`actuator_coordinates_one` hands its compiled call
        once a reading has been solved (``pk`` the packed buffer, ``view`` its solution, ``prev``
        where the call keeps the previous one, ``out (na,)`` the answer), for a caller that makes
        the same call in its own compiled loop (:mod:`pkmdyn.simulate`); None before."""
        st = self._state(model)
        if st.encoder_q is None or st.encoder_pk is None:
            return None
        return st.encoder_pk, st.encoder_view, st.encoder_prev, st.encoder_out

    def direct_task_buffers(self, model: MechanismModel) -> tuple[NDArray[np.int64], NDArray[np.int64], Array,
                                                                    int] | None:
        """``(pk, d, out, ok)``: what :meth:`direct_one` hands :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one`
        once primed, where the mechanism takes the task-space route (``out (2 nt,)`` the pose
        and its rate, ``ok`` the status of an answer); None otherwise."""
        st = self._state(model)
        if not st.direct_task:
            return None
        pk1, d, out, _, ok, _ = st.direct_task
        return pk1, d, out, int(ok)

    def direct_one(self, model: MechanismModel, a: Array, ad: Array) -> tuple[Array, Array]:
        """The task pose and rate ``(nt,), (nt,)`` at actuated joint coordinates ``a`` and rates
        ``ad`` by the direct kinematics (:mod:`pkmdyn.multibody.kinematics.direct`), warm-started from the previous call
        (the first from the reference configuration): the controller's pose from its encoders.
        One compiled call: in task space where every actuator belongs to a leg placed from the
        task alone (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one`: the Gough-Stewart platform, a 3PUS+S platform), else
        on the tree coordinates with a packed buffer (:func:`pkmdyn.multibody.kinematics._direct_kernels.direct_one`); where it
        cannot answer, the checked route. Raises where the actuators reach no pose or sit on a
        singularity."""
        st = self._state(model)
        a = np.ascontiguousarray(a, dtype=float)
        ad = np.ascontiguousarray(ad, dtype=float)
        if a.ndim != 1 or ad.ndim != 1:
            a, ad = a.reshape(-1), ad.reshape(-1)
        nt = model.nt
        fit = a.shape == ad.shape == (model.na,)
        status = -1
        if st.direct_task:  # (the kernels have run or been waited for: nothing to wait for)
            pk1, d, out, kernel, ok, _ = st.direct_task
            status = kernel(pk1, d, a, ad, out) if fit else ok - 1
            if status == ok:
                return out[:nt].copy(), out[nt:].copy()
        elif st.direct is not None:
            pk, out, kernel, ok = st.direct
            status = kernel(pk, a, ad, out) if fit else ok - 1
            if status == ok:
                return out[:nt].copy(), out[nt:].copy()
        if st.direct is None:  # the first call packs both routes
            return self._direct_checked(model, st, a, ad, status)
        if st.direct_task:
            return self._direct_task_on(model, st, a, ad, fit, status)
        return self._direct_checked(model, st, a, ad, status)

    @staticmethod
    def _pack_direct(model: MechanismModel, st: _State) -> None:
        """Pack both single-sample routes of :meth:`direct_one` into ``st`` (the task-space one
        where the mechanism takes it, else ``False``), neither primed."""

        st.direct = (pack_one(model), np.zeros(2 * model.nt), D.direct_one, D.OK)
        d = pack_task(model)
        st.direct_task = False
        if d is not None:  # (the task route only reads the model's arrays from a single-sample buffer)
            pk1 = st.pk if st.pk is not None else _one.pack(model)
            st.direct_task = (pk1, d, np.zeros(2 * model.nt), D.direct_task_one, D.OK, D.CROSSED)

    def _direct_task_on(self, model: MechanismModel, st: _State, a: Array, ad: Array, fit: bool,
                        status: int) -> tuple[Array, Array]:
        """:meth:`direct_one` where the task-space call did not answer: a move too large for one
        call (or one it cannot solve) along the straight actuator path in 8, then 64 steps, else
        the checked route from the last solution; the branch checked by the sign of ``det A``
        against the last solution's. Raises on a crossing."""

        pk1, d, out, kernel, ok, crossed = st.direct_task
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

    def _direct_checked(self, model: MechanismModel, st: _State, a: Array, ad: Array,
                        status: int) -> tuple[Array, Array]:
        """:meth:`direct_one` by the checked route: where the tree-space call did not answer
        (from its last solution; raises on a crossing), or on the first call (from the reference
        configuration), which packs both single-sample routes and primes them."""

        if st.direct is not None:
            if status == D.CROSSED:
                raise SingularityError(_CROSSING)
            prev = one_state(st.direct[0])
            q_prev, det_prev = prev[2:2 + model.nq].copy(), float(prev[1])
            dk = direct_kinematics(model, a[None], ad[None], q_start=q_prev)
            if dk.det[0] * det_prev < 0:  # the checked route names what is wrong otherwise
                raise SingularityError(_CROSSING)
        else:
            dk = direct_kinematics(model, a[None], ad[None])
            self._pack_direct(model, st)
        prime_one(st.direct[0], dk.q[0], dk.x[0], a, float(dk.det[0]))
        if st.direct_task:
            prime_task(st.direct_task[1], dk.q[0], dk.x[0], a)
        return dk.x[0].copy(), dk.xd[0].copy()


def machine_verbs(model: MechanismModel) -> MechanismVerbs:
    """The :class:`pkmdyn.machine_protocol.MachineDynamics` verbs of a described mechanism."""
    return MechanismVerbs(model)


@dataclass(frozen=True)
class GeneratedModel:
    """A machine generated as a description (a paper's machine): its own parameters ``params``
    (for its motions and drawings) and the compiled mechanism of their description, the model
    :class:`RenamedVerbs` run on."""

    params: Any
    mechanism: MechanismModel


class RenamedVerbs:
    """The verbs of a machine generated as a description (a paper's machine), under its own
    names: ``COORDINATES`` and ``ACTUATORS`` renamed (same order and units as the
    description's), every verb the :class:`MechanismVerbs` one of the compiled mechanism that
    its models carry as ``.mechanism`` (a model object that also carries the paper's
    parameters, for its motions and drawings)."""

    def __init__(self, mechanism: MechanismModel, coordinates: tuple[str, ...], actuators: tuple[str, ...]) -> None:
        if len(coordinates) != mechanism.nt or len(actuators) != mechanism.na:
            raise ParameterError(f"mechanism {mechanism.name!r}: {mechanism.nt} task coordinates and {mechanism.na} "
                                 f"actuators, renamed as {len(coordinates)} and {len(actuators)}")
        self._verbs = MechanismVerbs(mechanism)
        self.COORDINATES = tuple(coordinates)
        self.ACTUATORS = tuple(actuators)

    def __getattr__(self, name: str) -> Any:
        verb = None if name.startswith("_") else getattr(self._verbs, name, None)
        if not callable(verb):
            raise AttributeError(name)

        def on_mechanism(model: Any, *args: Any, **kwargs: Any) -> Any:
            return verb(model.mechanism, *args, **kwargs)

        on_mechanism.__doc__ = verb.__doc__
        setattr(self, name, on_mechanism)  # made once: a loop's calls then find it as an attribute
        return on_mechanism

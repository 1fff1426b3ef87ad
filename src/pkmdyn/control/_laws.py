"""Controllers: reference in, sensed state in, actuator efforts out.

A controller is a frozen :class:`Controller` (its kind, gains and whatever it precomputes
from its own model along the reference) and one free function, :func:`effort`, called once
per control cycle ``k``. The controller's model may differ from the plant's.

Equations of motion in minimal coordinates (``pkmdyn.machine_protocol``): ``M(q) qdd + h = B(q) u``.
Errors ``e = q_ref - q_s``, ``e_dot = qd_ref - qd_s`` with ``q_s, qd_s`` the sensed pose and
its rate; ``u_ff(k)`` the effort held over interval ``k``: the model's inverse dynamics along
the reference at the middle of the interval, corrected by ``- T^2/24`` times its second
derivative (:func:`held_efforts`; why, in ``pkmdyn.control._reference``).

- ``feedforward``: ``u = u_ff(k)``, open loop.
- ``pd`` - the workspace PD of Chen, Cheng & Pang (2022), Eq. (15). The printed equation,
  ``F_j = J_j^-1 [K_d omega_dot_j + K_p omega]`` with ``Delta omega_j = omega_j^d - omega_j``
  "the attitude angle error", is garbled: the bracket must hold the *errors* (the paper
  defines ``Delta omega`` and never uses it), ``K_p`` multiplies the posture-angle error and
  ``K_d`` its rate, and ``J_j^-1`` carries the workspace generalised force to the actuators.
  Our reading: ``u = B(q_ref)^-1 (K_p e + K_d e_dot)``, ``B^-1`` the inverse actuator map of
  the controller's model along the reference (the workspace force -> actuator efforts; for
  motors behind lead screws of lead ``p``, ``tau = (p / 2 pi) J^-T Q``); ``K_p`` [N m/rad], ``K_d`` [N m s/rad] diagonal.
- ``augmented-pd`` - that paper's Fig. 9: the PD above plus the model-based feedforward, whose
  inverse dynamics contain the model's friction (in that paper, bearing friction under the
  load, Eq. 16) evaluated at the reference velocity: ``u = u_ff(k) + B(q_ref)^-1 (K_p e + K_d e_dot)``.
- ``computed-torque``: ``u = ID(q_s, qd_s, qdd_ref + K_p e + K_d e_dot, load)`` with the
  model's inverse dynamics at the sensed state; ``K_p`` [1/s^2], ``K_d`` [1/s]
  (``omega_n^2``, ``2 zeta omega_n``).
- ``pid`` - a position-loop PID in joint space (as in the PDM paper's section 7): on each actuator's
  displacement ``s`` (from its encoder), ``u = K_p e_s + K_i integral(e_s) + K_d e_s_dot``,
  ``e_s = s_ref - s_enc`` and ``e_s_dot = sd_ref - sd_enc`` (the encoder's differenced and
  filtered rate); the integral is a rectangle sum over cycles.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from ..multibody.dynamics.distribution import least_norm_map
from ._reference import JointReference, Reference

__all__ = ["CONTROLLERS", "Gains", "Sensed", "Controller", "make_controller", "effort", "new_memory", "held_efforts"]

Array = NDArray[np.float64]

_NO_FF = np.zeros((1, 1))

CONTROLLERS = ("pd", "augmented-pd", "feedforward", "computed-torque", "pid")


@dataclass(frozen=True)
class Gains:
    """Diagonal gains, one value per coordinate (workspace laws) or actuator (``pid``); units
    per controller in the module docstring. ``ki`` is used by ``pid`` only."""

    kp: Array
    kd: Array
    ki: Array


@dataclass(frozen=True)
class Sensed:
    """What the sensors report at a cycle instant (buffers rewritten in place each cycle):
    ``q, qd (nq,)`` the pose and its rate (pose sensor, differenced and filtered);
    ``s, sd, sdd (nu,)`` the actuator displacement from the encoders (quantised), its
    differenced-and-filtered rate and acceleration."""

    q: Array
    qd: Array
    s: Array
    sd: Array
    sdd: Array


@dataclass(frozen=True)
class Controller:
    """A controller ready to run along one reference.

    ``u_ff (K, nu)`` the model's efforts held over each interval (:func:`held_efforts`;
    feedforward, augmented PD); ``B_inv (K + 1, nu, nq)`` the inverse actuator map along the reference
    (PD laws); ``joint`` the joint-space reference (PID); ``id_one`` the model's single-sample
    inverse dynamics ``(q, qd, qdd, load) -> u`` (computed torque); ``out (nu,)`` the buffer
    the laws write their efforts into and ``acc (nq,)`` computed torque's commanded
    acceleration (no allocation per cycle).
    """

    kind: str
    gains: Gains
    u_ff: Array | None
    B_inv: Array | None
    joint: JointReference | None
    id_one: Any
    out: Array
    acc: Array
    #: ``(p, inverse, has_load)`` where ``id_one`` is the machine's compiled single-sample kernel
    #: ``inverse(p, q, qd, qdd, load, out)`` (``one_sample_kernels``), for a compiled loop; else None
    id_kernel: Any = None


def _id_one(verbs: Any, model: Any, has_load: bool) -> Any:
    one = getattr(verbs, "inverse_dynamics_one", None)
    kernels = getattr(verbs, "one_sample_kernels", None)
    compiled = kernels(model) if one is not None and kernels is not None else None
    if compiled is not None:
        p, inverse, _ = compiled
        nu = len(verbs.ACTUATORS)

        def id_kernel(q: Array, qd: Array, qdd: Array, load: float) -> Array:
            out = np.empty(nu)
            if inverse(p, q, qd, qdd, load if has_load else 0.0, out):
                return one(model, q, qd, qdd, load if has_load else None)  # raises the machine's error
            return out

        id_kernel.kernel = (p, inverse, has_load)  # type: ignore[attr-defined]
        return id_kernel
    if one is not None:
        if has_load:
            return lambda q, qd, qdd, load: one(model, q, qd, qdd, load)
        return lambda q, qd, qdd, load: one(model, q, qd, qdd, None)
    batched = verbs.inverse_dynamics
    if has_load:
        return lambda q, qd, qdd, load: batched(model, q[None], qd[None], qdd[None], np.array([load]))[0]
    return lambda q, qd, qdd, load: batched(model, q[None], qd[None], qdd[None], None)[0]


def check_gains(kind: str, gains: Gains, n: int) -> None:
    """Every gain finite and >= 0, ``n`` values each; errors name the controller and the gain."""
    for name in ("kp", "kd", "ki"):
        g = np.asarray(getattr(gains, name), dtype=float)
        if g.shape != (n,):
            raise ParameterError(f"gains [{kind}] {name}: expected {n} values, got shape {g.shape}")
        bad = np.flatnonzero(~(np.isfinite(g) & (g >= 0)))
        if bad.size:
            raise ParameterError(f"gains [{kind}] {name}[{bad[0]}]: {g[bad[0]]:g} must be finite and >= 0")


def make_controller(kind: str, gains: Gains, verbs: Any, model: Any, ref: Reference,
                    joint: JointReference | None = None) -> Controller:
    """Precompute what ``kind`` needs from the controller's ``model`` along ``ref`` (batched
    verb calls, once). ``joint`` is required by ``pid``."""
    if kind not in CONTROLLERS:
        raise ParameterError(f"controller {kind!r}: unknown (known: {', '.join(CONTROLLERS)})")
    nq, nu = len(verbs.COORDINATES), len(verbs.ACTUATORS)
    check_gains(kind, gains, nu if kind == "pid" else nq)
    has_load = ref.load is not None
    u_ff = B_inv = None
    if kind in ("feedforward", "augmented-pd"):
        u_mid = verbs.inverse_dynamics(model, ref.mid_q, ref.mid_qd, ref.mid_qdd, ref.mid_load)
        u_ff = held_efforts(u_mid)
    if kind in ("pd", "augmented-pd"):
        if joint is not None:
            B = np.swapaxes(joint.Bt, -1, -2)  # the same model's actuator map along ref.q
        else:
            B = np.asarray(verbs.actuator_map(model, ref.q), dtype=float)
        if nq > nu:
            raise ParameterError(f"controller {kind!r}: needs at least as many actuators as coordinates ({nu} < {nq})")
        B_inv = np.linalg.inv(B) if nq == nu else _task_effort_map(model, B)
    if kind == "pid" and joint is None:
        raise ParameterError("controller 'pid': needs the joint-space reference")
    id_one = _id_one(verbs, model, has_load) if kind == "computed-torque" else None
    g = Gains(*(np.ascontiguousarray(getattr(gains, n), dtype=float) for n in ("kp", "kd", "ki")))
    return Controller(kind, g, u_ff, B_inv, joint if kind == "pid" else None, id_one, np.zeros(nu),
                      np.zeros(nq), getattr(id_one, "kernel", None))


def _task_effort_map(model: Any, B: Array) -> Array:
    """A redundantly actuated machine's efforts per task effort ``(K + 1, nu, nq)`` along the
    reference, from its actuator map ``B = J_ax^T k``: a described mechanism's (weighted)
    least-norm joint efforts (:func:`pkmdyn.multibody.dynamics.distribution.least_norm_map`, Eq.
    R1-R2: its distribution's rule, or that rule's linear part for a minimax, bounded or
    preloaded one, whose internal force the feedforward holds), each divided by its drive's
    ratio ``k``; ``B^+`` for another machine, and for an under-actuated one (fewer actuators
    than task coordinates: the efforts whose generalised force is nearest the task effort, in
    least squares; the least-norm map needs ``B`` of full row rank)."""
    k = getattr(model, "drive_ratio", None)
    if k is None or not hasattr(model, "act_distribution") or B.shape[-2] > B.shape[-1]:
        return np.linalg.pinv(B)
    return least_norm_map(model, B / k[None, None, :]) / k[None, :, None]


def held_efforts(u_mid: Array) -> Array:
    """The effort to hold over each interval from the ideal efforts ``u_mid (K, nu)`` at the
    interval middles: ``u_k = u_mid,k - T^2/24 u''_k`` with ``T^2 u''_k`` the second difference
    of the middles (``(-u_mid,k-1 + 26 u_mid,k - u_mid,k+1) / 24``; the first and last interval
    take their neighbour's difference), i.e. the interval mean minus ``T^2/12 u''``; the first
    interval also less ``T/12 u'(0)`` (``(u_mid,1 - u_mid,0) / 12``). Why this and not the
    mean: see the module docstring of :mod:`pkmdyn.control._reference`."""
    u = np.asarray(u_mid, dtype=float)
    if u.shape[0] < 3:
        return u.copy()
    d2 = np.empty_like(u)
    d2[1:-1] = u[:-2] - 2.0 * u[1:-1] + u[2:]
    d2[0] = d2[1]
    d2[-1] = d2[-2]
    held = u - d2 / 24.0
    held[0] -= (u[1] - u[0]) / 12.0  # the start: the velocity offset -T^2/12 G u*'(0)
    return held


def new_memory(ctrl: Controller, nu: int) -> Array:
    """The controller's state between cycles (the PID's error integral), zero at the start."""
    return np.zeros(nu)


@numba.njit(cache=True)
def _pd(k: int, q_ref: Array, qd_ref: Array, q: Array, qd: Array, kp: Array, kd: Array, B_inv: Array,
        u_ff: Array, with_ff: bool, out: Array) -> None:  # pragma: no cover - compiled
    """``out = [u_ff(k) +] B_inv(k) (K_p e + K_d e_dot)``."""
    nu, nq = B_inv.shape[1], B_inv.shape[2]
    for a in range(nu):
        acc = u_ff[k, a] if with_ff else 0.0
        for i in range(nq):
            acc += B_inv[k, a, i] * (kp[i] * (q_ref[k, i] - q[i]) + kd[i] * (qd_ref[k, i] - qd[i]))
        out[a] = acc


@numba.njit(cache=True)
def _ct_acc(k: int, q_ref: Array, qd_ref: Array, qdd_ref: Array, q: Array, qd: Array, kp: Array, kd: Array,
            out: Array) -> None:  # pragma: no cover - compiled
    """``out = qdd_ref + K_p e + K_d e_dot`` (computed torque's commanded acceleration)."""
    for i in range(out.shape[0]):
        out[i] = qdd_ref[k, i] + kp[i] * (q_ref[k, i] - q[i]) + kd[i] * (qd_ref[k, i] - qd[i])


@numba.njit(cache=True)
def _pid(k: int, T: float, s_ref: Array, sd_ref: Array, s: Array, sd: Array, kp: Array, ki: Array, kd: Array,
         memory: Array, out: Array) -> None:  # pragma: no cover - compiled
    """``out = K_p e + K_i sum(e T) + K_d e_dot`` per actuator; ``memory`` holds the sum."""
    for a in range(out.shape[0]):
        e = s_ref[k, a] - s[a]
        memory[a] += e * T
        out[a] = kp[a] * e + ki[a] * memory[a] + kd[a] * (sd_ref[k, a] - sd[a])


def effort(ctrl: Controller, ref: Reference, k: int, y: Sensed, memory: Array) -> Array:
    """Efforts ``u (nu,)`` of cycle ``k`` from the reference and the sensed state ``y``
    (``memory`` is updated in place; the returned array may be reused by the next call).
    See the module docstring for each law."""
    kind = ctrl.kind
    g = ctrl.gains
    if kind == "feedforward":
        return ctrl.u_ff[k]
    out = ctrl.out
    if kind == "pid":
        j = ctrl.joint
        _pid(k, ref.T, j.s, j.sd, y.s, y.sd, g.kp, g.ki, g.kd, memory, out)
        return out
    if kind == "computed-torque":
        load = 0.0 if ref.load is None else ref.load[k]
        _ct_acc(k, ref.q, ref.qd, ref.qdd, y.q, y.qd, g.kp, g.kd, ctrl.acc)
        return np.asarray(ctrl.id_one(y.q, y.qd, ctrl.acc, load), dtype=float)
    _pd(k, ref.q, ref.qd, y.q, y.qd, g.kp, g.kd, ctrl.B_inv, ctrl.u_ff if ctrl.u_ff is not None else _NO_FF,
        kind == "augmented-pd", out)
    return out

"""An under-actuated mechanism (fewer actuated joints than degrees of freedom) driven by its
actuators: the passive freedoms simulated.

The actuated joints follow a prescribed motion ``s(t)`` (na); the task coordinates ``x`` (nt)
move by the equations of motion of :mod:`pkmdyn.multibody.dynamics.verbs` (gravity, loads,
joint springs, friction and damping included) under the efforts ``u`` that make the actuated
joints follow it. Per instant, the square system

    [ M(x)      -B(x) ] [ xdd ]   [ -h(x, xd)                                     ]
    [ J_ax(x)    0    ] [ u   ] = [ sdd_ref - Jd_ax xd                            ]      (P1)

with ``B = J_ax^T K`` (the motors' map), ``Jd_ax xd`` the actuated joints' acceleration at
``xdd = 0``, and ``sdd_ref = sdd + 2 a (sd - J_ax xd) + a^2 (s - q_a(x))`` (Baumgarte's
stabilisation, ``a`` = :data:`BAUMGARTE` per second: the drift of the integration kept off the
actuated joints). The state ``(x, xd)`` is integrated by scipy's DOP853 (an explicit
Runge-Kutta method of order 8) to ``rtol``; ``s``, ``sd`` and ``sdd`` between samples by a
quintic Hermite interpolation of the given samples. Where the steps shrink without end (near
a singularity of the task coordinates, whose rates then grow) the integration stops
(:data:`STALL_WINDOW`), naming the time and the inverse singularity measure there.

The start: the pose nearest the reference task pose with the actuated joints at ``s(0)``
(least squares on the passive directions, Gauss-Newton) at the least-norm rate ``J_ax^+
sd(0)``, unless given."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError, PkmdynError
from ..multibody.dynamics.verbs import MechanismData, _all
from ..multibody.kinematics.inverse import reference_task, solve_kinematics
from ..multibody.kinematics.singularity.measures import singularity_measures
from ..multibody.kinematics.motion import TaskMotion
from ..multibody.model.compiler import MechanismModel

__all__ = ["passive_motion", "driven_motion"]

Array = NDArray[np.float64]

#: Baumgarte's rate [1/s]: how fast a drift of the actuated joints from their motion decays
BAUMGARTE = 50.0
#: the integration's check of its progress: every this many right-hand-side evaluations it must
#: have advanced by :data:`STALL_PROGRESS` of the motion's span or by :data:`STALL_SECONDS`,
#: whichever is less, or it stops, naming where (a step that shrinks without end, near a
#: singularity of the task coordinates, would run on; the cart-pole of the tests takes some
#: 6,000 evaluations for its whole 1.5 s, and 1e-4 s in 20,000 evaluations is a mean step some
#: 1e-7 s long: dynamics of megahertz)
STALL_WINDOW = 20_000
STALL_PROGRESS = 1e-3
STALL_SECONDS = 1e-4


class _Stalled(Exception):
    """The integration stopped advancing (:data:`STALL_WINDOW`)."""


def _hermite(t: Array, s: Array, sd: Array, sdd: Array) -> Any:
    """``f(tau) -> (s, sd, sdd)`` (na,) of the quintic Hermite interpolation through the samples."""
    from scipy.interpolate import BPoly

    y = np.stack([s, sd, sdd], axis=1)  # (n, 3, na)
    poly = BPoly.from_derivatives(t, y)
    d1, d2 = poly.derivative(1), poly.derivative(2)
    return lambda tau: (poly(tau), d1(tau), d2(tau))


def _start(model: MechanismModel, s0: Array, x_guess: Array) -> Array:
    """The task pose nearest ``x_guess`` with the actuated joints at ``s0`` (Gauss-Newton)."""
    x = x_guess.copy()
    z = np.zeros((1, model.nt))
    for _ in range(50):
        kin = solve_kinematics(model, x[None], z, z)
        r = s0 - kin.act_q[0]
        J = kin.J_ax[0]
        step = np.linalg.lstsq(J, r, rcond=None)[0]
        x = x + step
        if np.abs(r).max() <= 1e-12 * max(1.0, float(np.abs(s0).max())):
            return x
    raise MotionError(f"actuator motion: sample 0: no pose near the reference puts the actuated joints "
                      f"{', '.join(model.actuator_names)} at the motion's first values")


def passive_motion(model: MechanismModel, t: Array, s: Array, sd: Array, sdd: Array, x0: Array | None = None,
                   xd0: Array | None = None, rtol: float = 1e-10, load: Array | None = None,
                   progress: Callable[[float], None] | None = None) -> TaskMotion:
    """The task motion ``x, xd, xdd`` at the times ``t (n,)`` of an under-actuated mechanism
    whose actuated joints follow ``s, sd, sdd (n, na)`` [m or rad] (module docstring, Eq. P1);
    ``x0, xd0`` (nt,) the start (default: nearest the reference pose, least-norm rate);
    ``progress(tau)`` called with the time reached [s] every few hundred evaluations.
    Raises :class:`~pkmdyn.errors.MotionError` naming the time where the integration fails."""
    from scipy.integrate import solve_ivp

    nt, na = model.nt, model.na
    t = np.asarray(t, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise MotionError(f"actuator motion: the passive freedoms' simulation needs at least 2 samples, got {t.size}")
    s, sd, sdd = (np.asarray(a, dtype=float).reshape(len(t), na) for a in (s, sd, sdd))
    data = MechanismData(model)
    path = _hermite(t, s, sd, sdd)
    z = np.zeros((1, nt))
    if x0 is None:
        x0 = _start(model, s[0], reference_task(model))
    if xd0 is None:
        J0 = solve_kinematics(model, np.asarray(x0, dtype=float)[None], z, z).J_ax[0]
        xd0 = np.linalg.lstsq(J0, sd[0], rcond=None)[0]
    a = BAUMGARTE

    def accel(x: Array, xd: Array, tau: float) -> tuple[Array, Array]:
        # one kinematics solve gives M, h, B and the actuated joints' motion (the rates' bias:
        # act_qdd at xdd = 0)
        M, h, B, kin = _all(model, data, x[None], xd[None], None if load is None else np.atleast_1d(load))
        M, h, B = M[0], h[0], B[0]
        J, bias, qa, qad = kin.J_ax[0], kin.act_qdd[0], kin.act_q[0], kin.act_qd[0]
        sp, sdp, sddp = path(tau)
        ref = sddp + 2 * a * (sdp - qad) + a * a * (sp - qa)
        A = np.block([[M, -B], [J, np.zeros((na, na))]])
        sol = np.linalg.solve(A, np.concatenate([-h, ref - bias]))
        return sol[:nt], sol[nt:]

    calls, mark = [0], [float(t[0])]  # evaluations so far; the time at the last check
    least = min(STALL_PROGRESS * float(t[-1] - t[0]), STALL_SECONDS)  # the least advance of a window [s]

    def rhs(tau: float, y: Array) -> Array:
        calls[0] += 1
        if progress is not None and calls[0] % 256 == 0:
            progress(float(tau))
        if calls[0] % STALL_WINDOW == 0:
            if tau - mark[0] < least:
                raise _Stalled(tau, y)
            mark[0] = tau
        try:
            return np.concatenate([y[nt:], accel(y[:nt], y[nt:], tau)[0]])
        except (np.linalg.LinAlgError, PkmdynError) as exc:
            raise MotionError(f"actuator motion: t = {tau:.6g} s: the passive freedoms' simulation stopped "
                              f"({str(exc).split(': ', 1)[-1]})") from None

    try:
        res = solve_ivp(rhs, (t[0], t[-1]), np.concatenate([x0, xd0]), method="DOP853", t_eval=t, rtol=rtol,
                        atol=rtol * 1e-2)
    except _Stalled as exc:
        tau, y = exc.args
        try:
            kin = solve_kinematics(model, y[None, :nt], y[None, nt:], z, q_start=data.last_q())
            where = (f"the task coordinates' inverse singularity measure is "
                     f"{float(singularity_measures(model, kin.q, only='inverse').inverse[0]):.3g} there")
        except PkmdynError as err:
            where = f"the pose there: {str(err).split(': ', 1)[-1]}"
        raise MotionError(f"actuator motion: t = {tau:.6g} s: the passive freedoms' simulation stopped, its steps "
                          f"shrinking (less than {least:.3g} s in {STALL_WINDOW} evaluations); {where} "
                          "(a task whose coordinates stay independent along the motion, e.g. another task body, "
                          "may pass)") from None
    if res.status != 0 or res.y.shape[1] != len(t):
        at = float(res.t[-1]) if res.t.size else float(t[0])
        raise MotionError(f"actuator motion: t = {at:.6g} s: the passive freedoms' simulation stopped "
                          f"({res.message})")
    x, xd = res.y[:nt].T.copy(), res.y[nt:].T.copy()
    # the accelerations sample by sample from the start, warm-started from the sample before (not
    # from the integration's last pose, which may lead Newton onto another assembly branch)
    data = MechanismData(model)
    xdd = np.array([accel(x[i], xd[i], float(t[i]))[0] for i in range(len(t))])
    return TaskMotion(t, x, xd, xdd, {})


def driven_motion(model: MechanismModel, motion: TaskMotion,
                  progress: Callable[[float], None] | None = None) -> TaskMotion:
    """An under-actuated mechanism's motion whose actuated joints follow those of the task
    motion ``motion`` (its inverse kinematics' actuator coordinates, rates and accelerations),
    the passive freedoms simulated (:func:`passive_motion`) from the task motion's first pose
    and rates: the default motion of such a mechanism, which a task motion of its own would not
    be (its efforts exist only where it is dynamically consistent)."""
    kin = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
    return passive_motion(model, motion.t, kin.act_q, kin.act_qd, kin.act_qdd, x0=motion.x[0], xd0=motion.xd[0],
                          progress=progress)

"""The plant integrator: a machine's forward dynamics over one control cycle, efforts held.

Problem. With the efforts ``u`` held (zero-order hold) over a control cycle, integrate

    qd' = f(t, q, qd) = M(q)^-1 (B(q) u - h(q, qd, load(t))),     q' = qd

from the cycle's start to its end in ``substeps`` equal steps ``dt``, the load known at every
step boundary and middle. The only access to the machine is its verbs (:mod:`pkmdyn.machine_protocol`):
the compiled kernel behind ``forward_dynamics_one`` (``one_sample_kernels``, no input checks)
where the machine offers it, else ``forward_dynamics_one`` itself (the fast path), else the
batched ``forward_dynamics`` at ``n = 1``.

Where the ODE is stiff, and where it is not. Regularised Coulomb friction
``F w / sqrt(|w|^2 + eps^2)`` has the slope ``F / eps`` at zero velocity: 4 N m of bearing
friction with ``eps = 1e-3 rad/s`` is a damper of 4000 N m s/rad, and against about 0.1-2
kg m^2 of inertia its time constant is 25 us to 0.5 ms. But the slope falls as ``F / |w|``
away from zero (transverse to a vector friction) and faster along it: the ODE is stiff only
inside the regularisation band, within a few ``eps`` of a stop, and smooth elsewhere. An
explicit method must take steps below the band's time constant inside it; outside, a
higher-order explicit step is far more accurate per evaluation than a second-order implicit
one. So each step is one of two methods:

- **Explicit** where ``dt |d f / d qd|`` is below ``EXPLICIT_LIMIT = 0.5``: by default
  Nystroem's third-order Runge-Kutta method (three evaluations of ``f``; nodes ``0, 2/3, 2/3``,
  ``a21 = a32 = 2/3``, weights ``1/4, 3/8, 3/8``; the load at ``2/3 dt`` by the parabola through
  the step's start, middle and end), or classical RK4 (four evaluations; ``make_work(plant,
  "rk4-ros2")``). Both are stable on the negative real axis down to ``dt lambda = -2.5``
  (-2.79); 0.5 keeps the step well inside, where it is accurate. Whether the step is there is
  read off the step itself, at no extra cost: its stages 2 and 3 sit at the same time and
  (to ``O(dt^2 qdd)``) the same position and differ in velocity by ``2/3 dt (a2 - a1)``
  (RK4: ``dt / 2 (a2 - a1)``), so ``|a3 - a2| / |v3 - v2|`` estimates the slope of ``f`` along
  ``qd`` (stiffness detection as in Hairer & Wanner, Solving ODEs II, section IV.2). A step
  whose estimate reaches the limit is taken again by ROS2.
- **ROS2** (Verwer, Spee, Blom & Hundsdorfer 1999, SIAM J. Sci. Comput. 20) in the band: linearly
  implicit, two evaluations of ``f`` and one linear solve with ``W = I - gamma dt J`` per step,
  L-stable (a sticking phase is damped out in one step, as the exact solution does, instead of
  ringing), of order two **for any** ``J`` (a W-method), so the Jacobian may be approximate.
  ``J = [[0, I], [0, A]]`` with ``A = d f / d qd`` by one-sided finite differences (``nq``
  extra evaluations, velocity increments ``1e-7 (1 + |qd_j|)``, far below any friction
  regularisation scale), without ``d f / d q`` (no stiff springs in these machines): the stiff
  part - friction, through ``qd`` - is exact, the rest costs nothing in order. With
  ``gamma = 1 + 1/sqrt(2)``:

      (I - gamma dt J) k1 = F(t_n, y_n)
      (I - gamma dt J) k2 = F(t_n + dt, y_n + dt k1) - 2 k1
      y_n+1 = y_n + 3/2 dt k1 + 1/2 dt k2

  The steps stay ROS2 while ``dt |A|_inf >= EXPLICIT_LIMIT`` (``A`` is at hand there) and go
  back to RK4 when the motion has left the band. ``A`` does not depend on the held efforts
  (``M^-1 B u`` has no ``qd`` in it) and is evaluated again only when the velocity has moved by
  more than ``JACOBIAN_REUSE`` (5 %) of its size, or the load by more than 5 %.

Velocity reversals. Where friction is sharp, Coulomb friction turns over within
``~eps / |qdd|`` (tens of microseconds) at a reversal: the solution has a near-kink there, a
step that straddles it makes a velocity error of the order of ``dt x (jump of the
acceleration)``, and that error then grows linearly in the position. A step (of either
method) in which any velocity component changes sign is therefore taken again as
``REFINE = 16`` ROS2 steps of ``dt / 16`` (a fixed refinement, not an adaptive collapse:
reversals are a few per cycle, so the cost is small), with a fresh Jacobian at every one in
the band and the reuse rule above outside it. A step in which a component leaves zero (a start
from rest, where friction turns on) or comes to it is refined alike. A velocity smaller than
``REVERSAL_FLOOR = 1e-10`` times the step's largest ``|velocity|`` (or than 1e-10 m/s or
rad/s) counts as zero: a coordinate held at rest by the machine's symmetry has a velocity of
rounding size whose sign is the rounding's, and a step refined or not on that sign made a
run depend on the solvers' warm starts (the PDM's PID run from rest: 2e-4 of its first
step's size one way or the other, 5e-6 rad of its angle gamma after 0.25 s).

Accuracy per cost (``tests/test_simulate.py`` against ``solve_ivp`` Radau at tolerances 1e-10;
docs/control.md). One step per 1 ms cycle on a two-link machine with friction as sharp as a
joint-wear simulator's (Chen, Cheng & Pang 2022), from rest, max position error over 0.15 s: ROS2 alone 4.2e-5 rad (2 evaluations per
step plus its Jacobians, about 3 in all; 9.9e-4 while a start from rest counted as a reversal
only where a velocity left zero downwards), Nystroem/ROS2 2.9e-5, RK4/ROS2 3.0e-5 rad (ROS2
alone stops converging near 3e-6 rad at 0.125 ms steps, the explicit steps do not); with
smooth friction (eps = 0.1 rad/s) 8.1e-5, 9.6e-7 and 5.3e-7 rad. On that simulator's ISO 14242-1 cycle no
step outside the velocity reversals is in the band at 1 ms; the feedforward replay on the
exact plant is off by 3.0e-3 deg with ROS2 alone, 7e-6 deg with Nystroem/ROS2 and 6e-6 deg
with RK4/ROS2, for 3.0, 3.2 and 4.2 evaluations per cycle. Nystroem/ROS2 is the default: the
third order costs what ROS2 costs and leaves the replay error to the zero-order hold.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from .._dense import solve_in_place

__all__ = ["Plant", "make_plant", "make_work", "accelerations", "hold_interval", "ROS2_GAMMA", "METHODS",
           "EXPLICIT_LIMIT"]

Array = NDArray[np.float64]

#: gamma of ROS2 (L-stable, second order for any Jacobian approximation)
ROS2_GAMMA = 1.0 + 1.0 / 2.0**0.5
#: relative velocity increment of the finite-difference Jacobian d f / d qd
FD_STEP = 1e-7
#: the Jacobian is reused while the velocity stays within this fraction of its size
JACOBIAN_REUSE = 0.05
#: sub-steps of a step in which a velocity component reverses
REFINE = 16
#: a velocity component smaller than this times the largest velocity (or than this, in m/s or
#: rad/s) counts as zero when a step is checked for a reversal (:func:`_reversed`)
REVERSAL_FLOOR = 1e-10
#: a step is explicit (third order or RK4) where ``dt |d f / d qd|`` is below this
EXPLICIT_LIMIT = 0.5


@dataclass(frozen=True)
class Plant:
    """The machine being simulated: its verbs, its own model (may differ from the controller's),
    the sizes ``nq``, ``nu`` and ``f(q (nq,), qd (nq,), u (nu,), load) -> qdd (nq,)``,
    the single-sample forward dynamics (fast path) or the batched verb at ``n = 1``."""

    verbs: Any
    model: Any
    nq: int
    nu: int
    has_load: bool
    fast: bool
    f: Callable[[Array, Array, Array, float], Array]
    #: ``(p, forward)`` where ``f`` is the machine's compiled single-sample kernel
    #: ``forward(p, q, qd, u, load, out)`` (``one_sample_kernels``), for a compiled loop; else None
    kernel: Any = None


def make_plant(verbs: Any, model: Any, has_load: bool) -> Plant:
    """Wrap a machine (``verbs`` = its verbs, :class:`pkmdyn.machine_protocol.MachineDynamics`; ``model`` = its plant model).

    ``has_load``: whether the machine takes a load (a force along the motion, as a test rig's hydraulic
    load) or ``None``.
    """
    nq, nu = len(verbs.COORDINATES), len(verbs.ACTUATORS)
    one = getattr(verbs, "forward_dynamics_one", None)
    kernels = getattr(verbs, "one_sample_kernels", None)
    compiled = kernels(model) if one is not None and kernels is not None else None
    if compiled is not None:
        p, _, forward = compiled

        def f(q: Array, qd: Array, u: Array, load: float) -> Array:
            out = np.empty(nq)
            if forward(p, q, qd, u, load if has_load else 0.0, out):
                return one(model, q, qd, u, load if has_load else None)  # raises the machine's error
            return out
    elif one is not None:
        if has_load:
            def f(q: Array, qd: Array, u: Array, load: float) -> Array:
                return one(model, q, qd, u, load)
        else:
            def f(q: Array, qd: Array, u: Array, load: float) -> Array:
                return one(model, q, qd, u, None)
    else:
        batched = verbs.forward_dynamics
        if has_load:
            def f(q: Array, qd: Array, u: Array, load: float) -> Array:
                return batched(model, q[None], qd[None], u[None], np.array([load]))[0]
        else:
            def f(q: Array, qd: Array, u: Array, load: float) -> Array:
                return batched(model, q[None], qd[None], u[None], None)[0]
    return Plant(verbs, model, nq, nu, has_load, one is not None, f,
                 None if compiled is None else (compiled[0], compiled[2]))


def accelerations(plant: Plant, q: Array, qd: Array, u: Array, load: float) -> Array:
    """``qdd (nq,)`` of the plant at one state (``load`` ignored by a machine without one)."""
    return np.asarray(plant.f(q, qd, u, load), dtype=float)


@numba.njit(cache=True)
def _solve_small(W: Array, b: Array, out: Array) -> None:  # pragma: no cover - compiled
    """``out = W^-1 b`` (W is overwritten)."""
    for i in range(b.shape[0]):
        out[i] = b[i]
    solve_in_place(W, out)


@numba.njit(cache=True)
def _copy_matrix(W: Array) -> None:  # pragma: no cover - compiled
    """``W[1] = W[0]`` element by element: the array assignment would compile numba's shape
    mismatch message (string formatting, some 4 s of a cold start) for a case that cannot occur."""
    for i in range(W.shape[1]):
        for j in range(W.shape[2]):
            W[1, i, j] = W[0, i, j]


@numba.njit(cache=True)
def _stage1(q: Array, v: Array, f0: Array, A: Array, dt: float, W: Array, buf: Array) -> None:  # pragma: no cover
    """Form ``W[0] = I - gamma dt A`` and solve stage 1 into ``buf`` (rows: k1q, k1v, q2, v2,
    rhs, k2v, q_n, v_n); ``q2, v2 = y_n + dt k1``."""
    n = q.shape[0]
    g = ROS2_GAMMA * dt
    for i in range(n):
        buf[6, i] = q[i]
        buf[7, i] = v[i]
    for i in range(n):
        for j in range(n):
            W[0, i, j] = -g * A[i, j]
        W[0, i, i] += 1.0
    _copy_matrix(W)
    _solve_small(W[1], f0, buf[1])
    for i in range(n):
        buf[0, i] = v[i] + g * buf[1, i]
        buf[2, i] = q[i] + dt * buf[0, i]
        buf[3, i] = v[i] + dt * buf[1, i]


@numba.njit(cache=True)
def _side(v: float, floor: float) -> int:  # pragma: no cover - compiled
    """-1, 0 or 1: the side of zero ``v`` is on, within ``floor`` of zero counting as zero."""
    return 1 if v > floor else (-1 if v < -floor else 0)


@numba.njit(cache=True)
def _reversed(v0: Array, v1: Array) -> bool:  # pragma: no cover - compiled
    """Whether a velocity component changed its side of zero from ``v0`` to ``v1``: crossed it,
    left it (a start from rest, where friction turns on) or came to it. A velocity smaller
    than ``REVERSAL_FLOOR`` times the largest ``|velocity|`` of the two, or than
    ``REVERSAL_FLOOR`` itself [m/s or rad/s], counts as zero: a coordinate held at rest by
    symmetry has a velocity of rounding size, whose sign is the rounding's."""
    scale = 1.0
    for i in range(v0.shape[0]):
        scale = max(scale, abs(v0[i]), abs(v1[i]))
    floor = REVERSAL_FLOOR * scale
    for i in range(v0.shape[0]):
        if _side(v0[i], floor) != _side(v1[i], floor):
            return True
    return False


@numba.njit(cache=True)
def _stage2(q: Array, v: Array, f2: Array, dt: float, W: Array, buf: Array) -> bool:  # pragma: no cover
    """Solve stage 2 and advance ``q, v`` in place; whether a velocity component reversed
    (:func:`_reversed`)."""
    n = q.shape[0]
    g = ROS2_GAMMA * dt
    for i in range(n):
        buf[4, i] = f2[i] - 2.0 * buf[1, i]
    _copy_matrix(W)
    _solve_small(W[1], buf[4], buf[5])
    for i in range(n):
        k2q = buf[3, i] - 2.0 * buf[0, i] + g * buf[5, i]
        q[i] += dt * (1.5 * buf[0, i] + 0.5 * k2q)
        v[i] += dt * (1.5 * buf[1, i] + 0.5 * buf[5, i])
    return _reversed(buf[7], v)


class _Work:
    """Preallocated buffers of one integration (no allocation per step)."""

    def __init__(self, n: int) -> None:
        self.A = np.empty((n, n))
        self.W = np.empty((2, n, n))
        self.vp = np.empty(n)
        self.buf = np.empty((8, n))
        self.q2 = self.buf[2]
        self.v2 = self.buf[3]
        self.rows = tuple(self.buf[i] for i in range(8))  # views, made once
        self.old = self.buf[6:8]
        self.qd_A = np.full(n, np.nan)
        self.ld_A = 0.0
        self.fresh = False
        self.explicit = True
        self.stiff = False
        self.explicit_steps = 0
        self.refined_steps = 0


#: the step methods of :func:`make_work` (the first is the default)
METHODS = ("rk3-ros2", "rk4-ros2", "ros2")


def make_work(plant: Plant, method: str = "rk3-ros2") -> _Work:
    """Buffers for :func:`hold_interval` (one set per simulation). ``method``: ``"rk3-ros2"``
    (Nystroem's third-order step where the motion is smooth, ROS2 in the friction band; the
    default), ``"rk4-ros2"`` (the same with classical RK4) or ``"ros2"`` (every step ROS2)."""
    if method not in METHODS:
        raise ValueError(f"integration method {method!r}: unknown (known: {', '.join(METHODS)})")
    w = _Work(plant.nq)
    w.explicit = method != "ros2"
    w.step = _rk3_step if method == "rk3-ros2" else _rk4_step
    return w


def _jacobian(plant: Plant, q: Array, qd: Array, u: Array, ld: float, f0: Array, w: _Work) -> None:
    """``A = d f / d qd`` by one-sided differences into ``w.A``; remembers the velocity."""
    f = plant.f
    A, vp = w.A, w.vp
    for c in range(plant.nq):
        d = FD_STEP * (1.0 + abs(qd[c]))
        vp[:] = qd
        vp[c] += d
        A[:, c] = (f(q, vp, u, ld) - f0) / d
    w.qd_A[:] = qd
    w.ld_A = ld
    w.fresh = True


@numba.njit(cache=True)
def _stale(qd: Array, qd_A: Array, rel: float) -> bool:  # pragma: no cover - compiled
    """Whether the velocity moved by more than ``rel`` of its size since the Jacobian."""
    d = 0.0
    v = 0.0
    for i in range(qd.shape[0]):
        d += (qd[i] - qd_A[i]) ** 2
        v += qd_A[i] ** 2
    return not (d <= rel * rel * v)


def _ros2_step(plant: Plant, q: Array, qd: Array, u: Array, ld0: float, ld1: float, dt: float, w: _Work,
               force_jacobian: bool = False, f0: Array | None = None) -> bool:
    """One ROS2 step of ``dt`` in place (loads at the step's two ends); returns whether a
    velocity component reversed (:func:`_reversed`; the state before the step is kept in
    ``w.buf[6:8]``). ``f0``: ``f`` at the step's start if already evaluated."""
    f = plant.f
    if f0 is None:
        f0 = f(q, qd, u, ld0)
    if force_jacobian or _stale(qd, w.qd_A, JACOBIAN_REUSE) or abs(ld0 - w.ld_A) > JACOBIAN_REUSE * abs(w.ld_A):
        _jacobian(plant, q, qd, u, ld0, f0, w)
    else:
        w.fresh = False
    _stage1(q, qd, f0, w.A, dt, w.W, w.buf)
    f2 = f(w.q2, w.v2, u, ld1)
    return _stage2(q, qd, f2, dt, w.W, w.buf)


@numba.njit(cache=True)
def _stiffness(A: Array) -> float:  # pragma: no cover - compiled
    """``max_i sum_j |A_ij|`` (the infinity norm, a bound on the spectral radius of ``A``)."""
    n = A.shape[0]
    r = 0.0
    for i in range(n):
        s = 0.0
        for j in range(n):
            s += abs(A[i, j])
        r = max(r, s)
    return r


@numba.njit(cache=True)
def _rk_stage(q: Array, v: Array, kq: Array, kv: Array, h: float, out_q: Array,
              out_v: Array) -> None:  # pragma: no cover - compiled
    """``out_q = q + h kq``, ``out_v = v + h kv``."""
    for i in range(q.shape[0]):
        out_q[i] = q[i] + h * kq[i]
        out_v[i] = v[i] + h * kv[i]


@numba.njit(cache=True)
def _rk_finish(q: Array, v: Array, a1: Array, a2: Array, a3: Array, a4: Array, h: float,
               old: Array) -> tuple[bool, float]:  # pragma: no cover - compiled
    """Advance ``q, v`` in place by the classical RK4 weights for ``q' = v, v' = a`` (stage
    velocities ``v, v + h/2 a1, v + h/2 a2, v + h a3``); keeps the old state in ``old[0:2]``.
    Returns whether a velocity component reversed (:func:`_reversed`) and the stiffness
    estimate ``|a3 - a2| / |v3 - v2|`` (max norms; stages 2 and 3 differ by ``h/2 (a2 - a1)``
    in the velocity), 0 where that difference is below rounding."""
    n = q.shape[0]
    da = 0.0
    dv = 0.0
    vs = 0.0
    for i in range(n):
        old[0, i] = q[i]
        old[1, i] = v[i]
        q[i] += h * v[i] + h * h / 6.0 * (a1[i] + a2[i] + a3[i])
        vn = v[i] + h / 6.0 * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i])
        da = max(da, abs(a3[i] - a2[i]))
        dv = max(dv, 0.5 * h * abs(a2[i] - a1[i]))
        vs = max(vs, abs(v[i]))
        v[i] = vn
    rev = _reversed(old[1], v)
    if dv <= 1e-12 * (1.0 + vs):
        return rev, 0.0
    return rev, da / dv


@numba.njit(cache=True)
def _rk3_finish(q: Array, v: Array, a1: Array, a2: Array, a3: Array, h: float,
                old: Array) -> tuple[bool, float]:  # pragma: no cover - compiled
    """Advance ``q, v`` in place by Nystroem's third-order weights ``(1/4, 3/8, 3/8)`` for
    ``q' = v, v' = a`` (stage velocities ``v, v + 2h/3 a1, v + 2h/3 a2``); keeps the old state
    in ``old[0:2]``. Returns whether a velocity component reversed (:func:`_reversed`) and the
    stiffness estimate ``|a3 - a2| / |v3 - v2|`` (stages 2 and 3 differ by ``2h/3 (a2 - a1)``
    in the velocity; 0 where that difference is below rounding)."""
    n = q.shape[0]
    da = 0.0
    dv = 0.0
    vs = 0.0
    for i in range(n):
        old[0, i] = q[i]
        old[1, i] = v[i]
        q[i] += h * v[i] + 0.25 * h * h * (a1[i] + a2[i])
        vn = v[i] + h * (0.25 * a1[i] + 0.375 * (a2[i] + a3[i]))
        da = max(da, abs(a3[i] - a2[i]))
        dv = max(dv, 2.0 / 3.0 * h * abs(a2[i] - a1[i]))
        vs = max(vs, abs(v[i]))
        v[i] = vn
    rev = _reversed(old[1], v)
    if dv <= 1e-12 * (1.0 + vs):
        return rev, 0.0
    return rev, da / dv


def _rk3_step(plant: Plant, q: Array, qd: Array, u: Array, ld0: float, ldm: float, ld1: float, dt: float, w: _Work,
              f0: Array) -> tuple[bool, float]:
    """One third-order Nystroem step of ``dt`` in place (``c = 0, 2/3, 2/3``; the load at
    ``2/3 dt`` by the parabola through the start, middle and end); see :func:`_rk3_finish`."""
    f = plant.f
    q2, v2, q3, v3 = w.rows[2:6]
    h3 = 2.0 / 3.0 * dt
    l23 = (-ld0 + 8.0 * ldm + 2.0 * ld1) / 9.0
    _rk_stage(q, qd, qd, f0, h3, q2, v2)            # q + 2h/3 v, v + 2h/3 a1
    a2 = f(q2, v2, u, l23)
    _rk_stage(q, qd, v2, a2, h3, q3, v3)            # q + 2h/3 (v + 2h/3 a1), v + 2h/3 a2
    a3 = f(q3, v3, u, l23)
    return _rk3_finish(q, qd, f0, a2, a3, dt, w.old)


def _rk4_step(plant: Plant, q: Array, qd: Array, u: Array, ld0: float, ldm: float, ld1: float, dt: float, w: _Work,
              f0: Array) -> tuple[bool, float]:
    """One classical RK4 step of ``dt`` in place (loads at the start, middle and end; ``f0`` =
    ``f`` at the start); returns whether a velocity component reversed (:func:`_reversed`) and
    the stiffness estimate of :func:`_rk_finish` (the state before the step is kept in
    ``w.buf[6:8]``)."""
    f = plant.f
    q4, v4, q2, v2, q3, v3 = w.rows[:6]
    h2 = 0.5 * dt
    _rk_stage(q, qd, qd, f0, h2, q2, v2)            # q + h/2 v, v + h/2 a1
    a2 = f(q2, v2, u, ldm)
    _rk_stage(q, qd, v2, a2, h2, q3, v3)            # q + h/2 (v + h/2 a1), v + h/2 a2
    a3 = f(q3, v3, u, ldm)
    _rk_stage(q, qd, v3, a3, dt, q4, v4)            # q + h (v + h/2 a2), v + h a3
    a4 = f(q4, v4, u, ld1)
    return _rk_finish(q, qd, f0, a2, a3, a4, dt, w.old)


def hold_interval(plant: Plant, q: Array, qd: Array, u: Array, loads: Array, dt: float, work: _Work) -> None:
    """Advance ``q, qd (nq,)`` **in place** over ``n = (len(loads) - 1) / 2`` steps of ``dt`` with
    the efforts ``u (nu,)`` held; ``loads (2 n + 1,)`` are the load [N] at the step boundaries
    and middles, ``t_0 + j dt / 2`` (zeros for a machine without load).

    Each step (module docstring) is explicit (third-order Nystroem or RK4, per
    :func:`make_work`) while the friction's slope ``dt |d f / d qd|`` estimated from the step's
    stages stays below ``EXPLICIT_LIMIT``, else ROS2 (retaken, and kept while ``dt |A|`` of its
    Jacobian stays at or above the limit); a step in which a velocity component reverses
    is taken again as ``REFINE`` ROS2 steps of ``dt / REFINE`` (fresh Jacobians in the band).
    ``make_work(plant, "ros2")`` takes every step by ROS2."""
    w = work
    f = plant.f
    n = (loads.shape[0] - 1) // 2
    for j in range(n):
        l0, lm, l1 = loads[2 * j], loads[2 * j + 1], loads[2 * j + 2]
        f0 = f(q, qd, u, l0)
        rev = False
        if w.explicit and not w.stiff:
            rev, rho = w.step(plant, q, qd, u, l0, lm, l1, dt, w, f0)
            if dt * rho >= EXPLICIT_LIMIT:  # entered the friction band: retake by ROS2
                w.stiff = True
                rev = False
                q[:] = w.rows[6]
                qd[:] = w.rows[7]
            elif not rev:
                w.explicit_steps += 1
        if not w.explicit or w.stiff:
            rev = _ros2_step(plant, q, qd, u, l0, l1, dt, w, f0=f0)
            w.stiff = dt * _stiffness(w.A) >= EXPLICIT_LIMIT
        if rev:
            w.refined_steps += 1
            q[:] = w.rows[6]
            qd[:] = w.rows[7]
            h = dt / REFINE
            fresh = w.stiff or not w.explicit
            for r in range(REFINE):
                la = _piecewise(l0, lm, l1, r / REFINE)
                lb = _piecewise(l0, lm, l1, (r + 1) / REFINE)
                _ros2_step(plant, q, qd, u, la, lb, h, w, force_jacobian=fresh)
            w.stiff = dt * _stiffness(w.A) >= EXPLICIT_LIMIT


@numba.njit(cache=True)
def _piecewise(l0: float, lm: float, l1: float, x: float) -> float:  # pragma: no cover - compiled
    """The load at the fraction ``x`` of a step, linear through its start, middle and end."""
    if x <= 0.5:
        return l0 + (lm - l0) * (2.0 * x)
    return lm + (l1 - lm) * (2.0 * x - 1.0)

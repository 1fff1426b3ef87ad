"""The fastest timing of a geometric path: time-optimal path parameterisation (TOPP) by
reachability analysis, with the joints' friction as :mod:`pkmdyn.multibody.dynamics` computes it.

**The path** ``x(s)``, ``s`` in [0, 1]: the task coordinates (``model.task_names``) through
given rows, an interpolating spline over the row number (quintic from 6 rows, cubic from 4,
else linear: :func:`task_path`). Along it ``xd = x' sd``, ``xdd = x' sdd + x'' sd^2``.

**Limits, linear in (sdd, sd^2).** With ``u = sdd`` and ``v = sd^2``, every quantity the
Newton-Euler equations give without friction is ``a(s) u + b(s) v + c(s)``: the actuated
joints' efforts (Eq. 3 of docs/multibody_dynamics.md), every joint's reaction, the actuated
joints' and motors' accelerations, the motors' efforts (Eq. A1 without their friction); ``a``,
``b`` and ``c`` come from three solves of the kinematics and dynamics at the grid's poses
(``xd = 0, xdd = x'``; ``xd = x', xdd = x''``; at rest). Speeds are ``k(s) sd`` and bound
``v <= (limit / |k|)^2``. Bounds (:class:`RetimeLimits`): each actuated joint's effort, each
drive's motor effort (``max_torque_Nm`` / ``max_force_N``), speed and acceleration of its
``[[actuators]]`` entry, the actuated joints' and task coordinates' speed and acceleration limits
of the description's ``[limits]`` (``max_joint_speed_*``, ``max_task_acceleration_*``, ...), and
optionally each joint's reaction force and moment magnitude.

**Friction** (every joint's, load-dependent friction included, and the motors'): evaluated on
the reactions of the previous timing and held fixed while the next timing is computed (the
iteration starts without friction); a reaction magnitude's bound ``|F| <= F_max`` is the linear
``d . F <= F_max`` along the previous timing's direction ``d`` of ``F``, exact once the timing
settles. **Stopping rule**: the largest change of ``sd`` over the grid at most ``1e-9`` of its
largest value, or at most ``1e-6`` with every bound met to ``1 + 1e-9`` at the new timing with
its own friction and reaction directions (a fixed point that cycles in its last digits); one
pass without friction and reaction bounds; at most ``max_iter`` passes.

**Reachability analysis** (Pham & Pham, "A new approach to time-optimal path parameterization
based on reachability analysis", IEEE T-RO 34(3), 2018): on the grid ``s_0 .. s_N`` (``N =
points - 1`` equal steps ``D``), ``v_{i+1} = v_i + 2 D u_i`` and the limits hold at every grid
point for ``(u_i, v_i)``. Backward, the controllable sets ``K_i = [lo_i, hi_i]`` (the speeds
from which the rest of the path can be followed and the end reached at rest, ``K_N = {0}``):
two linear programs in ``(u, v)`` per point (HiGHS, ``highspy``), ``max`` and ``min v`` within
point ``i``'s limits with ``v + 2 D u`` in ``K_{i+1}``. Forward from rest, the greatest ``u_i``
within point ``i``'s limits that keeps ``v_{i+1}`` in ``K_{i+1}`` (an interval in ``u``). The
time is ``t_{i+1} - t_i = 2 D / (sd_i + sd_{i+1})``.

Every result is checked by the caller independently: the timed motion through the same
inverse dynamics as ``pkmdyn run`` (:func:`limit_use`). The least-energy timing within a cycle
time, on the same grid and limits, is :mod:`pkmdyn.multibody.analyses.retime_energy`."""

from __future__ import annotations

import os
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import LimitError, MotionError, ParameterError, PkmdynError
from ..dynamics.actuators import effective_limits, motor_efforts, motor_friction
from ..dynamics.newton_euler import fr_any, joint_reactions
from ..kinematics.inverse import solve_kinematics
from ..kinematics.motion import TaskMotion
from ..model.compiler import MechanismModel

__all__ = ["LimitUse", "RetimeLimits", "Retiming", "TaskPath", "copper_coefficients", "limit_use", "retime", "task_path",
           "timing_energy"]

Array = NDArray[np.float64]

#: the stopping rule (module docstring): the change of sd, relative to its largest value, at
#: which the passes stop; or at which they stop where every bound is met to ``MET`` at the
#: timing with its own friction and reaction directions
SETTLED = 1e-9
CLOSE = 1e-6
MET = 1e-9


@dataclass(frozen=True)
class RetimeLimits:
    """Bounds beyond the description's own: ``effort (na,)`` on each actuated joint's effort [N
    or N m, the joint's unit]; ``reaction_force (nj,)`` [N] and ``reaction_moment (nj,)`` [N m] on
    each joint's reaction magnitude (``model.joint_names`` order); ``inf`` where none.
    ``overrides``: the description's ``[limits]`` replaced (``--limit KEY=VALUE``)."""

    effort: Array
    reaction_force: Array
    reaction_moment: Array
    overrides: dict

    @staticmethod
    def none(model: MechanismModel) -> RetimeLimits:
        nj = len(model.joint_names)
        return RetimeLimits(np.full(model.na, np.inf), np.full(nj, np.inf), np.full(nj, np.inf), {})


@dataclass(frozen=True)
class TaskPath:
    """A geometric path of the task coordinates: ``rows (m, nt)`` the given points and the
    spline through them over ``s = row / (m - 1)``."""

    rows: Array
    spline: Any

    def at(self, s: Array) -> tuple[Array, Array, Array]:
        """``x, x', x''`` (n, nt) at ``s`` (n,)."""
        return self.spline(s), self.spline(s, 1), self.spline(s, 2)


def task_path(model: MechanismModel, rows: Array, what: str = "path") -> TaskPath:
    """The spline through the path's rows ``(m, nt)`` (module docstring); a row equal to the one
    before it (the path would stop there) is refused naming it (counted from 1, after the header)."""
    from scipy.interpolate import make_interp_spline

    X = np.asarray(rows, dtype=float)
    if X.ndim != 2 or X.shape[1] != model.nt:
        raise MotionError(f"{what}: expected {model.nt} task columns per row, got shape {X.shape}")
    if X.shape[0] < 2:
        raise MotionError(f"{what}: a path needs at least 2 rows, got {X.shape[0]}")
    if not np.all(np.isfinite(X)):
        raise MotionError(f"{what}: row {int(np.flatnonzero(~np.isfinite(X).all(axis=1))[0]) + 1}: not a finite number")
    step = np.abs(np.diff(X, axis=0)).max(axis=1)
    scale = max(1.0, float(np.abs(X).max()))
    same = np.flatnonzero(step <= 1e-12 * scale)
    if same.size:
        r = int(same[0]) + 2
        raise MotionError(f"{what}: row {r} repeats row {r - 1} (a path's rows must differ: the timing of a "
                          "path that stays put is not defined)")
    m = X.shape[0]
    k = 5 if m >= 6 else 3 if m >= 4 else 1
    return TaskPath(X, make_interp_spline(np.linspace(0.0, 1.0, m), X, k=k))


@dataclass(frozen=True)
class Retiming:
    """The time-optimal timing of a path: at the grid's points ``s (N+1,)``, the times ``t``
    [s], ``sd``, ``sdd`` [1/s, 1/s^2], the task motion ``x, xd, xdd (N+1, nt)``; ``sd_limit``
    the bound of the speed limits alone and ``sd_reach`` the controllable sets' upper bound
    (``inf`` where no bound acts); ``iterations`` the passes (friction and reaction directions);
    ``bounds`` the names of the acceleration-type bounds in force."""

    s: Array
    t: Array
    sd: Array
    sdd: Array
    x: Array
    xd: Array
    xdd: Array
    sd_limit: Array
    sd_reach: Array
    iterations: int
    bounds: tuple[str, ...]

    @property
    def cycle_time(self) -> float:
        return float(self.t[-1])

    def motion(self) -> TaskMotion:
        """The timed motion (a motion file's rows: positions, rates and accelerations given)."""
        return TaskMotion(self.t, self.x, self.xd, self.xdd, {})


def _kin(model: MechanismModel, x: Array, xd: Array, xdd: Array, q_start: Array | None = None) -> Any:
    """The kinematics on the grid; the engine's errors say which grid point (its sample)."""
    try:
        return solve_kinematics(model, x, xd, xdd, None, q_start=q_start)
    except PkmdynError as e:
        raise type(e)(f"path (grid point = sample): {e}") from None


def _values(model: MechanismModel, kin: Any, reac: Any, limits: RetimeLimits, lim: dict, motor_friction_on: bool
            ) -> list[tuple[str, Array, float]]:
    """Every acceleration-type bound's quantity along ``kin`` with the efforts and reactions
    ``reac``: (name, value (n,) or a reaction's (n, 3), bound), bounds finite only."""
    out: list[tuple[str, Array, float]] = []

    def add(name: str, value: Array, bound: float) -> None:
        if np.isfinite(bound):
            out.append((name, value, float(bound)))

    k = model.drive_ratio
    for i, joint in enumerate(model.actuator_names):
        unit = model.actuator_units[i]
        add(f"effort of {joint} [{'N' if unit == 'm' else 'N m'}]", reac.u[:, i], limits.effort[i])
        add(f"acceleration of {joint} [{unit}/s^2] (max_joint_acceleration_{unit}_s2)", kin.act_qdd[:, i],
            lim[f"max_joint_acceleration_{unit}_s2"])
        if model.drive_name[i] is not None:
            mu, name = model.motor_units[i], model.drive_name[i]
            effort = reac.u[:, i] / k[i] + model.drive_rotor[i] * k[i] * kin.act_qdd[:, i]
            if motor_friction_on:
                effort = effort + motor_friction(model, kin.act_qd * k)[:, i]
            add(f"motor effort of {name} [{'N m' if mu == 'rad' else 'N'}] ([[actuators]] "
                f"{'max_torque_Nm' if mu == 'rad' else 'max_force_N'})", effort, model.drive_max_effort[i])
            add(f"motor acceleration of {name} [{mu}/s^2] ([[actuators]] max_acceleration_{mu}_s2)",
                k[i] * kin.act_qdd[:, i], model.drive_max_acceleration[i])
    for j, (nm, unit) in enumerate(zip(model.task_names, model.task_units)):
        add(f"task acceleration {nm} [{unit}/s^2] (max_task_acceleration_{unit}_s2)", kin.xdd[:, j],
            lim[f"max_task_acceleration_{unit}_s2"])
    for j, joint in enumerate(model.joint_names):
        add(f"reaction force of {joint} [N]", reac.joint_force[:, j], limits.reaction_force[j])
        add(f"reaction moment of {joint} [N m]", reac.joint_moment[:, j], limits.reaction_moment[j])
    return out


def _speeds(model: MechanismModel, kin: Any, lim: dict) -> list[tuple[str, Array, float]]:
    """Every speed bound's quantity along ``kin``: (name, value (n,), bound)."""
    out = []
    for i, joint in enumerate(model.actuator_names):
        unit = model.actuator_units[i]
        out.append((f"speed of {joint} [{unit}/s] (max_joint_speed_{unit}_s)", kin.act_qd[:, i],
                    float(lim[f"max_joint_speed_{unit}_s"])))
        if model.drive_name[i] is not None and np.isfinite(model.drive_max_speed[i]):
            mu = model.motor_units[i]
            out.append((f"motor speed of {model.drive_name[i]} [{mu}/s] ([[actuators]] max_speed_{mu}_s)",
                        model.drive_ratio[i] * kin.act_qd[:, i], float(model.drive_max_speed[i])))
    for j, (nm, unit) in enumerate(zip(model.task_names, model.task_units)):
        out.append((f"task speed {nm} [{unit}/s] (max_task_speed_{unit}_s)", kin.xd[:, j],
                    float(lim[f"max_task_speed_{unit}_s"])))
    return out


def _moving(v: Array) -> Array:
    """``v`` with each zero (the path at rest) replaced by its larger neighbour's value."""
    out = v.copy()
    rest = np.flatnonzero(v <= 0.0)
    for i in rest:
        out[i] = max(v[i - 1] if i > 0 else 0.0, v[i + 1] if i + 1 < len(v) else 0.0)
    return out


def _project(v: Array, d: Array) -> Array:
    return v if v.ndim == 1 else np.einsum("ij,ij->i", v, d)


#: the largest sd^2 a point's limits may leave unbounded (no limit acts there)
V_CAP = 1e16


def _highs(highspy: Any) -> Any:
    """A HiGHS instance; the banner HiGHS prints on standard output when the process makes its
    first one is kept off the command's output (standard output's descriptor pointed at the null
    device meanwhile)."""
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_RDWR)
    try:
        os.dup2(null, 1)
        return highspy.Highs()
    finally:
        os.dup2(saved, 1)
        os.close(saved)
        os.close(null)


class _Lp:
    """One small linear program in ``(u, v)`` re-filled per grid point (HiGHS): rows ``lo <= a u
    + b v <= hi`` and the transition row ``v + 2 D u`` in ``K_{i+1}``."""

    def __init__(self, r: int, D: float) -> None:
        import highspy

        self.h = h = _highs(highspy)
        h.setOptionValue("output_flag", False)
        h.setOptionValue("presolve", "off")
        h.setOptionValue("primal_feasibility_tolerance", 1e-10)
        h.setOptionValue("dual_feasibility_tolerance", 1e-10)
        self.inf = highspy.kHighsInf
        self.status = highspy.HighsModelStatus
        h.addVars(2, np.array([-self.inf, 0.0]), np.array([self.inf, V_CAP]))
        self.r = r
        starts = np.arange(0, 2 * (r + 1), 2, dtype=np.int32)
        idx = np.tile(np.array([0, 1], dtype=np.int32), r + 1)
        vals = np.ones(2 * (r + 1))
        vals[2 * r] = 2.0 * D
        h.addRows(r + 1, np.full(r + 1, -self.inf), np.full(r + 1, self.inf), 2 * (r + 1), starts, idx, vals)
        self.rows = np.arange(r + 1, dtype=np.int32)

    def set(self, a: Array, b: Array, lo: Array, hi: Array, klo: float, khi: float, vmax: float) -> None:
        h = self.h
        for j in range(self.r):
            h.changeCoeff(j, 0, float(a[j]))
            h.changeCoeff(j, 1, float(b[j]))
        h.changeRowsBounds(self.r + 1, self.rows, np.append(lo, klo), np.append(hi, khi))
        h.changeColBounds(1, 0.0, float(min(vmax, V_CAP)))

    def extreme(self, sign: float) -> float | None:
        """``max v`` (sign -1) or ``min v`` (sign +1) within the rows; None where infeasible."""
        h = self.h
        h.changeColCost(0, 0.0)
        h.changeColCost(1, sign)
        h.run()
        st = h.getModelStatus()
        if st == self.status.kOptimal:
            return float(h.getSolution().col_value[1])
        if st in (self.status.kInfeasible,):
            return None
        if st == self.status.kUnbounded and sign < 0:
            return V_CAP
        # anything else: solve again from scratch once
        h.clearSolver()
        h.run()
        if h.getModelStatus() == self.status.kOptimal:
            return float(h.getSolution().col_value[1])
        return None


def _interval(a: Array, b: Array, lo: Array, hi: Array, v: float) -> tuple[float, float]:
    """The interval of ``u`` with ``lo <= a u + b v <= hi`` for rows with ``a != 0``."""
    ul, uh = -np.inf, np.inf
    big = np.abs(a) > 1e-300
    if np.any(big):
        p, q = (lo[big] - b[big] * v) / a[big], (hi[big] - b[big] * v) / a[big]
        ul = float(np.max(np.minimum(p, q)))
        uh = float(np.min(np.maximum(p, q)))
    return ul, uh


def _held_still(point: int, s: float, names: list[str], C: Array, L: Array) -> LimitError | None:
    """The error where holding the mechanism still at grid point ``point`` breaks a bound (its
    weight and springs beyond an effort bound): the path cannot start or end at rest there."""
    use = np.abs(C) / L
    if use.size and use.max() > 1.0:
        j = int(np.argmax(use))
        return LimitError(f"path point {point} (s = {s:.6g}): {names[j]} is {C[j]:.6g} holding the mechanism still "
                          f"there, beyond its bound {L[j]:.6g}: no timing meets the limits (raise the bound or "
                          "change the path)")
    return None


def _topp(names: list[str], A: Array, B: Array, C: Array, L: Array, vmax: Array, s: Array,
          C2: Array | None = None) -> tuple[Array, Array, Array]:
    """One reachability pass (module docstring) on the rows ``|A u + B v + C| <= L`` (n, r),
    and ``|A u + B v + C2| <= L`` too where ``C2`` is given: ``v, u`` (n,) and the controllable
    sets' upper bounds (n,)."""
    n, r = A.shape
    D = float(s[1] - s[0])
    a, b = A / L, B / L
    C2 = C if C2 is None else C2
    lo, hi = -1.0 - np.minimum(C, C2) / L, 1.0 - np.maximum(C, C2) / L
    for end in (0, n - 1):
        err = _held_still(end, s[end], names, C[end], L)
        if err is not None:
            raise err
    if np.any(vmax <= 0.0):
        i = int(np.flatnonzero(vmax <= 0.0)[0])
        raise LimitError(f"path point {i} (s = {s[i]:.6g}): the speed limits leave the path no speed there")
    lp = _Lp(r, D)
    klo, khi = np.zeros(n), np.zeros(n)
    for i in range(n - 2, -1, -1):
        lp.set(a[i], b[i], lo[i], hi[i], klo[i + 1], khi[i + 1], vmax[i])
        top = lp.extreme(-1.0)
        bottom = lp.extreme(1.0) if top is not None else None
        if top is None or bottom is None:
            raise _held_still(i, s[i], names, C[i], L) or LimitError(
                f"path point {i} (s = {s[i]:.6g}): from there no timing within the limits reaches the path's end at "
                "rest (the limits cannot stop the motion in time, or "
                f"{' and '.join(names[j] for j in np.argsort(-np.abs(C[i]) / L)[:2])} cannot be met together)")
        khi[i], klo[i] = top, max(0.0, bottom)
    if klo[0] > 1e-12 * max(1.0, khi[0]):
        raise LimitError(f"path point 0 (s = 0): the path cannot be started from rest within the limits "
                         f"(the least speed that can go on is sd = {np.sqrt(klo[0]):.6g} 1/s)")
    v, u = np.zeros(n), np.zeros(n)
    for i in range(n - 1):
        uh = _interval(a[i], b[i], lo[i], hi[i], v[i])[1]
        th = (khi[i + 1] - v[i]) / (2 * D)
        ui = min(uh, th)
        if not np.isfinite(ui):
            ui = th
        nxt = min(max(v[i] + 2 * D * ui, klo[i + 1], 0.0), khi[i + 1])
        u[i] = (nxt - v[i]) / (2 * D)
        v[i + 1] = nxt
    v[-1] = 0.0
    ul, uh = _interval(a[-1], b[-1], lo[-1], hi[-1], 0.0)
    u[-1] = min(max(u[-2], ul), uh) if np.isfinite(ul) or np.isfinite(uh) else u[-2]
    return v, u, khi


@dataclass(frozen=True)
class _Grid:
    """The path on its grid and the limits' linear parts (module docstring): ``s, x, x1, x2``
    (the poses and the path's first two derivatives), ``q0`` the first pose's joint coordinates
    (every solve starts from it), the bounds' ``names``, values ``Lb``, parts ``Av, Bv, Cv``
    (each (n,) or a reaction's (n, 3)), ``vmax`` the speed limits' bound on ``v``."""

    model: MechanismModel
    limits: RetimeLimits
    lim: dict
    friction: bool
    s: Array
    x: Array
    x1: Array
    x2: Array
    q0: Array
    names: tuple[str, ...]
    Lb: Array
    Av: list
    Bv: list
    Cv: list
    vmax: Array
    has_fric: bool
    vector: bool
    #: the motor efforts' parts (Eq. A1 without the motors' and joints' friction): ``M[0] u +
    #: M[1] v + M[2]``, each (n, na)
    M: tuple[Array, Array, Array]

    @property
    def D(self) -> float:
        return float(self.s[1] - self.s[0])

    def start(self) -> tuple[list, list]:
        """The friction (none) and reaction directions (the weight's) of the first pass."""
        F = [np.zeros_like(c) for c in self.Cv]
        d = []
        for c in self.Cv:
            if c.ndim == 1:
                d.append(None)
                continue
            mag = np.linalg.norm(c, axis=-1, keepdims=True)
            d.append(np.where(mag > 0, c / np.maximum(mag, 1e-300), [1.0, 0.0, 0.0]))
        return F, d

    def rows(self, F: list, d: list, rest: Array | None) -> tuple[Array, Array, Array, Array]:
        """``A, B, C`` (n, r) of the rows ``|A u + B v + C| <= Lb`` with the friction ``F`` and
        reaction directions ``d``, and ``C2``: ``C`` where the path moves, without friction at
        the points ``rest`` (at rest the regularised friction is zero)."""
        r = len(self.names)
        if not r:
            z = np.zeros((len(self.s), 0))
            return z, z, z, z
        A = np.stack([_project(self.Av[j], d[j]) for j in range(r)], axis=1)
        B = np.stack([_project(self.Bv[j], d[j]) for j in range(r)], axis=1)
        C = np.stack([_project(self.Cv[j] + F[j], d[j]) for j in range(r)], axis=1)
        C2 = C.copy()
        if rest is not None and np.any(rest):
            C0 = np.stack([_project(self.Cv[j], d[j]) for j in range(r)], axis=1)
            C2[rest] = C0[rest]
        return A, B, C, C2

    def motion(self, u: Array, v: Array) -> tuple[Array, Array]:
        """``xd, xdd`` of the timing ``(u, v)`` (``v >= 0``)."""
        return self.x1 * np.sqrt(v)[:, None], self.x1 * u[:, None] + self.x2 * v[:, None]

    def solve(self, u: Array, v: Array) -> tuple[Any, Any]:
        """The kinematics and the efforts and reactions (the friction included) of ``(u, v)``."""
        xd, xdd = self.motion(u, v)
        kt = _kin(self.model, self.x, xd, xdd, self.q0)
        return kt, joint_reactions(self.model, kt, friction=self.friction)

    def friction_at(self, u: Array, v: Array, d: list) -> tuple[list, list, float, Any, Any]:
        """The friction and reaction directions of the timing ``(u, v)``, the largest use of a
        bound there with its own friction, and the solve they come from (kinematics, efforts and
        reactions). Where the path is at rest, the friction is that of the motion leaving or
        reaching it (the neighbouring point's speed): the friction a grid step starting from
        rest meets at once."""
        ve = _moving(v)
        kt, reac = self.solve(u, ve)
        full = _values(self.model, kt, reac, self.limits, self.lim, self.friction)
        F, dn = [], []
        worst = 0.0
        for j in range(len(self.names)):
            Av, Bv, Cv = self.Av[j], self.Bv[j], self.Cv[j]
            uu, vv, vn = (u, ve, v) if Av.ndim == 1 else (u[:, None], ve[:, None], v[:, None])
            Fj = full[j][1] - (Av * uu + Bv * vv + Cv)
            val = Av * uu + Bv * vn + Cv + Fj
            F.append(Fj)
            worst = max(worst, float(np.max(np.abs(val) if val.ndim == 1 else np.linalg.norm(val, axis=-1))) / self.Lb[j])
            if d[j] is None:
                dn.append(None)
            else:  # the direction at the timing itself (at rest: the weight's)
                mag = np.linalg.norm(val, axis=-1, keepdims=True)
                dn.append(np.where(mag > 0, val / np.maximum(mag, 1e-300), d[j]))
        return F, dn, worst, kt, reac


def _grid(model: MechanismModel, path: TaskPath, points: int, limits: RetimeLimits | None, friction: bool) -> _Grid:
    if not 3 <= points <= 1_000_000:
        raise ParameterError(f"points: {points} is not between 3 and 1,000,000")
    if model.na > model.nt and (model.act_distribution == "minimax" or model.act_preload):
        raise ParameterError(f"{model.name}: [actuation]: retiming takes the efforts as linear in the path's "
                             f"acceleration and squared speed; the {model.act_distribution.replace('_', ' ')} "
                             f"distribution{' with a preload' if model.act_preload else ''} is not (retime with "
                             "distribution = \"minimum_norm\" or \"weighted\" and no preload)")
    limits = RetimeLimits.none(model) if limits is None else limits
    lim = effective_limits(model, limits.overrides)
    s = np.linspace(0.0, 1.0, points)
    x, x1, x2 = path.at(s)
    z = np.zeros_like(x)
    kc = _kin(model, x, z, z)
    q0 = kc.q[0]
    ka, kb = _kin(model, x, z, x1, q0), _kin(model, x, x1, x2, q0)
    reacs = [joint_reactions(model, k, friction=False) for k in (kc, ka, kb)]
    parts = [_values(model, k, r, limits, lim, False) for k, r in zip((kc, ka, kb), reacs)]
    mot = [r.u / model.drive_ratio + model.drive_rotor * model.drive_ratio * k.act_qdd for k, r in zip((kc, ka, kb), reacs)]
    Cv = [p[1] for p in parts[0]]
    vmax = np.full(points, np.inf)
    for _, kval, bound in _speeds(model, kb, lim):
        with np.errstate(divide="ignore"):
            vmax = np.minimum(vmax, np.where(np.abs(kval) > 0, (bound / np.abs(kval)) ** 2, np.inf))
    has_fric = friction and (fr_any(model) or bool(np.any(model.drive_coulomb > 0))
                             or bool(np.any(model.drive_viscous > 0)))
    return _Grid(model, limits, lim, friction, s, x, x1, x2, q0, tuple(p[0] for p in parts[0]),
                 np.array([p[2] for p in parts[0]]), [pa[1] - pc[1] for pa, pc in zip(parts[1], parts[0])],
                 [pb[1] - pc[1] for pb, pc in zip(parts[2], parts[0])], Cv, vmax, has_fric,
                 any(c.ndim == 2 for c in Cv), (mot[1] - mot[0], mot[2] - mot[0], mot[0]))


def _change(sd: Array, sd_prev: Array) -> float:
    return float(np.max(np.abs(sd - sd_prev))) / max(float(np.max(sd)), 1e-300)


def _times(g: _Grid, sd: Array) -> Array:
    gaps = sd[:-1] + sd[1:]
    stuck = np.flatnonzero(gaps <= 0)
    if stuck.size:
        i = int(stuck[0])
        raise LimitError(f"path point {i} (s = {g.s[i]:.6g}): the limits leave the path no speed to move on "
                         "(sd = 0 on both sides of a grid step)")
    return np.concatenate([[0.0], np.cumsum(2 * g.D / gaps)])


def retime(model: MechanismModel, path: TaskPath, points: int = 1000, limits: RetimeLimits | None = None,
           friction: bool = True, max_iter: int = 50) -> Retiming:
    """The time-optimal timing of ``path`` on a grid of ``points`` (module docstring): rest at
    both ends, every limit met at every grid point. Raises :class:`~pkmdyn.errors.LimitError`
    naming the path point and the limit where no timing meets them, and the engine's errors (an
    unreachable pose, a singularity) naming the grid point."""
    g = _grid(model, path, points, limits, friction)
    F, d = g.start()
    sd_prev = None
    it = 0
    while True:
        it += 1
        A, B, C, C2 = g.rows(F, d, None if sd_prev is None else sd_prev <= 0.0)
        v, u, khi = _topp(list(g.names), A, B, C, g.Lb, g.vmax, g.s, C2)
        sd = np.sqrt(v)
        if not (g.has_fric or g.vector):
            break
        F, d, worst, _, _ = g.friction_at(u, v, d)
        if sd_prev is not None:
            change = _change(sd, sd_prev)
            if change <= SETTLED or (change <= CLOSE and worst <= 1.0 + MET):
                break
            if it >= max_iter:
                raise LimitError(f"the timing did not settle within {max_iter} passes of the friction and the "
                                 f"reaction directions (the largest change of sd was {change:.3g} of its largest "
                                 "value): friction or reaction bounds too strong for this path")
        sd_prev = sd
    t = _times(g, sd)
    xd, xdd = g.motion(u, v)
    return Retiming(g.s, t, sd, u, g.x, xd, xdd, np.sqrt(g.vmax), np.sqrt(khi), it, g.names)


@dataclass(frozen=True)
class LimitUse:
    """Each bound's use along a motion: ``names`` (acceleration-type bounds, then speeds),
    ``use (n, nb)`` the quantity's magnitude over its bound (a reaction's magnitude), ``largest
    (nb,)`` the most of each."""

    names: tuple[str, ...]
    use: Array

    @property
    def largest(self) -> Array:
        return self.use.max(axis=0) if self.use.size else np.zeros(0)

    @property
    def active(self) -> Array:
        """The most used bound per sample (index into ``names``)."""
        return np.argmax(self.use, axis=1)


def limit_use(model: MechanismModel, kin: Any, reac: Any, limits: RetimeLimits) -> LimitUse:
    """The use of every bound of :func:`retime` along the kinematics ``kin`` with the efforts and
    reactions ``reac`` (friction included): the independent check of a timing."""
    lim = effective_limits(model, limits.overrides)
    rows = _values(model, kin, reac, limits, lim, True) + _speeds(model, kin, lim)
    use = [np.abs(v) / b if v.ndim == 1 else np.linalg.norm(v, axis=-1) / b for _, v, b in rows]
    return LimitUse(tuple(n for n, _, _ in rows), np.stack(use, axis=1) if use else np.zeros((len(kin.x), 0)))


def copper_coefficients(model: MechanismModel) -> tuple[Array, Array]:
    """``(w, given)`` (na,): the copper losses per squared motor effort ``R / k_t^2`` [W/(N m)^2 or
    W/N^2] of each actuated joint's drive (``winding_resistance_ohm`` and its motor constant), 1
    where the drive does not give them (``given`` False)."""
    c = np.asarray(model.drive_copper, dtype=float) if len(model.drive_copper) else np.full(model.na, np.nan)
    given = np.isfinite(c)
    return np.where(given, c, 1.0), given


def timing_energy(model: MechanismModel, kin: Any, reac: Any) -> dict[str, float]:
    """A timed motion's energy of Eq. (E1) of :mod:`pkmdyn.multibody.analyses.retime_energy`
    [J] and its parts, from its kinematics ``kin`` and its efforts and reactions ``reac``
    (trapezoidal rule over the samples' times): ``copper_loss_J`` (``sum_k w_k int tau_k^2 dt``,
    :func:`copper_coefficients`), ``friction_dissipation_J`` (the joints' and the motors'), and
    the integrals over time of the squared joint efforts and squared motor efforts."""
    t = kin.t
    motors = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, reac.u)
    w, _ = copper_coefficients(model)
    copper = float(np.trapezoid((w * motors.effort ** 2).sum(axis=1), t))
    joints = float(np.trapezoid(np.abs(reac.dissipation), t))
    drives = float(np.trapezoid(np.abs(motors.friction * motors.theta_dot).sum(axis=1), t))
    return {"energy_J": copper + joints + drives, "copper_loss_J": copper,
            "friction_dissipation_J": joints + drives, "joint_friction_dissipation_J": joints,
            "motor_friction_dissipation_J": drives,
            "effort_squared_integral_SI": float(np.trapezoid((reac.u ** 2).sum(axis=1), t)),
            "motor_effort_squared_integral_SI": float(np.trapezoid((motors.effort ** 2).sum(axis=1), t))}

"""The least-energy timing of a geometric path for a given cycle time, and the Pareto curve of
cycle time against energy, under the limits of :mod:`pkmdyn.multibody.analyses.retime`.

**The energy** [J] of a timed motion, Eq. (E1):

``E = sum_k w_k int tau_k^2 dt + int (P_joints + sum_k |tau_f,k theta_dot_k|) dt``

- the first term is the motors' copper losses: ``tau_k`` the motor effort of Eq. A1
  (transmitted, rotor and motor friction; an actuated joint without a drive: its effort), ``w_k
  = R / k_t^2`` from the drive's ``winding_resistance_ohm`` and motor constant
  (``torque_constant_Nm_A`` / ``force_constant_N_A``); where a drive does not give them, ``w_k
  = 1`` W per (N m)^2 or per N^2 (the squared-effort integral) and the result says so;
- the second is the friction's dissipation: the joints' (load-dependent friction included,
  ``P_joints`` of docs/multibody_dynamics.md) and the motors'.

**The convex program** (Verscheure, Demeulenaere, Swevers, De Schutter and Diehl, "Time-optimal
path tracking for robots: a convex optimization approach", IEEE TAC 54(10), 2009): on the
grid of the time-optimal timing, with ``u_i = sdd``, ``v_i = sd^2`` at the points and ``c_i <=
sqrt(v_i)``:

- ``v_{i+1} = v_i + 2 D u_i``, ``v_0 = v_N = 0``, every limit row at every point (the same
  rows as the time-optimal timing, friction and reaction directions included);
- the time of step ``i`` is ``2 D / (c_i + c_{i+1})`` (exact for a constant ``sdd`` over the
  step), bounded by ``t_i (c_i + c_{i+1}) >= 1`` (a rotated second-order cone), and ``2 D sum
  t_i <= T``;
- the copper losses of step ``i`` by the trapezoidal rule in time over the step's motion (its
  own ``sdd = u_i`` at both ends), ``D sum_k w_k (tau_k(s_i; u_i, v_i)^2 + tau_k(s_{i+1}; u_i,
  v_{i+1})^2) / (c_i + c_{i+1})``, bounded by ``e_i (c_i + c_{i+1}) >= ||y_i||^2`` (a rotated
  cone; ``tau`` affine in ``(u, v)``);
- the friction's dissipation ``int phi ds`` with ``phi = P / sd`` the dissipation per unit of
  path, by the trapezoidal rule in ``s``, ``phi`` linear in ``(u_i, v_i)`` about the previous
  timing (forward differences of the engine's friction).

Each inequality is tight at the optimum (less ``c`` only costs time and energy), so the program's
solution is a timing. It is solved by Clarabel, an interior-point solver for conic programs.
As in the time-optimal timing, the joints' and motors' friction in the efforts and the reaction
directions are those of the previous timing (the first from the time-optimal one); the passes
stop when the largest change of ``sd`` is at most ``SETTLED`` of its largest value.

**The cycle time** is an upper bound ``T`` of the program. Where a longer motion would cost more
(the copper losses of holding a weight grow with time), the least energy is reached sooner than
``T``: the timing's cycle time is then shorter than ``T`` (``Retiming.cycle_time``), the
least-energy cycle time of the path; the Pareto curve ends there."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import LimitError, ParameterError
from ..dynamics.actuators import motor_efforts
from ..model.compiler import MechanismModel
from .retime import (
    RetimeLimits,
    Retiming,
    TaskPath,
    _change,
    _Grid,
    _grid,
    _moving,
    _times,
    copper_coefficients,
    retime,
)

__all__ = ["EnergyTiming", "pareto_front", "retime_energy"]

Array = NDArray[np.float64]

#: the stopping rule: the largest change of sd between passes, relative to its largest value
SETTLED = 1e-5
#: the passes at most
MAX_PASSES = 30
#: the grid points at most (the program holds about 6 variables and cone rows per point)
MAX_POINTS = 20_000
#: the cycle time held by the program, short of the bound by this share (the interior-point
#: solver meets its rows to about 1e-9)
MARGIN = 2e-8
#: the relative step of the forward differences of the dissipation per unit of path
STEP = 1e-5


@dataclass(frozen=True)
class EnergyTiming:
    """The least-energy timing of a path within the cycle time ``cycle_time_bound`` [s]:
    ``timing`` (its ``cycle_time`` the reached one, at most the bound), ``energy_J`` the
    program's value of Eq. (E1) at the last pass, ``passes``; ``fastest_s`` the time-optimal
    cycle time of the same path and limits."""

    timing: Retiming
    cycle_time_bound: float
    energy_J: float
    passes: int
    fastest_s: float

    @property
    def beyond_least_energy(self) -> bool:
        """True where the least energy is reached sooner than the bound (the path's least-energy
        cycle time is shorter)."""
        return self.timing.cycle_time < self.cycle_time_bound * (1.0 - 1e-6)


def _state(g: _Grid, u: Array, v: Array, d: list) -> tuple[list, list, Array, Array]:
    """At the timing ``(u, v)``: the friction and reaction directions of the limit rows, the
    motor efforts' friction part ``Fm (n, na)`` (their value less ``M[0] u + M[1] v + M[2]``) and
    the dissipation per unit of path ``phi (n,)`` [J]."""
    F, dn, _, kt, reac = g.friction_at(u, v, d)  # (solved at the speeds of _moving(v))
    ve = _moving(v)
    me = motor_efforts(g.model, kt.act_q, kt.act_qd, kt.act_qdd, reac.u)
    Fm = me.effort - (g.M[0] * u[:, None] + g.M[1] * ve[:, None] + g.M[2])
    return F, dn, Fm, _phi(g, reac, me, ve)


def _phi(g: _Grid, reac: Any, me: Any, v: Array) -> Array:
    """The dissipation per unit of path ``|P| / sd`` [J] of a solve at the speeds ``sqrt(v) > 0``
    (its reactions and motor efforts)."""
    if not g.friction:
        return np.zeros(len(v))
    p = np.abs(reac.dissipation) + np.abs(me.friction * me.theta_dot).sum(axis=1)
    return p / np.sqrt(v)


def _phi_slopes(g: _Grid, u: Array, v: Array, phi0: Array) -> tuple[Array, Array]:
    """Forward differences of ``phi`` in ``u`` and ``v`` at each point (at rest: the neighbour's
    speed)."""
    if not g.friction:
        z = np.zeros(len(v))
        return z, z
    ve = _moving(v)
    du = STEP * max(float(np.max(np.abs(u))), 1e-12)
    dv = STEP * np.maximum(ve, 1e-3 * float(np.max(ve)))
    out = []
    for uu, vv, h in ((u + du, ve, du), (u, ve + dv, dv)):
        kt, reac = g.solve(uu, vv)
        me = motor_efforts(g.model, kt.act_q, kt.act_qd, kt.act_qdd, reac.u)
        out.append((_phi(g, reac, me, vv) - phi0) / h)
    return out[0], out[1]


def _clarabel() -> Any:
    import clarabel

    return clarabel


def _program(g: _Grid, T: float, F: list, d: list, rest: Array, Fm: Array, w: Array, phi: Array,
             phi_u: Array, phi_v: Array, u0: Array, v0: Array, vtop: Array, V: float, tau_s: float, E_s: float
             ) -> tuple[Array, Array, float]:
    """One pass's conic program (module docstring) in the scaled variables ``u = V uh``, ``v = V
    vh``, ``c = sqrt(V) ch``: ``u, v`` (n,) and the program's energy [J]; ``vtop`` the bound of
    ``v`` (the speed limits' and the controllable sets')."""
    from scipy import sparse

    clarabel = _clarabel()
    n = len(g.s)
    N = n - 1
    D = g.D
    na = Fm.shape[1]
    iu, iv, ic, it, ie = 0, n, 2 * n, 3 * n, 3 * n + N
    nx = 3 * n + 2 * N
    rows: list[Any] = []
    rhs: list[Array] = []
    cones: list[Any] = []
    idx = np.arange(N)

    def block(r: Array, c: Array, val: Array, m: int, b: Array) -> None:
        rows.append(sparse.csc_matrix((val, (r, c)), shape=(m, nx)))
        rhs.append(np.asarray(b, dtype=float))

    # equalities: v_{i+1} - v_i - 2 D u_i = 0, v_0 = v_N = 0, c_0 = c_N = 0, and u_N = u_{N-1} (the
    # end point's sdd is the last step's: the motion arriving there)
    r = np.concatenate([idx, idx, idx, [N, N + 1, N + 2, N + 3, N + 4, N + 4]])
    c = np.concatenate([iv + idx + 1, iv + idx, iu + idx, [iv, iv + N, ic, ic + N, iu + N, iu + N - 1]])
    val = np.concatenate([np.ones(N), -np.ones(N), np.full(N, -2 * D), np.ones(5), [-1.0]])
    block(r, c, val, N + 5, np.zeros(N + 5))
    cones.append(clarabel.ZeroConeT(N + 5))
    # inequalities b - A x >= 0
    A, B, C, C2 = g.rows(F, d, rest)
    L = g.Lb
    lo = -1.0 - np.minimum(C, C2) / L
    hi = 1.0 - np.maximum(C, C2) / L
    a, b = A / L * V, B / L * V
    k = A.shape[1]
    pts = np.repeat(np.arange(n), k)
    ra = np.concatenate([np.arange(n * k)] * 2)
    ca = np.concatenate([iu + pts, iv + pts])
    lin = [(np.concatenate([a.ravel(), b.ravel()]), hi.ravel()), (np.concatenate([-a.ravel(), -b.ravel()]), -lo.ravel())]
    m0 = 0
    parts_r, parts_c, parts_v, parts_b = [], [], [], []
    for vals, bound in lin:
        parts_r.append(ra + m0)
        parts_c.append(ca)
        parts_v.append(vals)
        parts_b.append(bound)
        m0 += n * k
    # every timing within the limits has v_i at most the controllable sets' upper bound; a bound
    # beyond 1e6 V cannot act and is left out (it would only spoil the program's scaling)
    fin = np.flatnonzero(vtop <= 1e6 * V)
    parts_r += [m0 + np.arange(fin.size)]
    parts_c += [iv + fin]
    parts_v += [np.ones(fin.size)]
    parts_b += [vtop[fin] / V]
    m0 += fin.size
    parts_r += [m0 + np.arange(2 * n)]
    parts_c += [np.concatenate([iv + np.arange(n), ic + np.arange(n)])]
    parts_v += [-np.ones(2 * n)]
    parts_b += [np.zeros(2 * n)]
    m0 += 2 * n
    parts_r += [np.full(N, m0)]
    parts_c += [it + idx]
    parts_v += [np.full(N, 2 * D / (np.sqrt(V) * T * (1.0 - MARGIN)))]
    parts_b += [np.ones(1)]
    m0 += 1
    block(np.concatenate(parts_r), np.concatenate(parts_c), np.concatenate(parts_v), m0, np.concatenate(parts_b))
    cones.append(clarabel.NonnegativeConeT(m0))
    s2 = np.sqrt(2.0)
    # c_i^2 <= v_i: (v + 1/2, v - 1/2, sqrt(2) c) in the second-order cone
    i3 = np.arange(n)
    block(np.concatenate([3 * i3, 3 * i3 + 1, 3 * i3 + 2]), np.concatenate([iv + i3, iv + i3, ic + i3]),
          np.concatenate([-np.ones(2 * n), np.full(n, -s2)]), 3 * n, np.tile([0.5, -0.5, 0.0], n))
    cones += [clarabel.SecondOrderConeT(3)] * n

    def pair(first: Array, base: Array) -> tuple[Array, Array, Array]:
        """The rows ``(z + sigma/2, z - sigma/2)`` of the cone ``z sigma >= ...`` with ``sigma = c_i
        + c_{i+1}``, ``z`` the columns ``first``, from the rows ``base``."""
        r = np.concatenate([base, base, base, base + 1, base + 1, base + 1])
        c = np.concatenate([first, ic + idx, ic + idx + 1, first, ic + idx, ic + idx + 1])
        v = np.concatenate([-np.ones(N), np.full(2 * N, -0.5), -np.ones(N), np.full(2 * N, 0.5)])
        return r, c, v

    # t_i (c_i + c_{i+1}) >= 1
    r, c, val = pair(it + idx, 3 * idx)
    block(r, c, val, 3 * N, np.tile([0.0, 0.0, s2], N))
    cones += [clarabel.SecondOrderConeT(3)] * N
    # e_i (c_i + c_{i+1}) >= ||y_i||^2, y the scaled motor efforts at both ends of the step
    m = 2 + 2 * na
    sw = np.sqrt(w) * s2 / tau_s
    base = g.M[2] + Fm  # (n, na)
    r, c, val = pair(ie + idx, m * idx)
    rs, cs, vs = [r], [c], [val]
    bb = np.zeros((N, m))
    for side in (0, 1):
        p = idx + side
        for j in range(na):
            row = m * idx + 2 + side * na + j
            rs += [row, row]
            cs += [iu + idx, iv + p]
            vs += [-sw[j] * V * g.M[0][p, j], -sw[j] * V * g.M[1][p, j]]  # the step's own sdd, u_i
            bb[:, 2 + side * na + j] = sw[j] * base[p, j]
    block(np.concatenate(rs), np.concatenate(cs), np.concatenate(vs), m * N, bb.ravel())
    cones += [clarabel.SecondOrderConeT(m)] * N
    Amat = sparse.vstack(rows, format="csc")
    bvec = np.concatenate(rhs)
    # the objective, in units of E_s: copper sum D tau_s^2 / sqrt(V) e_i, friction by the
    # trapezoidal rule in s of phi linear in (u, v)
    q = np.zeros(nx)
    q[ie:ie + N] = D * tau_s ** 2 / np.sqrt(V) / E_s
    ws = np.full(n, D)
    ws[[0, -1]] = D / 2
    q[iu:iu + n] = ws * phi_u * V / E_s
    q[iv:iv + n] = ws * phi_v * V / E_s
    const = float(np.sum(ws * (phi - phi_u * u0 - phi_v * v0)))
    P = sparse.csc_matrix((nx, nx))
    st = clarabel.DefaultSettings()
    st.verbose = False
    st.max_iter = 500
    st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-9
    sol = clarabel.DefaultSolver(P, q, Amat, bvec, cones, st).solve()
    ok = str(sol.status).split(".")[-1] in ("Solved", "AlmostSolved")
    if not ok:
        raise LimitError(f"the least-energy timing for the cycle time {T:.6g} s was not found (the conic program "
                         f"ended {str(sol.status).split('.')[-1]}): choose a cycle time further from the fastest")
    xs = np.asarray(sol.x)
    u = xs[iu:iu + n] * V
    v = np.maximum(xs[iv:iv + n] * V, 0.0)
    v[[0, -1]] = 0.0
    return u, v, float(sol.obj_val) * E_s + const


def _energy(g: _Grid, fastest: Retiming, T: float, max_passes: int) -> EnergyTiming:
    T_min = fastest.cycle_time
    if len(g.s) > MAX_POINTS:
        raise ParameterError(f"points: the least-energy timing takes at most {MAX_POINTS:,} grid points (one conic "
                             f"program holds them all), got {len(g.s):,}")
    if not (np.isfinite(T) and T > 0):
        raise ParameterError(f"cycle time: {T!r} is not a finite number > 0 [s]")
    if T < T_min * (1.0 - 1e-9):
        raise LimitError(f"cycle time {T:.6g} s: the fastest timing within the limits takes {T_min:.6g} s")
    w, _ = copper_coefficients(g.model)
    u, v = fastest.sdd.copy(), fastest.sd ** 2
    F, d = g.start()
    F, d, Fm, phi = _state(g, u, v, d)
    tau0 = g.M[0] * u[:, None] + g.M[1] * v[:, None] + g.M[2] + Fm
    E0 = float(np.trapezoid((w * tau0 ** 2).sum(axis=1), fastest.t)) + float(np.trapezoid(phi, g.s))
    if T <= T_min * (1.0 + 1e-9):
        return EnergyTiming(fastest, T, E0, 0, T_min)
    V = float(np.max(v))
    vtop = np.minimum(g.vmax, fastest.sd_reach ** 2)
    tau_s = max(float(np.max(np.abs(tau0) * np.sqrt(w))), 1e-300)
    E_s = max(E0, 1e-300)
    sd_prev = np.sqrt(v)
    energy = float("nan")
    for it in range(1, max_passes + 1):
        phi_u, phi_v = _phi_slopes(g, u, v, phi)
        u, v, energy = _program(g, T, F, d, sd_prev <= 0.0, Fm, w, phi, phi_u, phi_v, u, v, vtop, V, tau_s, E_s)
        sd = np.sqrt(v)
        if not (g.has_fric or g.vector):
            break
        F, d, Fm, phi = _state(g, u, v, d)
        if _change(sd, sd_prev) <= SETTLED:
            break
        if it == max_passes:
            raise LimitError(f"the least-energy timing for the cycle time {T:.6g} s did not settle within "
                             f"{max_passes} passes of the friction (the largest change of sd was "
                             f"{_change(sd, sd_prev):.3g} of its largest value)")
        sd_prev = sd
    t = _times(g, sd)
    if t[-1] > T:  # beyond the bound by the solver's tolerance (about 1e-8): the same timing sped up to T
        a = t[-1] / T
        sd, u, v, t = sd * a, u * a * a, v * a * a, t / a
        t[-1] = min(t[-1], T)
    xd, xdd = g.motion(u, v)
    ret = Retiming(g.s, t, sd, u, g.x, xd, xdd, np.sqrt(g.vmax), fastest.sd_reach, it, g.names)
    return EnergyTiming(ret, T, energy, it, T_min)


def retime_energy(model: MechanismModel, path: TaskPath, cycle_time: float, points: int = 1000,
                  limits: RetimeLimits | None = None, friction: bool = True, fastest: Retiming | None = None,
                  max_passes: int = MAX_PASSES) -> EnergyTiming:
    """The least-energy timing of ``path`` (Eq. E1) within ``cycle_time`` [s] and the limits of
    :func:`~pkmdyn.multibody.analyses.retime.retime` (module docstring); ``fastest``, when
    given, is that function's result for the same path, grid and limits. Raises
    :class:`~pkmdyn.errors.LimitError` where the cycle time is shorter than the fastest."""
    g = _grid(model, path, points, limits, friction)
    fastest = retime(model, path, points, limits, friction) if fastest is None else fastest
    return _energy(g, fastest, float(cycle_time), max_passes)


def pareto_front(model: MechanismModel, path: TaskPath, cycle_times: Array, points: int = 1000,
                 limits: RetimeLimits | None = None, friction: bool = True, fastest: Retiming | None = None,
                 progress: Any = None) -> list[EnergyTiming]:
    """The least-energy timings within each of ``cycle_times`` [s] (ascending, each at least the
    fastest): the Pareto curve of cycle time against energy, which ends where a timing reaches
    the path's least-energy cycle time (:attr:`EnergyTiming.beyond_least_energy`; later cycle
    times are not computed). ``progress(k)`` is called after each."""
    T = np.asarray(cycle_times, dtype=float)
    if T.ndim != 1 or T.size == 0 or np.any(np.diff(T) <= 0):
        raise ParameterError("cycle times: expected an ascending list of at least one cycle time [s]")
    g = _grid(model, path, points, limits, friction)
    fastest = retime(model, path, points, limits, friction) if fastest is None else fastest
    out = []
    for k, Tk in enumerate(T):
        e = _energy(g, fastest, float(Tk), MAX_PASSES)
        out.append(e)
        if progress is not None:
            progress(k)
        if e.beyond_least_energy:
            break
    return out

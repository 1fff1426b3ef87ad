"""The closed loop's cycles in one compiled call, for a described mechanism.

:func:`pkmdyn.simulate.run_span` takes the cycles of :mod:`._loop` one by one in Python: each
cycle calls some ten compiled kernels (encoders, sensors, direct kinematics, the law, about six
single-sample forward dynamics of the integrator), and the calls between them cost about as much
as the kernels themselves. Where every one of those kernels is the described mechanism's own
(:mod:`pkmdyn.multibody.dynamics._sample_kernels`, :func:`pkmdyn.multibody.kinematics._direct_kernels.direct_task_one`),
:func:`run_cycles` takes the same cycles with the same arithmetic in one call: the encoders
(module docstring of :mod:`._loop`, item 1), the sensors, the pose by the direct kinematics
(item 2), the law (:mod:`pkmdyn.control._laws`), the limits (item 3), the plant's steps
(:func:`._plant.hold_interval`, item 4: the explicit step, ROS2 in the friction band, the
refinement of a velocity reversal).

A cycle that is not a plain one - a kernel that does not answer (no solution to start from, an
input the checked route names, a singularity), a coordinate past its divergence limit - is left to the
Python cycle, which keeps every message and fallback: the compiled call restores the state it
took the cycle from and returns its index; :func:`run_span` takes that cycle in Python and hands
the next ones back. (The kernels' warm starts are not restored: a Python cycle after such a
return starts its Newton solves from where the compiled one left them, so its results may differ
from a wholly Python run's within the solvers' tolerances.)

Its kernel takes some 15-30 s to compile where numba's cache lacks it (it links the single-sample
dynamics and direct kinematics a second time; the install compiles it, ``pkmdyn compile``), so it
runs where it is compiled in this process or cached, or where the run is long enough to repay its
compilation (:func:`available`); otherwise the Python cycles run. Both routes give the same records
(tests/test_compiled_cycles.py: to 1e-12 of each record's size where no cycle is handed back).
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from .. import _dense
from ..control import _laws
from ..control._laws import _ct_acc, _pd, _pid
from ..multibody import _cache
from ..multibody._cache import cached
from ..multibody.dynamics import _dyn_kernels, friction
from ..multibody.dynamics import _sample_kernels as _one
from ..multibody.dynamics import newton_euler as dynamics
from ..multibody.kinematics import _direct_kernels as _direct
from ..multibody.kinematics import _solve_kernels as _kernels
from ..multibody.model import _tree_kernels
from . import _plant, _sensors
from ._plant import (
    EXPLICIT_LIMIT,
    FD_STEP,
    JACOBIAN_REUSE,
    REFINE,
    _piecewise,
    _rk3_finish,
    _rk3_step,
    _rk4_step,
    _rk_finish,
    _rk_stage,
    _stage1,
    _stage2,
    _stale,
    _stiffness,
)
from ._sensors import _actuate, _sense

__all__ = ["LAWS", "CompiledCycles", "compiled_cycles", "run_cycles", "example_arguments", "example_signature", "available"]

Array = NDArray[np.float64]

#: the laws' codes in the compiled call
LAWS = {"feedforward": 0, "pid": 1, "computed-torque": 2, "pd": 3, "augmented-pd": 4}
#: the integrator's scalars in one array: the load at the Jacobian, whether the Jacobian is
#: fresh, whether the motion is in the friction band, explicit and refined step counts
_LD_A, _FRESH, _STIFF, _EXPLICIT, _REFINED = range(5)

_FORWARD, _INVERSE, _POSITIONS, _OK = _one.FORWARD, _one.INVERSE, _one.POSITIONS, _one.OK


@numba.njit(cache=True)
def _f(pk, q, qd, u, load, has_load, out):  # pragma: no cover - compiled
    """The plant's accelerations (:func:`._plant.make_plant`'s ``f``); the kernel's status.
    ``pk``: the packed buffer and the kernel's modes (forward, inverse, positions) as values: a
    mode written here as a constant would compile the kernel once more for that literal value."""
    ld = load if has_load else 0.0
    return _one._dynamics(pk[0], q, qd, u, ld, pk[1][0], out)


@numba.njit(cache=True)
def _jacobian(pk, has_load, q, qd, u, ld, f0, A, vp, qd_A, ws, fv):  # pragma: no cover - compiled
    """:func:`._plant._jacobian`: ``A = d f / d qd`` by one-sided differences."""
    n = q.shape[0]
    for c in range(n):
        d = FD_STEP * (1.0 + abs(qd[c]))
        for i in range(n):
            vp[i] = qd[i]
        vp[c] += d
        st = _f(pk, q, vp, u, ld, has_load, fv)
        if st != _OK:
            return st
        for i in range(n):
            A[i, c] = (fv[i] - f0[i]) / d
    for i in range(n):
        qd_A[i] = qd[i]
    ws[_LD_A] = ld
    ws[_FRESH] = 1.0
    return _OK


@numba.njit(cache=True)
def _ros2(pk, has_load, q, qd, u, ld0, ld1, dt, force, have_f0, f0, A, W, vp, buf, qd_A, ws,
          fv):  # pragma: no cover - compiled
    """:func:`._plant._ros2_step`; returns the status and whether a velocity reversed
    (:func:`._plant._reversed`)."""
    if not have_f0:
        st = _f(pk, q, qd, u, ld0, has_load, f0)
        if st != _OK:
            return st, False
    if force or _stale(qd, qd_A, JACOBIAN_REUSE) or abs(ld0 - ws[_LD_A]) > JACOBIAN_REUSE * abs(ws[_LD_A]):
        st = _jacobian(pk, has_load, q, qd, u, ld0, f0, A, vp, qd_A, ws, fv)
        if st != _OK:
            return st, False
    else:
        ws[_FRESH] = 0.0
    _stage1(q, qd, f0, A, dt, W, buf)
    st = _f(pk, buf[2], buf[3], u, ld1, has_load, fv)
    if st != _OK:
        return st, False
    return _OK, _stage2(q, qd, fv, dt, W, buf)


@numba.njit(cache=True)
def _save(src, dst):  # pragma: no cover - compiled
    """``dst[:] = src`` (1-D) element by element."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@numba.njit(cache=True)
def _save_all(src, dst, A_src, A_dst):  # pragma: no cover - compiled
    """:func:`_save` of each vector of the tuple ``src`` into that of ``dst``, and of each row of
    the matrix ``A_src`` into ``A_dst``: a cycle's state kept, or put back."""
    for j in range(len(src)):
        _save(src[j], dst[j])
    for r in range(A_src.shape[0]):
        _save(A_src[r], A_dst[r])


@numba.njit(cache=True)
def _hold(pk, has_load, q, qd, u, loads, lo, n, dt, method, A, W, vp, buf, qd_A, ws, f0, a2, a3, a4,
          fv):  # pragma: no cover - compiled
    """:func:`._plant.hold_interval` over ``n`` steps, the loads from ``loads[lo]``; the status."""
    for j in range(n):
        l0, lm, l1 = loads[lo + 2 * j], loads[lo + 2 * j + 1], loads[lo + 2 * j + 2]
        st = _f(pk, q, qd, u, l0, has_load, f0)
        if st != _OK:
            return st
        rev = False
        if method != 2 and ws[_STIFF] == 0.0:
            if method == 0:  # Nystroem's third order (:func:`._plant._rk3_step`)
                h3 = 2.0 / 3.0 * dt
                l23 = (-l0 + 8.0 * lm + 2.0 * l1) / 9.0
                _rk_stage(q, qd, qd, f0, h3, buf[2], buf[3])
                st = _f(pk, buf[2], buf[3], u, l23, has_load, a2)
                if st != _OK:
                    return st
                _rk_stage(q, qd, buf[3], a2, h3, buf[4], buf[5])
                st = _f(pk, buf[4], buf[5], u, l23, has_load, a3)
                if st != _OK:
                    return st
                rev, rho = _rk3_finish(q, qd, f0, a2, a3, dt, buf[6:8])
            else:  # classical RK4 (:func:`._plant._rk4_step`)
                h2 = 0.5 * dt
                _rk_stage(q, qd, qd, f0, h2, buf[2], buf[3])
                st = _f(pk, buf[2], buf[3], u, lm, has_load, a2)
                if st != _OK:
                    return st
                _rk_stage(q, qd, buf[3], a2, h2, buf[4], buf[5])
                st = _f(pk, buf[4], buf[5], u, lm, has_load, a3)
                if st != _OK:
                    return st
                _rk_stage(q, qd, buf[5], a3, dt, buf[0], buf[1])
                st = _f(pk, buf[0], buf[1], u, l1, has_load, a4)
                if st != _OK:
                    return st
                rev, rho = _rk_finish(q, qd, f0, a2, a3, a4, dt, buf[6:8])
            if dt * rho >= EXPLICIT_LIMIT:  # entered the friction band: retake by ROS2
                ws[_STIFF] = 1.0
                rev = False
                _save(buf[6], q)
                _save(buf[7], qd)
            elif not rev:
                ws[_EXPLICIT] += 1.0
        if method == 2 or ws[_STIFF] != 0.0:
            st, rev = _ros2(pk, has_load, q, qd, u, l0, l1, dt, False, True, f0, A, W, vp, buf, qd_A, ws, fv)
            if st != _OK:
                return st
            ws[_STIFF] = 1.0 if dt * _stiffness(A) >= EXPLICIT_LIMIT else 0.0
        if rev:
            ws[_REFINED] += 1.0
            _save(buf[6], q)
            _save(buf[7], qd)
            h = dt / REFINE
            fresh = ws[_STIFF] != 0.0 or method == 2
            for r in range(REFINE):
                la = _piecewise(l0, lm, l1, r / REFINE)
                lb = _piecewise(l0, lm, l1, (r + 1) / REFINE)
                st, _ = _ros2(pk, has_load, q, qd, u, la, lb, h, fresh, False, f0, A, W, vp, buf, qd_A, ws, fv)
                if st != _OK:
                    return st
            ws[_STIFF] = 1.0 if dt * _stiffness(A) >= EXPLICIT_LIMIT else 0.0
    return _OK


@numba.njit(cache=True)
def run_cycles(i0, i1, first, pre, done, delay, steps, dt, method, law, exact, sense, plant, encoders, direct,
               ctrl, act, integ, keep):  # pragma: no cover - compiled
    """Cycles ``i0 .. i1 - 1`` of :func:`._loop.run_span` (its names: ``first`` the span's first
    row in the reference arrays, ``pre`` the delayed pose sensor's carried rows, ``done`` the
    cycles before the span, ``delay`` the sensor's delay in cycles), each as its Python cycle
    takes it; returns the first cycle it did not take (``i1`` where it took them all).

    ``sense``: :func:`._sensors._sense`'s arguments after ``s_exact``, in its order (``q, qd,
    div, noise, pose_from_sensor`` and its groups ``ref, filt, mem, rec``);
    ``plant``: ``(pk, has_load, loads, modes)`` (``modes``: the
    single-sample kernel's forward, inverse and positions modes); ``encoders``: ``(pk, view, prev, out, ratio, a0,
    s_exact)``; ``direct``: ``(pk, d, out, ok, a0, ratio, a, ad)``; ``ctrl``: ``(pk, has_load,
    ref_load, qd_ref, qdd_ref, kp, kd, ki, B_inv, u_ff, with_ff, s_ref, sd_ref, T, memory, acc, out)``;
    ``act``: ``(lim, u, out_u, sat)``; ``integ``: ``(A, W, vp, buf, qd_A, ws, f0, a2, a3, a4,
    fv)``; ``keep``: room for the state a cycle starts from (restored where it returns early).
    """
    q, qd, div, noise, from_sensor, s_ref, s_filt, s_mem, s_rec = sense
    q_ref = s_ref[0]
    s_prev, sd_prev, yq, yqd, ys, ysd, ysdd = s_mem
    out_qs, out_qds = s_rec[4], s_rec[5]
    pk, has_load, loads, modes = plant
    pk = (pk, modes)
    e_pk, e_view, e_prev, e_out, e_ratio, e_a0, s_exact = encoders
    d_pk, d_d, d_out, d_ok, d_a0, d_ratio, d_a, d_ad = direct
    (c_pk, c_has_load, ref_load, qd_ref, qdd_ref, kp, kd, ki, B_inv, u_ff, with_ff, j_s, j_sd, T_c, memory, acc,
     c_out) = ctrl
    lim, u, out_u, sat = act
    A, W, vp, buf, qd_A, ws, f0, a2, a3, a4, fv = integ
    k_q, k_qd, k_sp, k_sdp, k_sd, k_sdd, k_mem, k_ws, k_qdA, k_A = keep
    nq = q.shape[0]
    nu = u.shape[0]
    # what a cycle changes and puts back where it returns early
    state = (q, qd, s_prev, sd_prev, ysd, ysdd, memory, ws, qd_A)
    kept = (k_q, k_qd, k_sp, k_sdp, k_sd, k_sdd, k_mem, k_ws, k_qdA)
    for i in range(i0, i1):
        kr, k, g = first + i, pre + i, done + i
        _save_all(state, kept, A, k_A)
        ok = True
        if exact:  # the plant's encoders (:meth:`._loop.ExactEncoders.read`)
            _save(e_view, e_prev)
            if _one._dynamics(e_pk, q, qd, qd, 0.0, modes[2], e_out) != _OK:
                _save(e_prev, e_view)
                ok = False
            else:
                for a in range(nu):
                    s_exact[a] = e_ratio[a] * (e_out[a] - e_a0[a])
        if ok:
            jd = k - delay if g >= delay else 0
            start = g == 0
            bad = _sense(kr, k, jd, start, exact, s_exact, q, qd, div, noise, from_sensor, s_ref, s_filt, s_mem,
                         s_rec)
            ok = bad < 0
        if ok and exact:  # the controller's pose (:meth:`._loop.ExactEncoders.pose`)
            for a in range(nu):
                d_a[a] = d_a0[a] + ys[a] / d_ratio[a]
                d_ad[a] = ysd[a] / d_ratio[a]
            if _direct.direct_task_one(d_pk, d_d, d_a, d_ad, d_out) != d_ok:
                ok = False
            else:
                for t in range(nq):
                    if not from_sensor:
                        yq[t] = d_out[t]
                        out_qs[k, t] = d_out[t]
                    yqd[t] = d_out[nq + t]
                    out_qds[k, t] = d_out[nq + t]
        if ok:  # the law (:func:`pkmdyn.control.effort`)
            if law == 0:
                u_raw = u_ff[kr]
            elif law == 1:
                _pid(kr, T_c, j_s, j_sd, ys, ysd, kp, ki, kd, memory, c_out)
                u_raw = c_out
            elif law == 2:
                _ct_acc(kr, q_ref, qd_ref, qdd_ref, yq, yqd, kp, kd, acc)
                ld = ref_load[kr] if ref_load.shape[0] > 0 and c_has_load else 0.0
                ok = _one._dynamics(c_pk, yq, yqd, acc, ld, modes[1], c_out) == _OK
                u_raw = c_out
            else:
                _pd(kr, q_ref, qd_ref, yq, yqd, kp, kd, B_inv, u_ff, with_ff, c_out)
                u_raw = c_out
        if ok:
            _actuate(k, u_raw, lim, u, out_u, sat)
            lo = 2 * kr * steps
            ok = _hold(pk, has_load, q, qd, u, loads, lo, steps, dt, method, A, W, vp, buf, qd_A, ws,
                       f0, a2, a3, a4, fv) == _OK
        if not ok:
            _save_all(kept, state, k_A, A)
            return i
    return i1


def _c(a: Any, dtype: Any = float) -> Any:
    return np.ascontiguousarray(a, dtype=dtype)


class CompiledCycles:
    """The tuples :func:`run_cycles` reads, made once per span from the Python cycle's own arrays
    (the same objects, so that both routes read and write one state); :meth:`run` takes cycles
    and carries the integrator's scalars between its :class:`._plant._Work` and the call."""

    def __init__(self, args: tuple, plant: Any, loads: Array, encoders: tuple, direct: tuple, ctrl: tuple,
                 act: tuple, work: Any, method: int, law: int, exact: bool, steps: int, dt: float) -> None:
        w = work
        self.work = w
        self.ws = np.array([w.ld_A, float(w.fresh), float(w.stiff), float(w.explicit_steps), float(w.refined_steps)])
        n = plant.nq
        self.integ = (w.A, w.W, w.vp, w.buf, w.qd_A, self.ws, np.empty(n), np.empty(n), np.empty(n), np.empty(n),
                      np.empty(n))
        nu = act[1].shape[0]
        self.keep = (np.empty(n), np.empty(n), np.empty(nu), np.empty(nu), np.empty(nu), np.empty(nu),
                     np.empty(ctrl[14].shape[0]), np.empty(5), np.empty(n), np.empty((n, n)))
        self.head = (steps, float(dt), method, law, exact)
        modes = np.array([_FORWARD, _INVERSE, _POSITIONS], dtype=np.int64)
        self.tail = (args, (plant.kernel[0], bool(plant.has_load), loads, modes), encoders, direct, ctrl, act, self.integ,
                     self.keep)

    def run(self, i0: int, i1: int, first: int, pre: int, done: int, delay: int) -> int:
        """Cycles ``i0 .. i1 - 1`` (:func:`run_cycles`); the first not taken."""
        w, ws = self.work, self.ws
        ws[:] = (w.ld_A, float(w.fresh), float(w.stiff), float(w.explicit_steps), float(w.refined_steps))
        j = run_cycles(i0, i1, first, pre, done, delay, *self.head, *self.tail)
        w.ld_A, w.fresh, w.stiff = float(ws[_LD_A]), bool(ws[_FRESH]), bool(ws[_STIFF])
        w.explicit_steps, w.refined_steps = int(ws[_EXPLICIT]), int(ws[_REFINED])
        return int(j)


def compiled_cycles(plant: Any, controller: Any, ref: Any, exact: Any, work: Any, args: tuple,
                    loads: Array, lim: Array, u: Array, out_u: Array, sat: Array, memory: Array, s_exact: Array,
                    steps: int, dt: float) -> CompiledCycles | None:
    """The compiled cycles of a span, or None where a kernel of the cycle is not the described
    mechanism's own, a buffer is not primed yet (exact encoders: the encoders' and the direct
    kinematics' solutions at the run's first pose), or
    the kernel is not compiled yet (:func:`available`)."""
    if plant.kernel is None or plant.kernel[1] is not _one.forward_one:
        return None
    if not work.explicit:  # the integrator's own method (:func:`._plant.make_work`)
        method = 2
    elif work.step is _rk3_step:
        method = 0
    elif work.step is _rk4_step:
        method = 1
    else:
        return None
    kind = controller.kind
    if kind not in LAWS or (kind == "computed-torque" and (controller.id_kernel is None
                                                           or controller.id_kernel[1] is not _one.inverse_one)):
        return None
    if kind == "pid" and controller.joint is None:
        return None
    nu = plant.nu
    if exact is not None:
        enc_of = getattr(exact.verbs, "encoder_buffers", None)
        dk_of = getattr(exact.verbs, "direct_task_buffers", None)
        if enc_of is None or dk_of is None:
            return None
        enc, dk = enc_of(exact.plant_model), dk_of(exact.ctrl_model)
        if enc is None or dk is None:
            return None
        encoders = (*enc, _c(exact.ratio), _c(exact.a0_plant), s_exact)
        direct = (dk[0], dk[1], dk[2], dk[3], _c(exact.a0_ctrl), _c(exact.ratio), np.empty(nu), np.empty(nu))
    else:
        z = np.zeros(1)
        encoders = (np.zeros(1, dtype=np.int64), z, z, z, z, z, s_exact)
        direct = (np.zeros(1, dtype=np.int64), np.zeros(1, dtype=np.int64), z, 0, z, z, z, z)
    g = controller.gains
    if kind == "computed-torque":
        c_pk, c_load = controller.id_kernel[0], bool(controller.id_kernel[2])
    else:
        c_pk, c_load = np.zeros(1, dtype=np.int64), False
    j = controller.joint
    ctrl = (c_pk, c_load, _c(ref.load) if ref.load is not None else np.zeros(0), _c(ref.qd), _c(ref.qdd), g.kp, g.kd,
            g.ki, _c(controller.B_inv) if controller.B_inv is not None else np.zeros((1, 1, 1)),
            _c(controller.u_ff) if controller.u_ff is not None else np.zeros((1, 1)), kind == "augmented-pd",
            _c(j.s) if kind == "pid" else np.zeros((1, 1)), _c(j.sd) if kind == "pid" else np.zeros((1, 1)),
            float(ref.T), memory, controller.acc, controller.out)
    if not all(a.flags.c_contiguous for a in _leaves(args) if isinstance(a, np.ndarray)):
        return None
    cc = CompiledCycles(args, plant, loads, encoders, direct, ctrl, (lim, u, out_u, sat), work, method,
                        LAWS[kind], exact is not None, steps, dt)
    if _kinds((0, 0, 0, 0, 0, 0, *cc.head, *cc.tail)) != _kinds(example_arguments()):
        return None  # another type than the compiled one: the Python cycles, rather than a compilation here
    return cc


def _leaves(args: Any) -> Any:
    """Every leaf of nested tuples, in order."""
    for a in args:
        if isinstance(a, tuple):
            yield from _leaves(a)
        else:
            yield a


def _kinds(args: Any) -> Any:
    """What decides an argument's numba type, leaf by leaf (dtype, dimensions and layout of an
    array; a scalar's Python type): a cheaper comparison than ``numba.typeof``."""
    if isinstance(args, tuple):
        return tuple(_kinds(a) for a in args)
    if isinstance(args, np.ndarray):
        return args.dtype.str, args.ndim, bool(args.flags.c_contiguous), bool(args.flags.writeable)
    return type(args)


def example_arguments() -> tuple:
    """Arguments of :func:`run_cycles` of the types a run passes (two coordinates, nothing to
    run): what the install compiles it for (:func:`compile_for_runs`)."""
    n = 2
    v, m2, m3 = np.zeros(n), np.zeros((1, n)), np.zeros((1, n, n))
    ipk = np.zeros(1, dtype=np.int64)
    args = (v, v, v, m2, False, (m2, m2, m3, m2, m3), (v, 1.0, 1.0, 1.0), (v,) * 7, (m2,) * 9)
    encoders = (ipk, v, v, v, v, v, v)
    direct = (ipk, ipk, v, 0, v, v, v, v)
    ctrl = (ipk, False, v, m2, m2, v, v, v, m3, m2, False, m2, m2, 1.0, v, v, v)
    act = (v, v, m2, np.zeros((1, n), dtype=bool))
    integ = (np.zeros((n, n)), np.zeros((2, n, n)), v, np.zeros((8, n)), v, np.zeros(5), v, v, v, v, v)
    keep = (v, v, v, v, v, v, v, np.zeros(5), v, np.zeros((n, n)))
    return (0, 0, 0, 0, 0, 0, 1, 1.0, 0, 0, False, args, (ipk, False, v, ipk), encoders, direct, ctrl, act, integ, keep)


_SIGNATURE: list[tuple] = []


def example_signature() -> tuple:
    """The numba types of :func:`example_arguments` (the compiled signature)."""
    if not _SIGNATURE:
        _SIGNATURE.append(tuple(numba.typeof(a) for a in example_arguments()))
    return _SIGNATURE[0]


#: a run of this many cycles or more compiles :func:`run_cycles` where the cache lacks it: at
#: about 0.1 ms a cycle in Python (a six-legged platform's cycle of two steps), about a minute,
#: which its compilation (some 15-30 s) repays
WORTH_COMPILING_CYCLES = 600_000


def compile_for_runs() -> None:
    """Compile (or load from numba's cache) :func:`run_cycles` for the signature every run
    passes (:func:`example_signature`)."""
    run_cycles.compile(example_signature())


def available(cycles: int = 0) -> bool:
    """Whether :func:`run_cycles` is compiled for :func:`example_signature` in this process or
    in numba's cache; a run of ``cycles`` at least :data:`WORTH_COMPILING_CYCLES` compiles it
    here where it is neither (said on stderr by a command, :mod:`pkmdyn.compile_notice`)."""
    if run_cycles.signatures or cached(run_cycles):
        return True
    if cycles >= WORTH_COMPILING_CYCLES:
        compile_for_runs()
        return True
    return False


def _refresh_cache() -> None:
    """The kernels above link the single-sample dynamics and direct kinematics, the integrator's,
    the sensors' and the laws' kernels of other modules (:mod:`pkmdyn.multibody._cache`)."""

    _cache.refresh((_f, _jacobian, _ros2, _hold, run_cycles),
                   (_one, _direct, _kernels, _tree_kernels, _dyn_kernels, _dense, friction, dynamics, _sensors, _plant, _laws))


_refresh_cache()

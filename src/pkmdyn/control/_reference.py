"""The reference a controller tracks, sampled on the control grid.

The control cycle ``T`` divides time into hold intervals ``[t_k, t_k + T]``, ``t_k = k T``,
``k = 0 .. K - 1``. A :class:`Reference` holds the reference motion at the cycle instants
(the feedback target) and at the middles of the hold intervals (where the feedforward effort
is evaluated), and the actuator displacements along it (the joint-space reference of a
joint-space loop).

Which constant to hold. Let ``u*(t)`` be the effort that makes the machine follow the
reference exactly and ``G = M^-1 B`` (taken constant over a few cycles). A constant ``u_k``
held over interval ``k`` leaves, per interval, the velocity error ``G T (u_k - mean u*)`` and
the position error ``G int_0^T (T - s) (u_k - u*(s)) ds``. Expanding ``u*`` about the middle,
``u* = u_m + x u' + x^2/2 u''`` (``x = s - T/2``), the mean is ``u_m + T^2/24 u''`` and the
position integral ``T^2/2 (u_k - u_m) + T^3/12 u' - T^4/48 u''``. With ``u_k = u_m + c T^2 u''``
the errors summed over the intervals up to ``t`` are, to order ``T^2``,

    position = G T^2 [ (c - 1/24) (u*(t) - u*(0) - u*'(0) t) + 1/12 (u*(t) - u*(0)) ]

The interval mean (``c = 1/24``: no velocity error) leaves ``T^2/12 G (u*(t) - u*(0))``: each
interval's position offset ``T^3/12 G u'`` adds up. The middle value (``c = 0``) halves it; ``c
= -1/24`` cancels it: the velocity error it makes, ``-T^2/12 G (u*'(t) - u*'(0))``, carries the
positions back onto the reference at the cycle instants, all but ``T^2/12 G u*'(0) t``, which
comes from the start (the plant starts with no velocity error); the first interval's effort
less ``T/12 u*'(0)`` gives it the velocity error ``-T^2/12 G u*'(0)`` and removes that term.
The feedforward therefore holds ``u_k = u_m - T^2/24 u''`` (``u''`` by the second difference
of the middles), the first one less ``T/12 u'(0)`` (:func:`pkmdyn.control.held_efforts`); the
sampled positions then follow the reference to ``O(T^3)``. ``tests/test_control.py`` checks
the formula above on the exact sampled double integrator. On the ISO 14242-1 cycle of the
2(3PUS+S) wear simulator (Chen, Cheng & Pang 2022; 1 ms, exact plant) the replay errors are 3.2e-4 deg (the mean, by Simpson's rule over start,
middle and end), 1.7e-4 deg (the middle) and 6e-6 deg (this choice); docs/control.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError

__all__ = ["Reference", "JointReference", "sample_reference", "reference_window", "joint_reference",
           "hermite_motion"]

Array = NDArray[np.float64]

#: a motion: ``t (n,)`` [s] -> ``q, qd, qdd (n, nq)`` and ``load (n,)`` [N] or None
MotionFn = Callable[[Array], tuple[Array, Array, Array, Array | None]]


@dataclass(frozen=True)
class Reference:
    """Reference on the control grid.

    ``T`` control cycle [s]; ``t (K + 1,)`` cycle instants [s]; ``q, qd, qdd (K + 1, nq)``
    there; ``load (K + 1,)`` [N] or None; ``mid_q, mid_qd, mid_qdd (K, nq)`` and
    ``mid_load (K,)`` at ``t_k + T / 2``.
    """

    T: float
    t: Array
    q: Array
    qd: Array
    qdd: Array
    load: Array | None
    mid_q: Array
    mid_qd: Array
    mid_qdd: Array
    mid_load: Array | None

    @property
    def cycles(self) -> int:
        """Number of hold intervals ``K``."""
        return int(self.t.shape[0] - 1)


@dataclass(frozen=True)
class JointReference:
    """Actuator displacements along a reference, from a machine's actuator map.

    ``Bt (K + 1, nu, nq)`` = ``B(q_ref)^T`` (actuator rates per unit ``qd``: by virtual work
    ``u . s_dot = (B u) . qd``); ``s, sd, sdd (K + 1, nu)`` the displacements from the start
    [rad or m], their rates and accelerations. ``s`` is the integral of ``sd = B^T qd`` by the
    trapezoidal rule with its end correction (Euler-Maclaurin, ``- T^2/12 (sd'_k+1 - sd'_k)``,
    ``sd'`` by second-order differences on the grid; fourth order per cycle); ``sdd`` the
    central difference of ``sd`` over +-1e-6 T around each instant (one-sided at the two ends).
    """

    Bt: Array
    s: Array
    sd: Array
    sdd: Array


def sample_reference(motion: MotionFn, duration: float, T: float) -> Reference:
    """Sample ``motion`` on the grid of ``K = round(duration / T)`` cycles of ``T`` [s]."""
    K = int(round(duration / T))
    if K < 1:
        raise MotionError(f"motion: {duration:g} s is shorter than one control cycle ({T:g} s)")
    return reference_window(motion, T, 0, K)


def reference_window(motion: MotionFn, T: float, first: int, last: int) -> Reference:
    """The reference on the cycle instants ``first .. last`` (``t = k T``) of a longer run and the
    middles between them: a window of :func:`sample_reference`'s grid, with the same numbers."""
    t = np.arange(first, last + 1) * T
    tm = t[:-1] + 0.5 * T
    q, qd, qdd, load = motion(t)
    mq, mqd, mqdd, mload = motion(tm)
    return Reference(T, t, q, qd, qdd, load, mq, mqd, mqdd, mload)


def joint_reference(verbs: Any, model: Any, ref: Reference, motion: MotionFn, accelerations: bool = True) -> JointReference:
    """Actuator displacements, rates and (with ``accelerations``, else zeros) accelerations
    along ``ref`` (batched verb calls): the accelerations from the verbs'
    ``actuator_accelerations`` where they have it, else a central difference of the rates
    ``B^T qd`` in time."""
    Bt = np.swapaxes(verbs.actuator_map(model, ref.q), -1, -2)
    sd = np.einsum("kij,kj->ki", Bt, ref.qd)
    T = ref.T
    s = np.zeros_like(sd)
    if sd.shape[0] > 2:
        g = np.gradient(sd, T, axis=0, edge_order=2)
        s[1:] = np.cumsum(0.5 * T * (sd[:-1] + sd[1:]) - T * T / 12.0 * (g[1:] - g[:-1]), axis=0)
    else:
        s[1:] = np.cumsum(0.5 * T * (sd[:-1] + sd[1:]), axis=0)
    if not accelerations:
        return JointReference(Bt, s, sd, np.zeros_like(sd))
    exact = getattr(verbs, "actuator_accelerations", None)
    if exact is not None:  # a solved mechanism: its second-order kinematics
        return JointReference(Bt, s, sd, exact(model, ref.q, ref.qd, ref.qdd))
    d = 1e-6 * ref.T
    # one-sided at the ends of the reference, so that no instant falls outside the motion
    lo, hi = np.maximum(ref.t - d, ref.t[0]), np.minimum(ref.t + d, ref.t[-1])
    rates = []
    for tt in (lo, hi):
        q, qd, _, _ = motion(tt)
        rates.append(np.einsum("kij,kj->ki", np.swapaxes(verbs.actuator_map(model, q), -1, -2), qd))
    sdd = (rates[1] - rates[0]) / (hi - lo)[:, None]
    return JointReference(Bt, s, sd, sdd)


def hermite_motion(t: Array, q: Array, qd: Array, qdd: Array, load: Array | None) -> MotionFn:
    """A motion through samples: the quintic Hermite interpolant matching ``q, qd, qdd`` at every
    sample (``scipy.interpolate.BPoly.from_derivatives``, one per coordinate), the load linear
    between samples. Times outside ``[t_0, t_end]`` are an error.

    The coordinates' Bernstein pieces are stacked into one piecewise polynomial and converted
    once to the power basis (``PPoly.from_bernstein_basis``), whose evaluation (Horner's rule,
    derivatives included) is an order of magnitude cheaper than the Bernstein form's. Each
    piece's value at its start is taken out before the conversion and put back into its
    constant term, so that a large offset (a coordinate of 1 m moving by millimetres) does not
    enter the conversion's sums: the rates and accelerations keep the Bernstein form's
    accuracy."""
    from scipy.interpolate import BPoly, PPoly

    t = np.asarray(t, dtype=float)
    nq = q.shape[1]
    polys = [BPoly.from_derivatives(t, np.stack([q[:, c], qd[:, c], qdd[:, c]], axis=-1)) for c in range(nq)]
    c = np.stack([p.c for p in polys], axis=-1)
    start = c[0].copy()  # each piece's value at its start (the first Bernstein coefficient)
    poly = PPoly.from_bernstein_basis(BPoly(c - start, polys[0].x))
    poly.c[-1] += start
    t0, t1 = float(t[0]), float(t[-1])

    def motion(tt: Array) -> tuple[Array, Array, Array, Array | None]:
        x = np.asarray(tt, dtype=float) + t0
        if x.size and (x.min() < t0 - 1e-9 or x.max() > t1 + 1e-9):
            raise MotionError(f"motion: time {x.max() - t0:g} s is beyond the motion's {t1 - t0:g} s")
        x = np.clip(x, t0, t1)
        L = None if load is None else np.interp(x, t, load)
        return poly(x), poly(x, 1), poly(x, 2), L

    return motion

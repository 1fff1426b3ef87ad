"""A smooth periodic model of the ISO 14242-1 wear-test cycle (motion and load).

ISO 14242-1 prescribes, for a 1 Hz walking cycle, flexion/extension between +25 and -18
degrees, abduction/adduction between +7 and -4 degrees, internal/external rotation between
+2 and -10 degrees, and a double-peak axial load with 3000 N peaks and 300 N in the swing
phase. The standard's tabulated curves are not public, so this module does not reproduce
them: it builds a documented smooth model whose extremes, their phases and the load's key
points are parameters (:class:`IsoCycle`). The defaults are chosen to resemble the published
figure of the standard; they are *not* calibrated to any paper.

Angles. Each angle moves between its maximum ``q_max`` at phase ``p_max`` and its minimum
``q_min`` at phase ``p_min`` (fractions of the period ``T``) as

    q(t) = m + a cos(pi phi(tau)),   m = (q_max + q_min)/2,  a = (q_max - q_min)/2,
    tau = frac(t/T - p_max),  phi(tau) = 2 tau + A (1 - cos 2 pi tau) / (2 pi),
    A = 2 pi (1 - 2 d) / (1 - cos 2 pi d),  d = frac(p_min - p_max),

a cosine on a smoothly warped clock. ``phi(0) = 0`` (maximum), ``phi(d) = 1`` (minimum),
``phi(1) = 2``, and ``phi' = 2 + A sin 2 pi tau > 0`` when ``|A| < 2`` (rise and fall
durations between about 29 % and 71 % of the cycle), so the curve is infinitely smooth,
periodic, and its first and second derivatives below are exact.

Load. Stance starts at phase 0 at ``F_swing``, rises to the first peak, falls to the
mid-stance valley, rises to the second peak and falls back to ``F_swing`` at the end of
stance, where it stays through the swing phase. Between consecutive key points the load
follows the quintic smoothstep ``S(s) = 10 s^3 - 15 s^4 + 6 s^5``, so it passes exactly
through every key value, is monotone between them, has zero slope at the peaks and the valley,
and is twice continuously differentiable and periodic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ..errors import LimitError, MotionError, ParameterError
from ..io import DEFAULT_MAX_SAMPLES
from .orientation import OrientationMotion, make_motion

__all__ = ["AxisWave", "IsoCycle", "angle_wave", "iso_load", "iso14242_motion", "iso14242_samples",
           "iso14242_times", "iso14242_block"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class AxisWave:
    """Extremes of one Euler angle [deg] and their phases [fraction of the cycle]."""

    max_deg: float
    max_phase: float
    min_deg: float
    min_phase: float


@dataclass(frozen=True)
class IsoCycle:
    """Key points of the cycle model; every default value is a documented choice."""

    period_s: float = 1.0
    fe: AxisWave = field(default_factory=lambda: AxisWave(25.0, 0.0, -18.0, 0.55))
    aa: AxisWave = field(default_factory=lambda: AxisWave(7.0, 0.32, -4.0, 0.75))
    ier: AxisWave = field(default_factory=lambda: AxisWave(2.0, 0.10, -10.0, 0.58))
    swing_load_N: float = 300.0
    peak_load_N: float = 3000.0
    peak_phases: tuple[float, float] = (0.12, 0.50)
    valley_load_N: float = 1500.0
    valley_phase: float = 0.31
    stance_end_phase: float = 0.62


def _warp_coefficient(wave: AxisWave, name: str) -> float:
    d = (wave.min_phase - wave.max_phase) % 1.0
    if not wave.max_deg > wave.min_deg:
        raise ParameterError(f"{name}: max_deg ({wave.max_deg}) must exceed min_deg ({wave.min_deg})")
    denom = 1.0 - np.cos(2 * np.pi * d)
    a = 2 * np.pi * (1 - 2 * d) / denom if denom > 0 else np.inf
    if not abs(a) < 2.0:
        raise ParameterError(
            f"{name}: the minimum is {d:.2f} of a cycle after the maximum; the smooth model needs "
            "between about 0.29 and 0.71"
        )
    return float(a)


def angle_wave(t: Array, period: float, wave: AxisWave, name: str = "angle") -> tuple[Array, Array, Array]:
    """Angle [rad], rate [rad/s] and acceleration [rad/s^2] of one axis at times ``t (n,)`` [s]."""
    a_warp = _warp_coefficient(wave, name)
    mid = np.deg2rad(0.5 * (wave.max_deg + wave.min_deg))
    amp = np.deg2rad(0.5 * (wave.max_deg - wave.min_deg))
    tau = np.mod(np.asarray(t, dtype=float) / period - wave.max_phase, 1.0)
    two_pi_tau = 2 * np.pi * tau
    phi = 2 * tau + a_warp * (1 - np.cos(two_pi_tau)) / (2 * np.pi)
    dphi = 2 + a_warp * np.sin(two_pi_tau)
    ddphi = 2 * np.pi * a_warp * np.cos(two_pi_tau)
    s, c = np.sin(np.pi * phi), np.cos(np.pi * phi)
    q = mid + amp * c
    qd = -amp * np.pi * s * dphi / period
    qdd = -amp * np.pi * (np.pi * c * dphi**2 + s * ddphi) / period**2
    return q, qd, qdd


def iso_load(t: Array, cycle: IsoCycle = IsoCycle()) -> Array:
    """Hydraulic load [N] at times ``t (n,)`` [s]: double peak in stance, ``F_swing`` in swing."""
    knots = np.array([0.0, cycle.peak_phases[0], cycle.valley_phase, cycle.peak_phases[1], cycle.stance_end_phase, 1.0])
    if not np.all(np.diff(knots) > 0):
        raise ParameterError(
            "load phases: need 0 < first peak < valley < second peak < end of stance < 1, got "
            f"{knots[1:-1].tolist()}"
        )
    values = np.array(
        [cycle.swing_load_N, cycle.peak_load_N, cycle.valley_load_N, cycle.peak_load_N, cycle.swing_load_N, cycle.swing_load_N]
    )
    tau = np.mod(np.asarray(t, dtype=float) / cycle.period_s, 1.0)
    seg = np.clip(np.searchsorted(knots, tau, side="right") - 1, 0, len(knots) - 2)
    s = (tau - knots[seg]) / (knots[seg + 1] - knots[seg])
    smooth = s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
    return values[seg] + (values[seg + 1] - values[seg]) * smooth


def iso14242_samples(cycles: float, samples_per_cycle: int, max_samples: int = DEFAULT_MAX_SAMPLES) -> int:
    """The number of samples of ``cycles`` periods at ``samples_per_cycle`` (both ends included),
    checked before anything is allocated: ``cycles`` finite and > 0, at least 2 samples, at most
    ``max_samples`` (a :class:`LimitError` that says how to raise it)."""
    if isinstance(cycles, bool) or not isinstance(cycles, (int, float, np.integer, np.floating)):
        raise MotionError(f"cycles: expected a number, got {type(cycles).__name__}")
    if isinstance(samples_per_cycle, bool) or not isinstance(samples_per_cycle, (int, np.integer)):
        raise MotionError(f"samples per cycle: expected an integer, got {type(samples_per_cycle).__name__}")
    if not (math.isfinite(cycles) and cycles > 0):
        raise MotionError(f"cycles: must be a finite number > 0, got {cycles}")
    if samples_per_cycle < 2:
        raise MotionError(f"samples per cycle: must be >= 2, got {samples_per_cycle}")
    intervals = float(cycles) * float(samples_per_cycle)
    if not intervals <= max_samples:
        raise LimitError(
            f"cycles x samples per cycle = {intervals:.4g} samples exceeds the limit max_samples = {max_samples} "
            "(raise it with [limits] max_samples in the parameter file or --limit max_samples=N)"
        )
    n = int(round(intervals)) + 1
    if n < 2:
        raise MotionError(
            f"cycles x samples per cycle = {intervals:.4g} gives fewer than 2 samples; give more cycles or samples per cycle"
        )
    if n > max_samples:
        raise LimitError(
            f"{n} samples exceed the limit max_samples = {max_samples} "
            "(raise it with [limits] max_samples in the parameter file or --limit max_samples=N)"
        )
    return n


def iso14242_block(t: Array, cycle: IsoCycle = IsoCycle()) -> OrientationMotion:
    """The cycle model at the times ``t (n,)`` [s] (one block of a long run)."""
    waves = [angle_wave(t, cycle.period_s, w, name) for w, name in ((cycle.fe, "fe"), (cycle.aa, "aa"), (cycle.ier, "ier"))]
    q = np.stack([w[0] for w in waves], axis=-1)
    qd = np.stack([w[1] for w in waves], axis=-1)
    qdd = np.stack([w[2] for w in waves], axis=-1)
    return make_motion(t, q, qd, qdd, iso_load(t, cycle))


def iso14242_times(n: int, cycles: float, cycle: IsoCycle = IsoCycle(), start: int = 0, stop: int | None = None) -> Array:
    """Sample times ``start:stop`` of ``n`` equally spaced samples over ``cycles`` periods [s]
    (the same values as ``np.linspace(0, cycles T, n)[start:stop]``)."""
    stop = n if stop is None else min(stop, n)
    step = cycles * cycle.period_s / (n - 1)
    t = np.arange(start, stop, dtype=float) * step
    if stop == n:
        t[-1] = cycles * cycle.period_s
    return t


def iso14242_motion(
    cycles: float = 1.0, samples_per_cycle: int = 1000, cycle: IsoCycle = IsoCycle(),
    max_samples: int = DEFAULT_MAX_SAMPLES,
) -> OrientationMotion:
    """The cycle model sampled at ``samples_per_cycle`` points per period over ``cycles`` periods.

    Angles are returned in the order (alpha FE, beta AA, gamma IER). More than ``max_samples``
    samples is a :class:`LimitError`, raised before allocating.
    """
    n = iso14242_samples(cycles, samples_per_cycle, max_samples)
    return iso14242_block(iso14242_times(n, cycles, cycle), cycle)

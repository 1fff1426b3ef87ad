"""An excitation motion and load for identifying the hip simulator (optimised Fourier series),
on the engine's kinematics and regressor of the hip's description.

Each Euler angle and the load is a bounded Fourier series (:func:`bounded_fourier`), so the
angles stay inside their ranges and the load inside ``[F_min, F_max]`` by construction. The
slider speeds scale with ``1 / T`` and the accelerations with ``1 / T^2`` along a fixed path,
so each candidate's period is stretched from the requested one just enough to respect the
slider speed and acceleration limits. The cost is ``log10`` of the condition number of the
column-scaled regressor restricted to the parameters that a generic motion separates
(independent columns at a rank tolerance of 1e-3, so that pairs only separable near velocity
reversals do not dominate), plus a quadratic penalty where ``cond(J)`` exceeds its limit and
``(stretch - 1)^2``, which keeps the period near the requested one. An
unreachable or singular pose costs 1e6.

Slider speeds and accelerations are the actuated joints' rates of the engine's kinematics
(:func:`pkmdyn.multibody.solve_kinematics`); ``J`` maps the platform's angular velocity to the
slider speeds, ``J = J_ax E^-1`` with ``J_ax`` the engine's actuator Jacobian (slider rates per
Euler-angle rate) and ``E`` the Euler rates' map to the angular velocity
(:func:`pkmdyn.spatial.euler_kinematics`); the regressor is the engine's
(:func:`.identify_view.hip_regressor`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import PkmdynError, ParameterError
from ...identify._base import base_parameters
from ...identify._excite import bounded_fourier, max_evaluations, minimize_excitation
from ...profiles.orientation import OrientationMotion, make_motion
from .paper import euler_rate_map
from .identify_view import (Which, engine_kinematics, hip_regressor, parameter_names,
                            regressor_mechanism)
from .params import HipModel

__all__ = ["ExcitationLimits", "HipExcitation", "excitation_motion", "design_excitation", "design_work", "slider_rates",
           "MAX_HARMONICS", "MAX_DESIGN_SAMPLES", "MAX_ITERATIONS", "MAX_STARTS", "MAX_WORK"]

Array = NDArray[np.float64]
_SELECT_TOL = 1e-3
_DENSE = 4000  # samples per period of the final limit check
_STRETCH_MAX = 1e6  # a period stretched further than this counts as unreachable

#: bounds of the design, checked by :func:`design_excitation` (the command line states them)
from .identify_bounds import (MAX_COND_J, MAX_DESIGN_SAMPLES, MAX_HARMONICS, MAX_ITERATIONS, MAX_LOAD_N,  # noqa: E402
                     MAX_PERIOD_S, MAX_SLIDER_ACCEL_M_S2, MAX_SLIDER_SPEED_M_S, MAX_STARTS, MAX_WORK, MIN_PERIOD_S)


@dataclass(frozen=True)
class ExcitationLimits:
    """Ranges and limits of an excitation. Angles [deg] (FE, AA, IER; the ISO 14242-1 ranges by
    default), load [N], slider speed [m/s] and acceleration [m/s^2], and ``cond(J)``."""

    alpha_deg: tuple[float, float] = (-18.0, 25.0)
    beta_deg: tuple[float, float] = (-4.0, 7.0)
    gamma_deg: tuple[float, float] = (-10.0, 2.0)
    load_N: tuple[float, float] = (300.0, 3000.0)
    slider_speed_m_s: float = 0.3
    slider_accel_m_s2: float = 3.0
    cond_J: float = 10.0

    def check(self) -> None:
        """Every range finite, ordered and inside its plausible bounds (angles within +-180 deg,
        load in [0, MAX_LOAD_N]); every limit finite and > 0, ``cond_J >= 1``."""
        for name in ("alpha_deg", "beta_deg", "gamma_deg", "load_N"):
            lo, hi = (float(x) for x in getattr(self, name))
            if not (np.isfinite(lo) and np.isfinite(hi) and hi > lo):
                raise ParameterError(f"{name} range: need a finite maximum above the minimum, got {lo:g}..{hi:g}")
            if name != "load_N" and not (-180.0 <= lo and hi <= 180.0):
                raise ParameterError(f"{name} range: {lo:g}..{hi:g} deg is outside -180..180 deg")
        if self.load_N[0] < 0:
            raise ParameterError(f"load_N range: the load must be >= 0, got {self.load_N[0]:g}")
        if self.load_N[1] > MAX_LOAD_N:
            raise ParameterError(f"load_N range: {self.load_N[1]:g} N is above the limit {MAX_LOAD_N:g} N")
        for name, top in (("slider_speed_m_s", MAX_SLIDER_SPEED_M_S), ("slider_accel_m_s2", MAX_SLIDER_ACCEL_M_S2),
                          ("cond_J", MAX_COND_J)):
            v = float(getattr(self, name))
            if not (np.isfinite(v) and v > 0):
                raise ParameterError(f"{name}: must be finite and > 0, got {v:g}")
            if v > top:
                raise ParameterError(f"{name}: {v:g} is above the limit {top:g}")
        if self.cond_J < 1:
            raise ParameterError(f"cond_J: {self.cond_J:g} is below 1, which no pose reaches")


@dataclass(frozen=True)
class HipExcitation:
    """An optimised excitation: ``coeffs (4, 2L+1)`` (alpha, beta, gamma, load), ``period_s`` (after
    stretching),
    ``limits``, the condition number reached and the parameters it was designed for."""

    coeffs: Array
    period_s: float
    limits: ExcitationLimits
    condition_number: float
    parameters: tuple[str, ...]


def excitation_motion(coeffs: Array, period: float, limits: ExcitationLimits, t: Array) -> OrientationMotion:
    """The motion and load of coefficients ``coeffs (4, 2L+1)`` at times ``t (n,)`` [s]."""
    out = []
    for k, name in enumerate(("alpha_deg", "beta_deg", "gamma_deg")):
        lo, hi = np.deg2rad(getattr(limits, name))
        out.append(bounded_fourier(t, period, coeffs[k], lo, hi))
    load = bounded_fourier(t, period, coeffs[3], *limits.load_N)[0]
    q, qd, qdd = (np.stack([o[i] for o in out], axis=-1) for i in range(3))
    return make_motion(t, q, qd, qdd, load)


def slider_rates(mech: Any, kin: Any, sequence: str) -> tuple[Array, Array, Array]:
    """Slider speed and acceleration ``(n, 3)`` [m/s, m/s^2] and ``cond(J) (n,)`` of the engine's
    kinematics ``kin`` of ``mech`` (module docstring; Euler angles in ``sequence``)."""
    x = kin.x
    n = x.shape[0]
    E = euler_rate_map(sequence, x)
    J = np.linalg.solve(np.swapaxes(E, 1, 2), np.swapaxes(kin.J_ax, 1, 2)).swapaxes(1, 2)
    cond = np.linalg.cond(J) if n else np.zeros(0)
    return kin.act_qd, kin.act_qdd, cond


def _penalty(value: float, limit: float) -> float:
    return 0.0 if value <= limit else 10.0 * (min(value / limit, 1e100) - 1.0) ** 2


def design_work(harmonics: int, samples: int, iterations: int, starts: int) -> tuple[int, int]:
    """``(evaluations, work)``: the most cost evaluations of a design (the optimiser's, plus up to
    50 draws that choose the parameters and the final check) and those times the design
    samples, the measure bounded by :data:`MAX_WORK`."""
    n = max_evaluations(4 * (2 * harmonics + 1), starts, iterations) + 51
    return n, n * samples


def _check_design(period_s: float, harmonics: int, samples: int, iterations: int, starts: int, seed: int) -> None:
    period_s = float(period_s)
    if not (np.isfinite(period_s) and MIN_PERIOD_S <= period_s <= MAX_PERIOD_S):
        raise ParameterError(f"period: {period_s:g} s is outside {MIN_PERIOD_S:g}..{MAX_PERIOD_S:g} s")
    for name, v, lo, hi in (("harmonics", harmonics, 1, MAX_HARMONICS), ("samples", samples, 16, MAX_DESIGN_SAMPLES),
                            ("iterations", iterations, 0, MAX_ITERATIONS), ("starts", starts, 1, MAX_STARTS)):
        if isinstance(v, bool) or int(v) != v or not lo <= v <= hi:
            raise ParameterError(f"{name}: {v} is outside {lo}..{hi}")
    if samples < 8 * harmonics:
        raise ParameterError(f"harmonics/samples: need >= 8 samples per harmonic, got {harmonics}/{samples}")
    if isinstance(seed, bool) or int(seed) != seed or seed < 0:
        raise ParameterError(f"seed: {seed} must be a whole number >= 0")
    n, work = design_work(harmonics, samples, iterations, starts)
    if work > MAX_WORK:
        raise ParameterError(
            f"design effort: up to {n} cost evaluations x {samples} samples = {work:,} is above the limit "
            f"{MAX_WORK:,}; lower the iterations, starts, harmonics or design samples")


def design_excitation(
    model: HipModel,
    which: Which = "all",
    limits: ExcitationLimits = ExcitationLimits(),
    period_s: float = 2.0,
    harmonics: int = 3,
    samples: int = 120,
    iterations: int = 15,
    starts: int = 1,
    seed: int = 0,
    progress: Callable[[int], None] | None = None,
) -> HipExcitation:
    """Optimise the coefficients (module docstring) over one period sampled ``samples`` times.

    Sizes are bounded (``harmonics <= MAX_HARMONICS``, ``samples <= MAX_DESIGN_SAMPLES``,
    ``iterations <= MAX_ITERATIONS``, ``starts <= MAX_STARTS``, :func:`design_work` <=
    :data:`MAX_WORK`); ``progress``, if given, is called with 1 before each evaluation of a
    candidate motion, at most :func:`design_work` ``[0]`` times in all (a true bound)."""
    limits.check()
    _check_design(period_s, harmonics, samples, iterations, starts, seed)
    names = parameter_names(which)
    mech = regressor_mechanism(model)
    seq = model.geometry.euler_sequence
    pmap: list[Any] = []  # the parameter map, the same for every motion: made once
    t = np.linspace(0.0, period_s, samples, endpoint=False)
    shape = (4, 2 * harmonics + 1)
    selected: list[int] | None = None

    def evaluate(z: Array) -> tuple[float, Array | None, float, float]:
        """Penalty, stacked regressor, stretched period and max cond(J) of coefficients ``z``."""
        if progress is not None:
            progress(1)
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                motion = excitation_motion(z.reshape(shape), period_s, limits, t)
                Ld, Ldd, _ = slider_rates(mech, engine_kinematics(mech, motion), seq)
                stretch = max(1.0, float(np.max(np.abs(Ld))) / limits.slider_speed_m_s,
                              float(np.sqrt(np.max(np.abs(Ldd)) / limits.slider_accel_m_s2)))
                if not stretch <= _STRETCH_MAX:  # NaN included
                    return 1e6, None, period_s, np.inf
                period = period_s * stretch * (1.0 + 1e-9)
                motion = excitation_motion(z.reshape(shape), period, limits, t * (period / period_s))
                kin = engine_kinematics(mech, motion)
                _, _, cond = slider_rates(mech, kin, seq)
                W = hip_regressor(model, motion, names, mech, kin, pmap).stacked()
        except (PkmdynError, np.linalg.LinAlgError, FloatingPointError, OverflowError):
            return 1e6, None, period_s, np.inf
        if not (np.all(np.isfinite(W)) and np.all(np.isfinite(cond))):
            return 1e6, None, period_s, np.inf  # a model whose values overflow on this motion
        cond_J = float(np.max(cond))
        return _penalty(cond_J, limits.cond_J) + (stretch - 1.0) ** 2, W, period, cond_J

    def log_cond(W: Array) -> float:
        A = W[:, selected]
        norms = np.linalg.norm(A, axis=0)
        if not np.all(norms > 0):
            return 1e3
        try:
            s = np.linalg.svd(A / norms, compute_uv=False)
        except np.linalg.LinAlgError:
            return 1e3
        return float(np.log10(s[0] / s[-1])) if s[-1] > 0 else 1e3

    def cost(z: Array) -> float:
        pen, W, _, _ = evaluate(z)
        return pen if W is None else log_cond(W) + pen

    rng = np.random.default_rng(seed)
    # parameters a generic motion separates: chosen on a random reachable draw
    for _ in range(50):
        z0 = rng.normal(0.0, 0.8, shape[0] * shape[1])
        pen, W, _, _ = evaluate(z0)
        if W is not None:
            break
    else:
        raise ParameterError("excitation: no reachable motion found within the given ranges")
    selected = list(base_parameters(W, names, _SELECT_TOL).independent)
    z, c = minimize_excitation(cost, shape[0] * shape[1], rng, starts=starts, iterations=iterations)
    pen, W, period, cond_J = evaluate(z)
    if W is not None:  # limits checked again on a dense grid: the design grid can miss a peak
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            dense = np.linspace(0.0, period_s, _DENSE, endpoint=False)
            try:
                Ld, Ldd, cond = slider_rates(mech, engine_kinematics(
                    mech, excitation_motion(z.reshape(shape), period_s, limits, dense)), seq)
            except PkmdynError as exc:
                raise ParameterError(f"excitation: the designed motion leaves the reachable poses ({exc})") from None
        stretch = max(1.0, float(np.max(np.abs(Ld))) / limits.slider_speed_m_s,
                      float(np.sqrt(np.max(np.abs(Ldd)) / limits.slider_accel_m_s2)))
        if not stretch <= _STRETCH_MAX:
            raise ParameterError("excitation: the slider limits need a period stretched beyond "
                                 f"{_STRETCH_MAX:g} times the requested one; widen the limits")
        period = max(period, period_s * stretch * (1.0 + 1e-9))
        cond_J = max(cond_J, float(np.max(cond)))
    if W is None or cond_J > limits.cond_J:
        raise ParameterError("excitation: the optimiser found no motion within every limit; widen the limits")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        final = excitation_motion(z.reshape(shape), period, limits, t * (period / period_s))
        W = hip_regressor(model, final, names, mech, None, pmap).stacked()
    return HipExcitation(z.reshape(shape), period, limits, float(10 ** log_cond(W)), tuple(names[k] for k in selected))

"""The identification report (``identification.json``): estimates, base parameters, fit figures.

Machine-independent: it reads the base-parameter structure and the estimate. A parameter
that is not separable never gets a number of its own here; it appears only inside the
combinations (base parameters) it belongs to.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._base import BaseParameters
from ._solve import Estimate

__all__ = ["identification_report", "active_constraints", "explained_percent", "fit_failure", "MIN_EXPLAINED_PERCENT"]

Array = NDArray[np.float64]

#: the least share of each actuator's measured effort (its sum of squares) that an identified
#: model must explain for the identification to mean something
MIN_EXPLAINED_PERCENT = 50.0


def explained_percent(measured: Array, residual: Array) -> Array:
    """Per actuator, ``100 (1 - |residual|^2 / |measured|^2)`` [%] over the samples
    (``measured, residual (n, nu)``): 100 for a perfect fit, 0 for a model that explains nothing,
    negative for one that is worse than predicting zero (e.g. sign-flipped efforts)."""
    m2 = np.sum(np.asarray(measured, dtype=float) ** 2, axis=0)
    r2 = np.sum(np.asarray(residual, dtype=float) ** 2, axis=0)
    return np.where(m2 > 0, 100.0 * (1.0 - r2 / np.where(m2 > 0, m2, 1.0)), np.where(r2 > 0, -np.inf, 100.0))


def fit_failure(base: BaseParameters, estimate: Estimate, actuators: tuple[str, ...], measured: Array,
                residual: Array, min_explained: float = MIN_EXPLAINED_PERCENT) -> str | None:
    """Why an identification means nothing, or None: an actuator whose measured effort is zero
    throughout; every identifiable direction (as many solver coordinates as the rank) on a
    bound, i.e. the data ask for an unphysical machine and get the bounds; or an actuator whose
    effort the identified model explains less than ``min_explained`` per cent of."""
    measured = np.asarray(measured, dtype=float)
    for a, name in enumerate(actuators):
        if not np.any(measured[:, a]):
            return f"column {name!r} is zero in every row: no measured effort to identify from"
    if len(estimate.at_bound) >= base.rank:
        names = [base.names[k] for k in estimate.at_bound[:3]]
        more = f" and {len(estimate.at_bound) - 3} more" if len(estimate.at_bound) > 3 else ""
        return (f"identification failed: every identifiable parameter is on a bound of the physical machine "
                f"({', '.join(names)}{more}); the measured efforts fit no physical machine (sign-flipped or of "
                "another machine?)")
    share = explained_percent(measured, residual)
    worst = int(np.argmin(share))
    if not share[worst] >= min_explained:
        shown = f"{share[worst]:.3g} %" if np.isfinite(share[worst]) else "nothing"
        return (f"identification failed: the identified model explains {shown} of {actuators[worst]} (sum of squares; "
                f"at least {min_explained:g} % needed): the fit means nothing (sign-flipped, scaled or mislabelled "
                "efforts, or a motion that does not belong to them?)")
    return None


def active_constraints(names: tuple[str, ...], T: Array, at_bound: tuple[int, ...]) -> list[str]:
    """The consistency constraints the estimate sits on, written in the physical parameters.

    A solver coordinate that maps to one parameter is that parameter's bound; one that maps to
    a principal-inertia triplet (``T`` row pattern 0 1 1) is a triangle inequality.
    """
    out = []
    for k in at_bound:
        rows = np.flatnonzero(T[:, k])
        if rows.size == 1:
            out.append(f"{names[rows[0]]} at its lower bound")
        else:
            # S_k = (I_a + I_b - I_k) / 2 for the two other axes a, b
            trio = [int(j) for j in np.flatnonzero(np.any(T[:, rows] != 0, axis=1))]
            own = next(j for j in trio if T[j, k] == 0)
            others = [j for j in trio if j != own]
            out.append(f"{names[others[0]]} + {names[others[1]]} = {names[own]} (triangle inequality active)")
    return out


def _percent(r: float, m: float) -> float | None:
    """``100 r / m``; None (JSON null: undefined) when ``m`` is 0 and ``r`` is not, never 0."""
    if m > 0:
        return float(100.0 * r / m)
    return 0.0 if r == 0 else None


def identification_report(
    base: BaseParameters,
    estimate: Estimate,
    prior: Array,
    actuators: tuple[str, ...],
    measured_rms: Array,
    residual_rms: Array,
    T: Array,
    z: float = 1.96,
) -> dict[str, Any]:
    """The JSON-ready report of one identification (``docs/file_formats.md``); intervals are
    ``estimate +- z * standard_error`` (z = 1.96: 95 % for normal errors)."""
    names = base.names
    separable = set(base.separable())
    sep_out: dict[str, Any] = {}
    combos = []
    for i, j in enumerate(base.independent):
        est, se = float(estimate.base_values[i]), float(estimate.base_std[i])
        ci = [est - z * se, est + z * se]
        if j in separable:
            sep_out[names[j]] = {
                "estimate": est, "standard_error": se, "confidence_interval_95": ci, "parameter_file_value": float(prior[j])
            }
        else:
            combos.append(
                {
                    "combination": base.describe(i),
                    "terms": base.terms(i),
                    "estimate": est,
                    "standard_error": se,
                    "confidence_interval_95": ci,
                    "parameter_file_value": float(base.values(prior)[i]),
                }
            )
    in_combo = sorted({n for c in combos for n in c["terms"]})
    return {
        "parameters_asked": list(names),
        "rank": base.rank,
        "rank_tolerance": base.rank_tol,
        "condition_number": base.condition_number,
        "residual_rms_Nm": {a: float(v) for a, v in zip(actuators, residual_rms)},
        "measured_rms_Nm": {a: float(v) for a, v in zip(actuators, measured_rms)},
        "residual_rms_percent": {a: _percent(r, m) for a, r, m in zip(actuators, residual_rms, measured_rms)},
        "normalised_residual_std": estimate.sigma,
        "degrees_of_freedom": estimate.dof,
        "separable": sep_out,
        "combinations": combos,
        "not_separable": in_combo,
        "not_excited": [names[k] for k in base.unexcited],
        "active_constraints": active_constraints(names, T, estimate.at_bound),
    }

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

__all__ = ["identification_report", "active_constraints"]

Array = NDArray[np.float64]


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
        "residual_rms_percent": {a: float(100 * r / m) if m > 0 else 0.0 for a, r, m in zip(actuators, residual_rms, measured_rms)},
        "normalised_residual_std": estimate.sigma,
        "degrees_of_freedom": estimate.dof,
        "separable": sep_out,
        "combinations": combos,
        "not_separable": in_combo,
        "not_excited": [names[k] for k in base.unexcited],
        "active_constraints": active_constraints(names, T, estimate.at_bound),
    }

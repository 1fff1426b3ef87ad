"""Validation of the hip identification on synthetic measurements (``docs/identification.md``).

A known machine that is not the default one (``truth``) generates torques along an
identification motion; Gaussian noise is added; the parameters are identified from those
torques with the default parameter file as the prior; the identified model then predicts the
torques of the same machine along a *different* motion (the ISO 14242-1 cycle model), and over
repeated noise draws the fraction of base-parameter estimates whose interval
``estimate +- z * standard_error`` holds the true value is counted. The torques are the
engine's inverse dynamics of the machine's description (:func:`.identify_view.engine_torques`,
joint reactions with friction; not the regressor). Run
``python -m pkmdyn.machines.hip_simulator.identify_study`` to reproduce the figures of the
documentation.
"""

from __future__ import annotations

import copy
import json
import sys
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...profiles.iso14242 import iso14242_motion
from ...profiles.orientation import OrientationMotion
from .identify_excite import ExcitationLimits, design_excitation, excitation_motion
from .identify_view import Which, engine_torques, identify_hip, parameter_vector
from .params import HipModel, default_params_dict, model_from_dict

__all__ = ["truth_description", "StudyResult", "validation_study"]

Array = NDArray[np.float64]


def truth_description() -> dict[str, Any]:
    """The synthetic machine: the paper's, with a 4 kg platform and every friction non-default."""
    d = copy.deepcopy(default_params_dict())
    d["inertia"]["platform_mass_kg"] = 4.0
    d["friction"].update(
        hip_coefficient=0.12,
        thrust_coefficient=0.035,
        slider_coulomb_N=4.0,
        slider_viscous_Ns_m=30.0,
        screw_coulomb_Nm=0.01,
        screw_viscous_Nms_rad=2e-5,
        spherical_coulomb_Nm=0.15,
        spherical_viscous_Nms_rad=0.02,
        universal_coulomb_Nm=0.1,
        universal_viscous_Nms_rad=0.01,
    )
    return d


@dataclass(frozen=True)
class StudyResult:
    """Figures of a study: held-out prediction error (RMS %, per motor, first draw and worst
    draw), coverage of the ``z``-intervals of the separable and combined base parameters, and
    the estimation motion's regressor condition number and rank; ``per_parameter`` maps each base
    parameter to its true value, mean estimate, empirical and mean reported standard error and
    coverage."""

    heldout_rms_percent: Array
    heldout_rms_percent_worst: Array
    prior_heldout_rms_percent: Array
    coverage: float
    coverage_z: float
    intervals: int
    condition_number: float
    rank: int
    parameters: int
    noise_percent: float
    draws: int
    per_parameter: dict


def _torques(model: HipModel, motion: OrientationMotion) -> Array:
    return engine_torques(model, motion)


def validation_study(
    which: Which = "friction",
    noise_percent: float = 2.0,
    draws: int = 50,
    samples: int = 1000,
    coverage_z: float = 1.96,
    iterations: int = 15,
    seed: int = 1,
) -> StudyResult:
    """Run the study of the module docstring. Noise: standard deviation ``noise_percent`` of the
    RMS torque of each motor along the identification motion."""
    truth = model_from_dict(truth_description(), "synthetic machine")
    prior = model_from_dict(default_params_dict(), "built-in parameters")
    ex = design_excitation(prior, which, ExcitationLimits(), samples=200, iterations=iterations, starts=1, seed=seed)
    t = np.linspace(0.0, 2 * ex.period_s, samples)
    motion = excitation_motion(ex.coeffs, ex.period_s, ex.limits, t)
    heldout = iso14242_motion(2.0, 500)
    tau = _torques(truth, motion)
    tau_held = _torques(truth, heldout)
    held_rms = np.sqrt(np.mean(tau_held**2, axis=0))
    sd = 0.01 * noise_percent * np.sqrt(np.mean(tau**2, axis=0))
    rng = np.random.default_rng(seed)
    hits = total = 0
    first = None
    worst = np.zeros(3)
    cond, rank, p = np.nan, 0, 0
    est_all, se_all = [], []
    for k in range(draws):
        res = identify_hip(prior, motion, tau + rng.normal(0.0, 1.0, tau.shape) * sd, which)
        names = res.names
        true_b = res.base.values(parameter_vector(truth, names))
        inside = np.abs(res.estimate.base_values - true_b) <= coverage_z * res.estimate.base_std
        est_all.append(res.estimate.base_values)
        se_all.append(res.estimate.base_std)
        hits += int(np.sum(inside))
        total += inside.size
        err = 100 * np.sqrt(np.mean((_torques(res.model, heldout) - tau_held) ** 2, axis=0)) / held_rms
        worst = np.maximum(worst, err)
        if first is None:
            first, cond, rank, p = err, res.base.condition_number, res.base.rank, len(names)
    prior_err = 100 * np.sqrt(np.mean((_torques(prior, heldout) - tau_held) ** 2, axis=0)) / held_rms
    est_all, se_all = np.array(est_all), np.array(se_all)
    per = {
        res.base.describe(i): {
            "true": float(true_b[i]),
            "mean_estimate": float(est_all[:, i].mean()),
            "empirical_std": float(est_all[:, i].std(ddof=1)) if draws > 1 else 0.0,
            "mean_standard_error": float(se_all[:, i].mean()),
            "coverage": float(np.mean(np.abs(est_all[:, i] - true_b[i]) <= coverage_z * se_all[:, i])),
        }
        for i in range(res.base.rank)
    }
    return StudyResult(first, worst, prior_err, hits / total, coverage_z, total, cond, rank, p, noise_percent, draws, per)


if __name__ == "__main__":  # pragma: no cover - a documentation script
    out = {}
    for which in sys.argv[1:] or ["friction", "all"]:
        r = validation_study(which)
        out[which] = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.__dict__.items()}
    print(json.dumps(out, indent=2))

"""Identification of friction and inertia from measured actuator efforts.

Machine-independent parts: the regressor of an affine effort map (:mod:`._regressor`), base
parameters by a rank-revealing decomposition (:mod:`._base`), physically consistent
constrained least squares with standard errors (:mod:`._solve`), bounded Fourier excitation
(:mod:`._excite`) and the report (:mod:`._report`); described mechanisms are identified by
:mod:`.described` (their regressor is :func:`pkmdyn.multibody.analyses.regressor.regressor`), and a machine
may name the result in its own parameters (its folder under :mod:`pkmdyn.machines`). See
``docs/identification.md``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._base import DEFAULT_RANK_TOL, BaseParameters, base_parameters
    from ._excite import bounded_fourier, minimize_excitation
    from ._identify import fit_regressor
    from ._regressor import Regressor, affine_regressor
    from ._report import explained_percent, identification_report
    from ._solve import Estimate, constrained_least_squares

__all__ = [
    "Regressor",
    "affine_regressor",
    "BaseParameters",
    "base_parameters",
    "DEFAULT_RANK_TOL",
    "fit_regressor",
    "identification_report",
    "explained_percent",
    "Estimate",
    "constrained_least_squares",
    "bounded_fourier",
    "minimize_excitation",
]

#: where each public name lives, imported on first use (PEP 562), so that importing a light
#: submodule (``pkmdyn.identify.plots``) does not load the solvers
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("Regressor", "affine_regressor"), "._regressor"),
    **dict.fromkeys(("BaseParameters", "base_parameters", "DEFAULT_RANK_TOL"), "._base"),
    **dict.fromkeys(("Estimate", "constrained_least_squares"), "._solve"),
    **dict.fromkeys(("bounded_fourier", "minimize_excitation"), "._excite"),
    "fit_regressor": "._identify",
    **dict.fromkeys(("identification_report", "explained_percent"), "._report"),
})

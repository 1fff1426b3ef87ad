"""Identification of friction and inertia from measured actuator efforts.

Machine-independent parts: the regressor of an affine effort map (:mod:`._regressor`), base
parameters by a rank-revealing decomposition (:mod:`._base`), physically consistent
constrained least squares with standard errors (:mod:`._solve`), bounded Fourier excitation
(:mod:`._excite`) and the report (:mod:`._report`). The hip simulator is the first machine
(:mod:`.hip`, :mod:`.hip_excite`, :mod:`.hip_run`). See ``docs/identification.md``.
"""

from ._base import DEFAULT_RANK_TOL, BaseParameters, base_parameters
from ._excite import bounded_fourier, minimize_excitation
from ._regressor import Regressor, affine_regressor
from ._solve import Estimate, constrained_least_squares

__all__ = [
    "Regressor",
    "affine_regressor",
    "BaseParameters",
    "base_parameters",
    "DEFAULT_RANK_TOL",
    "Estimate",
    "constrained_least_squares",
    "bounded_fourier",
    "minimize_excitation",
]

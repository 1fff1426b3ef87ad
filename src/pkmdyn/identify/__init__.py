"""Identification of friction and inertia from measured actuator efforts.

Machine-independent parts: the regressor of an affine effort map (:mod:`._regressor`), base
parameters by a rank-revealing decomposition (:mod:`._base`), physically consistent
constrained least squares with standard errors (:mod:`._solve`), bounded Fourier excitation
(:mod:`._excite`) and the report (:mod:`._report`). The hip simulator is the first machine
(:mod:`.hip`, :mod:`.hip_excite`, :mod:`.hip_run`). See ``docs/identification.md``.
"""

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

#: where each public name lives; loaded on first use (PEP 562), so that importing a light
#: submodule (``pkmdyn.identify.bounds``) does not load the solvers
_WHERE = {"Regressor": "._regressor", "affine_regressor": "._regressor", "BaseParameters": "._base",
          "base_parameters": "._base", "DEFAULT_RANK_TOL": "._base", "Estimate": "._solve",
          "constrained_least_squares": "._solve", "bounded_fourier": "._excite", "minimize_excitation": "._excite",
          "fit_regressor": "._identify", "identification_report": "._report", "explained_percent": "._report"}


def __getattr__(name: str) -> object:
    if name in _WHERE:
        from importlib import import_module

        return getattr(import_module(_WHERE[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

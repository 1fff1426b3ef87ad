"""Identification of any machine from measured actuator efforts, through the machine verbs.

Given a machine (an object with the verbs of :class:`pkmdyn.machine_protocol.MachineDynamics`), a map
``model_with(theta)`` from the parameter vector to a model whose inverse dynamics is affine in
``theta``, and samples ``q, qd, qdd, load`` with measured efforts ``u (n, nu)``:

1. regressor ``u = Y theta + u_0`` by :func:`affine_regressor` over ``machine.inverse_dynamics``;
2. base parameters by :func:`base_parameters`;
3. the constrained fit :func:`constrained_least_squares`, then once more with each actuator's
   rows weighted by the inverse RMS of its first-pass residual (actuators may differ in noise).

Bad input raises :class:`MotionError` naming ``source``: efforts of the wrong shape or not
finite (row and actuator named), fewer samples than parameters, or a regressor of rank zero.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError
from ..machine_protocol import MachineDynamics
from ._base import DEFAULT_RANK_TOL, BaseParameters, base_parameters
from ._regressor import Regressor, affine_regressor
from ._solve import Estimate, constrained_least_squares

__all__ = ["Identification", "identify_efforts", "fit_regressor", "check_efforts"]

Array = NDArray[np.float64]


@dataclass(frozen=True)
class Identification:
    """One identification. ``names, prior (p,)`` the parameters and their prior values;
    ``u_measured, u_identified (n, nu)`` (the efforts fitted: a redundantly actuated mechanism's
    without their internal force); ``residual_rms (nu,)`` per actuator [effort]; ``T, lower,
    upper`` the consistency transform and bounds that were imposed; ``actuators`` the efforts'
    column names and ``u_given (n, nu)`` the efforts as given (where the fit knows them: a
    described mechanism's, :func:`pkmdyn.identify.described.fit_described`)."""

    names: tuple[str, ...]
    prior: Array
    regressor: Regressor
    base: BaseParameters
    estimate: Estimate
    u_measured: Array
    u_identified: Array
    residual_rms: Array
    T: Array
    lower: Array
    upper: Array
    actuators: tuple[str, ...] = ()
    u_given: Array | None = None

    def columns(self, t: Array | None = None) -> dict[str, Array]:
        """The efforts table ``pkmdyn identify`` writes (``efforts.csv``), by column name:
        ``t_s`` (the times ``t`` [s], where given), then per actuator ``measured_<effort>`` (the
        efforts as given) and ``identified_<effort>`` (``actuator_<k>`` where the fit names no
        efforts)."""
        given = self.u_measured if self.u_given is None else self.u_given
        cols: dict[str, Array] = {} if t is None else {"t_s": np.asarray(t, dtype=float)}
        for k in range(self.u_identified.shape[1]):
            a = self.actuators[k] if k < len(self.actuators) else f"actuator_{k + 1}"
            cols[f"measured_{a}"] = given[:, k]
            cols[f"identified_{a}"] = self.u_identified[:, k]
        return cols


def identify_efforts(
    machine: MachineDynamics,
    model_with: Callable[[Array], Any],
    names: tuple[str, ...],
    prior: Array,
    consistency: tuple[Array, Array, Array],
    q: Array,
    qd: Array,
    qdd: Array,
    load: Array | None,
    u_measured: Array,
    rank_tol: float = DEFAULT_RANK_TOL,
    source: str = "measured",
    what: str = "parameters",
) -> Identification:
    """Identify ``names`` (module docstring); ``consistency = (T, lower, upper)``, ``theta = T s``."""
    u = check_efforts(u_measured, np.asarray(q).shape[0], tuple(machine.ACTUATORS), len(names), source, what)
    reg = affine_regressor(lambda th: machine.inverse_dynamics(model_with(th), q, qd, qdd, load), names)
    return fit_regressor(reg, u, prior, consistency, rank_tol, source, what)


def check_efforts(u_measured: Array, n: int, actuators: tuple[str, ...], p: int, source: str = "measured",
                  what: str = "parameters") -> Array:
    """``u_measured`` as an array of shape ``(n, len(actuators))``, checked (module docstring):
    finite (row and actuator named) and enough samples for ``p`` parameters."""
    u = np.asarray(u_measured, dtype=float)
    nu = len(actuators)
    if u.shape != (n, nu):
        raise MotionError(f"{source}: expected efforts of shape ({n}, {nu}), got {u.shape}")
    bad = np.argwhere(~np.isfinite(u))
    if bad.size:
        r, c = bad[0]
        raise MotionError(f"{source}: row {r + 1}, column {actuators[c]!r}: value is not finite")
    if n < p or n * nu < 2 * p:
        raise MotionError(f"{source}: {n} samples are too few to identify {p} {what}; give at least {max(p, -(-2 * p // nu))}")
    return u


def fit_regressor(reg: Regressor, u_measured: Array, prior: Array, consistency: tuple[Array, Array, Array],
                  rank_tol: float = DEFAULT_RANK_TOL, source: str = "measured",
                  what: str = "parameters") -> Identification:
    """Steps 2-3 of the module docstring for a regressor ``u = Y theta + u_0`` given directly
    (e.g. the analytic one of a described mechanism, :func:`pkmdyn.multibody.analyses.regressor.regressor`)."""
    u = np.asarray(u_measured, dtype=float)
    n, nu = u.shape
    names = reg.names
    W = reg.stacked()
    base = base_parameters(W, names, rank_tol)
    if base.rank == 0:
        raise MotionError(
            f"{source}: the motion excites none of the {what} (regressor of rank 0); the machine must move, "
            "and its load vary, for them to show"
        )
    if n * nu < 2 * base.rank:
        raise MotionError(f"{source}: {n} samples are too few for the {base.rank} base {what} the motion shows "
                          f"(twice as many equations as base parameters needed); give at least "
                          f"{-(-2 * base.rank // nu)}")
    T, lower, upper = consistency
    y = (u - reg.offset).reshape(-1)
    est = constrained_least_squares(W, y, base, T, lower, upper, prior)
    level = np.sqrt(np.mean(est.residual.reshape(n, nu) ** 2, axis=0))
    if np.all(level > 1e-12 * max(float(np.max(np.abs(u))), 1e-300)):
        est = constrained_least_squares(W, y, base, T, lower, upper, prior, np.tile(1.0 / level, n))
    u_id = reg.efforts(est.theta)
    rms = np.sqrt(np.mean((u - u_id) ** 2, axis=0))
    return Identification(tuple(names), np.asarray(prior, float), reg, base, est, u, u_id, rms, T, lower, upper)

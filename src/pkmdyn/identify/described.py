"""Identification of any described mechanism (``pkmdyn identify --machine``) from measured
actuator efforts.

The efforts are linear in every body's ten barycentric parameters and every joint's Coulomb
and viscous coefficients (:func:`pkmdyn.multibody.analyses.regressor.regressor`); the known part (the
description's loads and the friction its named loads drive) is the offset. The fit is the
generic one of :func:`._identify.fit_regressor`: base parameters by a rank-revealing
decomposition, then least squares with the description's values as a vanishing prior (they
fix only what the motion cannot show), masses and friction coefficients kept >= 0.

Measured file (CSV): ``t_s``, the task columns of the description (``x_m`` ... as ``pkmdyn
run`` writes them; rates and accelerations optional, else from a quintic spline) or, for a log
of a real machine, its actuated joints' positions instead (``<joint>_pos_<m|rad>``; rates
``<joint>_vel_<u>_s`` and accelerations ``<joint>_acc_<u>_s2`` optional, else by the
Savitzky-Golay differentiator of ``sg_window`` samples and degree ``sg_order``), the pose then
by the direct kinematics (:mod:`pkmdyn.multibody.kinematics.direct`); one effort column per actuator,
its motor effort ``<actuator>_torque_Nm`` for a drive (``[[actuators]]``: what a real
machine's motor currents give) or the joint's ``<joint>_effort_<N|Nm>`` for an
actuated joint without one, and, optional, a column per named load and every other column a
``pkmdyn run`` results file carries (not used); any other column is refused by name, as a
misspelt one would be. With drives, the rotor inertias and motor friction coefficients are
parameters too; the friction named loads drive (``friction.external``) has its coefficients. The
job that writes ``identification.json`` and ``efforts.csv`` is :mod:`pkmdyn.jobs.identify`.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError
from ..io import read_csv_columns
from ..multibody.analyses.regressor import least_norm_projector, regressor
from ..multibody.columns import actuator_effort_column, results_column_names
from ..multibody.kinematics.direct import direct_kinematics
from ..multibody.kinematics.inverse import MechanismKinematics
from ..multibody.kinematics.motion import (
    MAX_MOTION_ROWS,
    actuator_columns,
    actuator_rates,
    task_columns,
)
from ..multibody.model.compiler import MechanismModel
from ..profiles._columns import column_group, derivatives, require_increasing
from ._base import DEFAULT_RANK_TOL
from ._identify import Identification, fit_regressor
from ._regressor import Regressor
from ._report import explained_percent, identification_report

__all__ = ["fit_described", "identification_document", "read_measured", "effort_columns"]

Array = NDArray[np.float64]


def effort_columns(model: MechanismModel) -> list[str]:
    """The measured file's effort columns, in actuator order: a drive's motor effort
    (``<actuator>_torque_Nm``), else the joint's (``<joint>_effort_<N|Nm>``)."""
    return [actuator_effort_column(model, i) for i in range(model.na)]


def read_measured(model: MechanismModel, path: Path, sg_window: int = 15, sg_order: int = 5
                  ) -> tuple[Array, Array, Array, Array, Array, dict[str, Array]]:
    """``t, x, xd, xdd, u, named loads`` from a measured file (module docstring)."""
    pos, vel, acc = task_columns(model)
    apos, avel, aacc = actuator_columns(model)
    eff = effort_columns(model)
    # what a pkmdyn run results file carries besides (joint and motor coordinates, the other
    # efforts, the effort split): accepted, not used
    own = ("t_s", *pos, *vel, *acc, *apos, *avel, *aacc, *eff, *model.named_loads)
    run_cols = [c for c in results_column_names(model) if c not in own]
    optional = (*pos, *vel, *acc, *apos, *avel, *aacc, *model.named_loads, *run_cols)
    cols = read_csv_columns(path, ("t_s", *eff), optional, max_rows=MAX_MOTION_ROWS,
                            beyond="the most a measured file holds (it is read whole); identify from a part of it")
    t = cols["t_s"]
    require_increasing(path, t)
    x = column_group(path, cols, pos)
    if x is not None:
        xd, xdd = derivatives(path, t, x, column_group(path, cols, vel), column_group(path, cols, acc), vel)
    else:  # a log in actuator coordinates: the pose by the direct kinematics

        s = column_group(path, cols, apos)
        if s is None:
            raise MotionError(f"{path}: give the task columns ({', '.join(pos)}) or the actuated joints' positions "
                              f"({', '.join(apos)})")
        sd, sdd = actuator_rates(path, t, s, column_group(path, cols, avel), column_group(path, cols, aacc), avel,
                                 sg_window, sg_order)
        dk = direct_kinematics(model, np.ascontiguousarray(s), np.ascontiguousarray(sd), np.ascontiguousarray(sdd), t,
                               bodies=False)
        x, xd, xdd = dk.x, dk.xd, dk.xdd
    u = np.column_stack([cols[c] for c in eff])
    _check_efforts(model, path, eff, u)
    named = {nm: cols[nm] for nm in model.named_loads if nm in cols}
    return t, np.ascontiguousarray(x), np.ascontiguousarray(xd), np.ascontiguousarray(xdd), u, named


def _check_efforts(model: MechanismModel, path: Path, names: list[str], u: Array) -> None:
    """The measured efforts within the description's plausibility limits (``max_force_N``,
    ``max_torque_Nm``) and not all zero (nothing to identify from); errors name the row and
    column."""
    for k, c in enumerate(names):
        key = "max_torque_Nm" if c.endswith("_Nm") else "max_force_N"
        lim = float(model.limits.get(key, np.inf))
        big = np.flatnonzero(~(np.abs(u[:, k]) <= lim))
        if big.size:
            raise MotionError(f"{path}: row {big[0] + 1}, column {c!r}: {u[big[0], k]:g} is beyond the plausibility "
                              f"limit {key} = {lim:g} (the description's [limits])")
    if not np.any(u != 0.0):
        raise MotionError(f"{path}: every effort column ({', '.join(names)}) is zero: nothing to identify from")


def _consistency(reg: Regressor) -> tuple[Array, Array, Array]:
    """``theta = s``; masses and friction coefficients >= 0, the rest free."""
    p = len(reg.names)
    lower = np.full(p, -np.inf)
    for k, nm in enumerate(reg.names):
        if nm.endswith(("_m_kg", "_coulomb", "_viscous", "_coefficient", "_rotor_inertia_kgm2", "_rotor_inertia_kg")):
            lower[k] = 0.0
    return np.eye(p), lower, np.full(p, np.inf)


def fit_described(model: MechanismModel, kin: MechanismKinematics, u: Array, named: dict[str, Array] | None = None,
                  rank_tol: float = DEFAULT_RANK_TOL, source: str = "measured") -> Identification:
    """The fit of ``model``'s parameters to the efforts ``u (n, na)`` measured along ``kin`` (each
    actuator's column as :func:`effort_columns` names it), ``named`` the named loads' magnitudes
    ``{name: (n,)}``: the :class:`._identify.Identification` (the parameters' names, the
    description's values as the prior, base parameters, estimate, identified efforts, residuals)."""
    reg0 = regressor(model, kin, named or None)
    reg = Regressor(reg0.Y, reg0.u0, reg0.names)
    given = u = np.asarray(u, dtype=float)
    P = least_norm_projector(model, kin)
    if P is not None:  # redundant actuation: measured efforts and regressor without the internal
        # force, which no parameter determines (the fit is the task-space one, A K u = A K Y theta)
        reg = Regressor(P @ reg.Y, np.einsum("nij,nj->ni", P, reg.offset), reg.names)
        u = np.einsum("nij,nj->ni", P, u)
    fit = fit_regressor(reg, u, reg0.theta, _consistency(reg), rank_tol, source=source)
    return replace(fit, actuators=tuple(effort_columns(model)), u_given=given)


def identification_document(model: MechanismModel, fit: Identification) -> dict[str, Any]:
    """``identification.json``'s document (``docs/identification.md``) of the fit ``fit`` of
    :func:`fit_described`, with every parameter's description value."""
    u, prior = fit.u_measured, fit.prior
    actuators = tuple(effort_columns(model))
    report = identification_report(fit.base, fit.estimate, prior, actuators,
                                   np.sqrt(np.mean(u ** 2, axis=0)), fit.residual_rms, fit.T)
    # the effort unit of each actuator (the shared report names its keys in N m)
    for key in ("residual_rms_Nm", "measured_rms_Nm"):
        report[key.replace("_Nm", "_si")] = report.pop(key)
    report["explained_percent"] = {a: (float(v) if np.isfinite(v) else None)
                                   for a, v in zip(actuators, explained_percent(u, u - fit.u_identified))}
    report["mechanism"] = model.name
    report["samples"] = int(len(u))
    report["parameters"] = {nm: {"description_value": float(p0), "estimate": float(th)}
                            for nm, p0, th in zip(fit.names, prior, fit.estimate.theta)}
    report["note"] = ("estimate: the fit, with the description's values along directions the motion does not "
                      "show (see separable and combinations for what the data determine)")
    return report

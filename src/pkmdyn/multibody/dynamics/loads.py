"""External loads of a described mechanism per sample: the ``[[loads]]`` entries, constant or
named (a direction times a magnitude per sample, ``docs/mechanism_format.md``, "Loads")."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError
from ..model.compiler import MechanismModel

__all__ = ["named_magnitudes", "load_forces"]

Array = NDArray[np.float64]


def named_magnitudes(model: MechanismModel, n: int, named: Mapping[str, object] | None = None) -> dict[str, Array]:
    """Magnitude (n,) [N] of every named load (``model.named_loads``) per sample: from
    ``named`` (``{name: scalar or (n,)}``), else the description's ``magnitude_N``. Unknown
    names, wrong lengths and non-finite values are a :class:`~pkmdyn.errors.ParameterError`
    naming the load."""
    out: dict[str, Array] = {}
    given = dict(named or {})
    for nm in given:
        if nm not in model.named_loads:
            known = ", ".join(model.named_loads) or "none"
            raise ParameterError(f"load {nm!r}: not a named load of mechanism {model.name!r} (named loads: {known})")
    for k, nm in enumerate(model.load_name):
        if nm is None or nm in out:
            continue
        if nm in given:
            v = np.asarray(given[nm], dtype=float)
            if v.ndim > 1 or (v.ndim == 1 and v.shape[0] != n):
                raise ParameterError(f"load {nm!r}: expected one value or {n} values, got shape {v.shape}")
            bad = np.flatnonzero(~np.isfinite(np.broadcast_to(v, (n,))))
            if bad.size:
                raise ParameterError(f"load {nm!r}: sample {int(bad[0])} is not finite")
            out[nm] = np.array(np.broadcast_to(v, (n,)), dtype=float)
        else:
            out[nm] = np.full(n, float(model.load_magnitude[k]))
    return out


def load_forces(model: MechanismModel, n: int, named: Mapping[str, object] | None = None) -> tuple[Array, Array]:
    """Force (n, nl, 3) [N] and moment (n, nl, 3) [N m] (base frame) of every ``[[loads]]``
    entry per sample: constant, or a named load's direction times its magnitude
    (:func:`named_magnitudes`)."""
    F = np.broadcast_to(model.load_force, (n,) + model.load_force.shape).copy()
    M = np.broadcast_to(model.load_moment, (n,) + model.load_moment.shape).copy()
    if model.named_loads:
        mags = named_magnitudes(model, n, named)
        for k, nm in enumerate(model.load_name):
            if nm is not None:
                F[:, k] = mags[nm][:, None] * model.load_direction[k]
    return F, M

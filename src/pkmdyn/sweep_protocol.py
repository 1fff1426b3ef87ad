"""What a machine provides to be swept (the protocol between ``pkmdyn.sweep`` and the machines;
it sits below both, so neither imports the other): a small set of free functions (a structural ``Protocol``).

A machine's adapter is a module (``machines/<machine>/sweep.py``) with these functions; the
sweep never imports a machine, it is handed the adapter. Every function works on the
machine's *description* (the parameter TOML as a nested dict) and on a *context* (the
design-independent part of the evaluation: the motion, precomputed rotations, options),
which must be picklable: it is sent once to every worker.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np

__all__ = ["SweepAdapter", "DesignOutcome", "STATUSES", "MetricInfo", "time_integral", "time_mean"]

#: every value of the ``status`` column, in the order of the summary
#:
#: - ``ok``: valid, the motion is reachable away from singularities, every constraint holds
#: - ``infeasible``: as ``ok`` but a constraint of the space file is violated (``reason`` says which)
#: - ``invalid``: the parameters fail the machine's own validation
#: - ``unreachable``: a pose of the motion cannot be reached (a loop does not close, a stroke is exceeded)
#: - ``singular``: the motion passes a singularity, or closer to one than the threshold
#: - ``limit``: the motion exceeds a plausibility limit of the machine (e.g. slider speed)
#: - ``nonfinite``: a metric came out non-finite (the design is outside what the model represents)
STATUSES = ("ok", "infeasible", "invalid", "unreachable", "singular", "limit", "nonfinite")


@dataclass(frozen=True)
class MetricInfo:
    """One metric: its column name (with its unit suffix), unit and a one-line formula."""

    name: str
    unit: str
    formula: str


@dataclass(frozen=True)
class DesignOutcome:
    """The result of one design: a status of :data:`STATUSES` other than ``infeasible`` (the
    sweep decides that from the constraints), a one-line reason (empty when ``ok``) and the
    metrics that could be computed (``{name: value}``; missing names are written as nulls)."""

    status: str
    reason: str = ""
    metrics: Mapping[str, float] = field(default_factory=dict)


class SweepAdapter(Protocol):
    """The functions a machine's sweep adapter module provides."""

    #: the name under which ``--machine`` finds it
    NAME: str

    def base_description(self, params_path: Path | None) -> dict[str, Any]:
        """The description to vary: the parameter file (``None``: the built-in one) as a dict."""
        ...

    def check_description(self, description: Mapping[str, Any], source: str) -> None:
        """Validate a description as the machine's ``run`` would; raise a ``PkmdynError`` naming the key."""
        ...

    def metrics(self, options: Mapping[str, Any], description: Mapping[str, Any]) -> tuple[MetricInfo, ...]:
        """The metrics computed under these motion options for designs of the base
        ``description`` (a described mechanism names them after its joints), in column order."""
        ...

    def prepare(self, description: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path) -> Any:
        """Check the ``[motion]`` options (one-line ``PkmdynError`` naming the key) and build the
        context: the motion each design performs and everything else that does not depend on
        the design. ``base_dir`` resolves relative file names of the space file."""
        ...

    def evaluate(self, descriptions: Sequence[Mapping[str, Any]], context: Any) -> list[DesignOutcome]:
        """Evaluate a batch of designs. Never raises for a bad design: that is an outcome.
        Each design's outcome must depend on that design alone (not on the batch)."""
        ...


def time_integral(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``int x dt`` over a motion sampled at times ``t``: the trapezoid rule along axis 0 (the
    adapters' energies and means)."""
    dt = np.diff(t).reshape((-1,) + (1,) * (x.ndim - 1))
    return np.sum(0.5 * (x[1:] + x[:-1]) * dt, axis=0)


def time_mean(x: np.ndarray, t: np.ndarray) -> np.ndarray:
    """``(1/T) int x dt`` over the motion (:func:`time_integral`, ``T`` its duration)."""
    return time_integral(x, t) / (t[-1] - t[0])

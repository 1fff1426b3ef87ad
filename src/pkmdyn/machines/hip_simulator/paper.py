"""The hip paper's own study of its ISO 14242-1 cycle: the cycle model fitted to the nine slider
maxima it reports (§5.1; the presets in :mod:`.iso_fit`).

:func:`fit_iso_cycle` fits the six phases of :class:`IsoCycle` (maximum and minimum of FE, AA
and IER; the ISO ranges and the load stay as they are) to :data:`.iso_fit.PAPER_SLIDER_MAXIMA`
by least squares on the relative differences (``scipy.optimize.least_squares`` from several
starts), each rise and fall held between 30 % and 70 % of the cycle as the smooth model needs.
Findings in ``docs/identification.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from ...errors import ParameterError
from ...profiles.iso14242 import IsoCycle, iso14242_motion
from .iso_fit import PAPER_SLIDER_MAXIMA
from .kinematics import inverse_kinematics

__all__ = ["IsoFit", "slider_maxima", "fit_iso_cycle"]

Array = NDArray[np.float64]


def slider_maxima(model, cycle: IsoCycle, samples: int = 400) -> Array:
    """The nine §5.1 quantities of ``cycle`` on ``model`` (order of :data:`PAPER_SLIDER_MAXIMA`)."""
    kin = inverse_kinematics(model, iso14242_motion(1.0, samples, cycle))
    return np.concatenate([kin.L[:, 0].max(axis=0), np.abs(kin.Ld[:, 0]).max(axis=0), np.abs(kin.Ldd[:, 0]).max(axis=0)])


def _cycle(base: IsoCycle, x: Array) -> IsoCycle:
    waves = []
    for k, w in enumerate((base.fe, base.aa, base.ier)):
        p_max, d = float(x[2 * k]) % 1.0, float(x[2 * k + 1])
        waves.append(replace(w, max_phase=p_max, min_phase=(p_max + d) % 1.0))
    return replace(base, fe=waves[0], aa=waves[1], ier=waves[2])


@dataclass(frozen=True)
class IsoFit:
    """A fitted cycle, its nine maxima and their relative differences from the targets."""

    cycle: IsoCycle
    maxima: Array
    relative_difference: Array


def fit_iso_cycle(model, targets: Array = PAPER_SLIDER_MAXIMA, base: IsoCycle = IsoCycle(), starts: int = 6,
                  seed: int = 0, samples: int = 300) -> IsoFit:
    """Fit the six phases of ``base`` to the nine ``targets`` (module docstring)."""
    targets = np.asarray(targets, dtype=float)
    if targets.shape != (9,) or not np.all(targets > 0):
        raise ParameterError("targets: expected nine positive maxima")

    def res(x: Array) -> Array:
        return slider_maxima(model, _cycle(base, x), samples) / targets - 1.0

    rng = np.random.default_rng(seed)
    x0 = []
    for w in (base.fe, base.aa, base.ier):
        x0 += [w.max_phase, (w.min_phase - w.max_phase) % 1.0]
    lo = np.tile([-1.0, 0.3], 3)
    hi = np.tile([2.0, 0.7], 3)
    best = None
    for k in range(starts):
        x = np.array(x0) if k == 0 else np.tile([0.0, 0.3], 3) + rng.uniform(0, 1, 6) * np.tile([1.0, 0.4], 3)
        sol = least_squares(res, x, bounds=(lo, hi), diff_step=1e-3, max_nfev=200)
        if best is None or sol.cost < best.cost:
            best = sol
    cycle = _cycle(base, best.x)
    maxima = slider_maxima(model, cycle, samples)
    return IsoFit(cycle, maxima, maxima / targets - 1.0)

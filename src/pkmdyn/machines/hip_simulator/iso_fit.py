"""The ISO 14242-1 cycle model calibrated to the hip paper's slider maxima (named motion ``paper-fit``).

The hip paper (§5.1) reports nine maxima of its simulated ISO cycle: the highest position of
the upper-platform sliders S11, S12, S13 and the largest speed and acceleration on each lead
screw. :func:`fit_iso_cycle` fits the six phases of :class:`IsoCycle` (maximum and minimum of
FE, AA and IER; the ISO ranges and the load stay as they are) to them by least squares on the
relative differences (``scipy.optimize.least_squares`` from several starts), each rise and
fall held between 30 % and 70 % of the cycle as the smooth model needs.
:data:`PAPER_FIT` holds the result for the built-in parameters, :data:`PAPER_FIT_ZXY` the result
with ``euler_sequence = "ZXY"``, and :func:`iso_cycle_preset` returns a preset by name; the
default cycle is unchanged. Findings in ``docs/identification.md``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import least_squares

from ...errors import ParameterError
from ...profiles.iso14242 import AxisWave, IsoCycle, iso14242_motion

__all__ = ["PAPER_SLIDER_MAXIMA", "PAPER_FIT", "PAPER_FIT_ZXY", "IsoFit", "slider_maxima", "fit_iso_cycle", "iso_cycle_preset"]

Array = NDArray[np.float64]

#: hip paper §5.1: max position of S11, S12, S13 [m]; max |Ld| [m/s] and max |Ldd| [m/s^2] per screw
PAPER_SLIDER_MAXIMA = np.array(
    [0.66558, 0.66047, 0.62442, 0.27515, 0.26780, 0.14397, 2.15240, 2.10080, 1.27090]
)

#: the phases fitted by :func:`fit_iso_cycle` to :data:`PAPER_SLIDER_MAXIMA` with the built-in
#: parameters (ranges and load as in the default :class:`IsoCycle`)
PAPER_FIT = IsoCycle(
    fe=AxisWave(25.0, 0.5773, -18.0, 0.0853),
    aa=AxisWave(7.0, 0.6432, -4.0, 0.0312),
    ier=AxisWave(2.0, 0.0636, -10.0, 0.4759),
)

#: the same fit with ``euler_sequence = "ZXY"`` in the parameter file (FE about the base Z axis
#: first, then AA, then IER): a motion for that parameter file only
PAPER_FIT_ZXY = IsoCycle(
    fe=AxisWave(25.0, 0.0397, -18.0, 0.5323),
    aa=AxisWave(7.0, 0.1731, -4.0, 0.6002),
    ier=AxisWave(2.0, 0.3350, -10.0, 0.9088),
)


def slider_maxima(model, cycle: IsoCycle, samples: int = 400) -> Array:
    """The nine §5.1 quantities of ``cycle`` on ``model`` (order of :data:`PAPER_SLIDER_MAXIMA`)."""
    from .kinematics import inverse_kinematics

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


def iso_cycle_preset(name: str) -> IsoCycle:
    """The cycle model by name: ``"default"`` (the documented choices), ``"paper-fit"`` (for the
    spec's ``XYZ`` sequence) or ``"paper-fit-zxy"`` (for a parameter file with ``euler_sequence =
    "ZXY"``; see ``docs/identification.md``)."""
    presets = {"default": IsoCycle(), "paper-fit": PAPER_FIT, "paper-fit-zxy": PAPER_FIT_ZXY}
    if name not in presets:
        raise ParameterError(f"motion model {name!r}: expected one of {', '.join(presets)}")
    return presets[name]

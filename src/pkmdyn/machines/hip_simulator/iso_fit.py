"""The ISO 14242-1 cycle presets of the hip simulator (named motions ``default``, ``paper-fit``,
``paper-fit-zxy``).

The hip paper (§5.1) reports nine maxima of its simulated ISO cycle: the highest position of
the upper-platform sliders S11, S12, S13 and the largest speed and acceleration on each lead
screw (:data:`PAPER_SLIDER_MAXIMA`). :data:`PAPER_FIT` holds the six phases of
:class:`IsoCycle` fitted to them for the built-in parameters
(:func:`pkmdyn.machines.hip_simulator.paper.fit_iso_cycle`), :data:`PAPER_FIT_ZXY` the result
with ``euler_sequence = "ZXY"``, and :func:`iso_cycle_preset` returns a preset by name; the
default cycle is unchanged. Findings in ``docs/identification.md``.
"""

from __future__ import annotations

import numpy as np

from ...errors import ParameterError
from ...profiles.iso14242 import AxisWave, IsoCycle

__all__ = ["PAPER_SLIDER_MAXIMA", "PAPER_FIT", "PAPER_FIT_ZXY", "iso_cycle_preset"]

#: hip paper §5.1: max position of S11, S12, S13 [m]; max |Ld| [m/s] and max |Ldd| [m/s^2] per screw
PAPER_SLIDER_MAXIMA = np.array(
    [0.66558, 0.66047, 0.62442, 0.27515, 0.26780, 0.14397, 2.15240, 2.10080, 1.27090]
)

#: the phases fitted by :func:`.paper.fit_iso_cycle` to :data:`PAPER_SLIDER_MAXIMA` with the built-in
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


def iso_cycle_preset(name: str) -> IsoCycle:
    """The cycle model by name: ``"default"`` (the documented choices), ``"paper-fit"`` (for the
    spec's ``XYZ`` sequence) or ``"paper-fit-zxy"`` (for a parameter file with ``euler_sequence =
    "ZXY"``; see ``docs/identification.md``)."""
    presets = {"default": IsoCycle(), "paper-fit": PAPER_FIT, "paper-fit-zxy": PAPER_FIT_ZXY}
    if name not in presets:
        raise ParameterError(f"motion model {name!r}: expected one of {', '.join(presets)}")
    return presets[name]

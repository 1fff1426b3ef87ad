"""The bounds of the hip simulator's identification and excitation options, in a module of plain
numbers, so that the command line states them without loading the solvers (a fast start)."""

from __future__ import annotations

__all__ = ["MAX_HARMONICS", "MAX_DESIGN_SAMPLES", "MAX_ITERATIONS", "MAX_STARTS", "MAX_WORK", "MIN_PERIOD_S",
           "MAX_PERIOD_S", "MAX_LOAD_N", "MAX_SLIDER_SPEED_M_S", "MAX_SLIDER_ACCEL_M_S2", "MAX_COND_J",
           "MAX_EXCITE_ROWS", "MAX_SG_WINDOW", "MAX_SG_ORDER"]

#: bounds of the excitation design, checked by :func:`.identify_excite.design_excitation` (the command line states them)
MAX_HARMONICS = 6
MAX_DESIGN_SAMPLES = 1000
MAX_ITERATIONS = 200
MAX_STARTS = 5
#: most cost evaluations x design samples of one design (:func:`pkmdyn.identify._excite.max_evaluations`)
MAX_WORK = 1_000_000
MIN_PERIOD_S, MAX_PERIOD_S = 1e-3, 3600.0
MAX_LOAD_N = 1e5
MAX_SLIDER_SPEED_M_S = 100.0
MAX_SLIDER_ACCEL_M_S2 = 1e5
MAX_COND_J = 1e6
#: most rows of an excitation motion file
MAX_EXCITE_ROWS = 2_000_000
#: bounds of ``hip identify``'s Savitzky-Golay options
MAX_SG_WINDOW = 10001
MAX_SG_ORDER = 20

"""Alias of :mod:`pkmdyn.machines.hip_simulator.identify_excite`, for imports that still use this
path; the hip simulator's excitation design lives in the machine's folder."""

from __future__ import annotations

from ..machines.hip_simulator.identify_excite import *  # noqa: F401,F403
from ..machines.hip_simulator.identify_excite import __all__  # noqa: F401

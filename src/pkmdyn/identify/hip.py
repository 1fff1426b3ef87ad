"""Alias of :mod:`pkmdyn.machines.hip_simulator.identify_view`, for imports that still use this
path; the hip simulator's identification lives in the machine's folder."""

from __future__ import annotations

from ..machines.hip_simulator.identify_view import *  # noqa: F401,F403
from ..machines.hip_simulator.identify_view import __all__  # noqa: F401

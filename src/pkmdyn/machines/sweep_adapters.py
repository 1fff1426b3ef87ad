"""The machines that ``pkmdyn sweep --machine NAME`` knows, each by its sweep adapter module.

The one place where a machine name meets the sweep: a new machine adds one entry (its
adapter module provides the functions of :class:`pkmdyn.sweep.adapter.SweepAdapter`).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from ..errors import ParameterError

__all__ = ["SWEEP_ADAPTERS", "sweep_adapter"]

#: ``--machine`` name -> module of its sweep adapter
SWEEP_ADAPTERS: dict[str, str] = {
    "hip": "pkmdyn.machines.hip_simulator.sweep",
    "pdm": "pkmdyn.machines.pdm4.sweep",
}


def sweep_adapter(name: str) -> ModuleType:
    """The sweep adapter of the machine called ``name`` (a key of :data:`SWEEP_ADAPTERS`)."""
    if name not in SWEEP_ADAPTERS:
        shown = name if len(name) <= 60 else name[:60] + "..."
        raise ParameterError(f"--machine {shown!r}: unknown machine; known: {', '.join(SWEEP_ADAPTERS)} "
                             "(machine description files are not sweepable yet)")
    return importlib.import_module(SWEEP_ADAPTERS[name])

"""Design sweeps and dimensional synthesis of any machine that provides a sweep adapter.

The sweep knows no machine: it is handed the machine's adapter (a module with the functions
of :class:`~pkmdyn.sweep_protocol.SweepAdapter`). Flow: space file -> validated
:class:`SweepSpace` -> designs (grid, random, Latin hypercube or Sobol) -> batches evaluated in
this process or on Dask -> Parquet part files -> ``designs.parquet``, Pareto set, best design as
a parameter file, plots (``docs/sweep.md``). A machine's adapter comes from the machines'
side (``pkmdyn.machines.registry.sweep_adapter(name)``); the whole sweep into an output folder
is the job :func:`pkmdyn.jobs.sweep.run_sweep`::

    report = run_sweep(adapter, "space.toml", "out", workers=2)
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ..sweep_protocol import STATUSES, DesignOutcome, MetricInfo, SweepAdapter
    from .pareto import best_index, minimised, pareto_mask
    from .space import SweepSpace, load_space, parse_path, sample_designs, space_from_dict

__all__ = [
    "SweepAdapter",
    "DesignOutcome",
    "MetricInfo",
    "STATUSES",
    "SweepSpace",
    "load_space",
    "space_from_dict",
    "parse_path",
    "sample_designs",
    "pareto_mask",
    "minimised",
    "best_index",
]

#: where each public name lives, imported on first use: ``import pkmdyn.sweep`` loads
#: neither pydantic nor Dask nor pymoo until a function is looked up
__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("STATUSES", "DesignOutcome", "MetricInfo", "SweepAdapter"), "..sweep_protocol"),
    **dict.fromkeys(("best_index", "minimised", "pareto_mask"), ".pareto"),
    **dict.fromkeys(("SweepSpace", "load_space", "parse_path", "sample_designs", "space_from_dict"), ".space"),
})

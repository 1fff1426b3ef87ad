"""The singularity measures (:mod:`.measures`) and their compiled bounds and brackets
(:mod:`._kernels`).

Every public name of :mod:`.measures` is importable from here; each is imported on first use."""

from __future__ import annotations

from ...._lazy import attach

__getattr__, __dir__ = attach(__name__, dict.fromkeys(
    ("SCREEN_STRIDE", "SingularityMeasures", "least_measure_bounds", "least_measures", "singularity_measures"),
    ".measures"))

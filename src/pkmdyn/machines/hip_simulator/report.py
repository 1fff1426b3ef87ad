"""The ``report.html`` of the hip simulator's runs: the machine animated from its kinematics,
motion, load, slider motion and motor torques against time, the PNG figures, the summary, the
parameters and every warning."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...report import Curve, Scene, TimePlot, write_report
from .dynamics import PARTS
from .params import DEFAULT_PARAMS_TEXT

__all__ = ["parameters_text", "run_plots", "write_run_report"]

Array = NDArray[np.float64]


def parameters_text(params_path: str | Path | None) -> str:
    """The parameter file's text (the built-in file when None), headed by where it came from."""
    if params_path is None:
        return "# built-in parameters (pkmdyn/machines/hip_simulator/default.toml)\n" + DEFAULT_PARAMS_TEXT
    try:
        return f"# {params_path}\n" + Path(params_path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return f"# {params_path}\n# (the file could not be read again for the report)"


def run_plots(data: Any) -> list[TimePlot]:
    """Time plots from the run's plot data (:class:`~pkmdyn.machines.hip_simulator.plots.PlotData`):
    samples, or min-max envelopes of bins for long runs."""

    def curves(key: str, names: Sequence[str], scale: float = 1.0) -> tuple[Curve, ...]:
        lo, hi = data.lo[key] * scale, data.hi[key] * scale
        if data.envelope:
            return tuple(Curve(n, lo=lo[:, c], hi=hi[:, c]) for c, n in enumerate(names))
        return tuple(Curve(n, lo[:, c]) for c, n in enumerate(names))

    t, note = data.t, data.note
    legs = [f"S{j}{i} (platform {j}, screw {i})" for j in (1, 2) for i in (1, 2, 3)]
    motors = [f"motor {i}" for i in (1, 2, 3)]
    plots = [
        TimePlot("Platform angles", "angle [deg]", t, curves("angles_deg", ("alpha (FE)", "beta (AA)", "gamma (IER)")),
                 note),
        TimePlot("Load", "load [N]", t, curves("load_N", ("load",)), note),
        TimePlot("Slider positions", "position [mm]", t, curves("L", legs, 1e3), note),
        TimePlot("Slider velocities", "velocity [mm/s]", t, curves("Ld", [f"screw {i}" for i in (1, 2, 3)], 1e3), note),
        TimePlot("Slider accelerations", "acceleration [m/s^2]", t, curves("Ldd", [f"screw {i}" for i in (1, 2, 3)]),
                 note),
        TimePlot("Motor torques", "torque [N m]", t, curves("tau", motors), note),
    ]
    for part in PARTS:
        plots.append(TimePlot(f"Motor torques: {part} part", "torque [N m]", t, curves(part, motors), note))
    return plots


def write_run_report(out: Path, *, title: str, scene: Scene | None, plots: list[TimePlot], summary: dict[str, Any],
                     params_path: str | Path | None, warnings: Sequence[str], images: Sequence[Path],
                     notes: Sequence[str], scene_note: str = "", samples: int | None = None,
                     figures: Sequence[tuple[str, Any]] = ()) -> Path:
    """Write ``report.html`` into a run's (temporary) output folder ``out``; ``figures``: further
    interactive figures (the slide tracks in 3D)."""
    return write_report(out, title=title, scene=scene, plots=plots, summary=summary,
                        parameters=parameters_text(params_path), warnings=warnings, images=images, notes=notes,
                        scene_note=scene_note, samples=samples, figures=figures)

"""Plots of the hip simulator in the style of the paper's figures (matplotlib, Agg backend).

Units on the axes are those of the results files (m, m/s, m/s^2, N m, N, deg), so a value read
off a plot can be looked up in ``results.csv`` unchanged. A plot never draws more than one
cycle's worth of curves: the built-in motion is periodic, so its plots show the first cycle;
a long motion file is shown as an envelope (minimum and maximum over equal bins of samples,
:class:`PlotData`), never as a solid block of overdrawn lines.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...report import Curve, Curves, TimePlot
from .paper import PARTS

__all__ = ["PlotData", "PlotCollector", "write_figures", "report_plots", "plot_motion_and_load", "plot_slider_motion",
           "plot_torque_parts", "plot_torques", "plot_friction_vs_load"]

Array = NDArray[np.float64]
SCATTER_MAX = 20_000  # points of the friction-against-load scatter
_LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green")


@dataclass(frozen=True)
class PlotData:
    """What the plots draw: ``t (m,)`` [s] and, per curve name, ``lo, hi (m, k)``.

    Without ``envelope`` ``lo == hi`` are the samples; with it they are the minimum and maximum
    of each bin centred at ``t``. Curves: ``angles_deg`` (3), ``load_N`` (1), ``L`` (6: platform
    1 legs 1-3, platform 2 legs 1-3) [m], ``Ld``, ``Ldd`` (3, one per screw) [m/s, m/s^2],
    ``tau`` and each part of :data:`~pkmdyn.machines.hip_simulator.paper.PARTS` (3) [N m].
    ``scatter_load (s,)`` [N], ``scatter_friction (s, 3)`` [N m]: thinned samples for the
    friction-against-load plot. ``note``: what the time axis shows (e.g. the first cycle).
    """

    t: Array
    lo: dict[str, Array]
    hi: dict[str, Array]
    envelope: bool
    note: str
    scatter_load: Array
    scatter_friction: Array


def _plt() -> Any:
    """matplotlib's pyplot on the Agg backend, imported when a figure is drawn (a run without
    plots does not load it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _curve(ax, data: PlotData, name: str, col: int, **style) -> None:
    lo, hi = data.lo[name][:, col], data.hi[name][:, col]
    if data.envelope:
        colour = style.get("color")
        ax.fill_between(data.t, lo, hi, alpha=0.3, color=colour, label=style.get("label"), lw=0)
        ax.plot(data.t, lo, color=colour, lw=0.7, alpha=style.get("alpha", 1.0))
        ax.plot(data.t, hi, color=colour, lw=0.7, alpha=style.get("alpha", 1.0))
    else:
        ax.plot(data.t, lo, style.pop("fmt", "-"), **style)


def _finish(fig, data: PlotData, path: Path) -> Path:
    if data.note:
        fig.suptitle(data.note, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    _plt().close(fig)
    return path


def plot_motion_and_load(data: PlotData, path: Path) -> Path:
    """Fig. 4 style: (a) the three Euler angles [deg], (b) the load [N] over time."""
    fig, (ax1, ax2) = _plt().subplots(1, 2, figsize=(11, 4))
    for k, label in enumerate(("FE (alpha)", "AA (beta)", "IER (gamma)")):
        _curve(ax1, data, "angles_deg", k, color=_LEG_COLOURS[k], label=label)
    ax1.set(xlabel="t [s]", ylabel="angle [deg]", title="(a) Motion")
    ax1.legend()
    ax1.grid(alpha=0.3)
    _curve(ax2, data, "load_N", 0, color="tab:red")
    ax2.set(xlabel="t [s]", ylabel="load F [N]", title="(b) Load")
    ax2.grid(alpha=0.3)
    return _finish(fig, data, path)


def plot_slider_motion(data: PlotData, path: Path) -> Path:
    """Fig. 6 style: displacement [m], velocity [m/s], acceleration [m/s^2] of the sliders.

    The two sliders of one screw share velocity and acceleration, so panels (b) and (c) show
    one curve per screw.
    """
    fig, axes = _plt().subplots(1, 3, figsize=(15, 4))
    for j in (0, 1):
        for i in range(3):
            _curve(axes[0], data, "L", 3 * j + i, fmt="-" if j == 0 else "--", color=_LEG_COLOURS[i], label=f"S{j + 1}{i + 1}")
    for ax, name in ((axes[1], "Ld"), (axes[2], "Ldd")):
        for i in range(3):
            _curve(ax, data, name, i, color=_LEG_COLOURS[i], label=f"S1{i + 1}, S2{i + 1}")
    titles = (("displacement L [m]", "(a) Displacement"), ("velocity dL/dt [m/s]", "(b) Velocity"),
              ("acceleration d2L/dt2 [m/s^2]", "(c) Acceleration"))
    for ax, (ylabel, title) in zip(axes, titles):
        ax.set(xlabel="t [s]", ylabel=ylabel, title=title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, ncol=2)
    return _finish(fig, data, path)


def plot_torque_parts(data: PlotData, path: Path) -> Path:
    """Fig. 8 style: one panel per part of Eq. (14), three motors each [N m]."""
    names = (("platform", "(a) platform"), ("lever", "(b) lever"), ("slider", "(c) slider"), ("screw", "(d) screw"))
    fig, axes = _plt().subplots(1, len(names), figsize=(4.2 * len(names), 4))
    for ax, (key, title) in zip(axes, names):
        for i in range(3):
            _curve(ax, data, key, i, color=_LEG_COLOURS[i], label=f"motor {i + 1}")
        ax.set(xlabel="t [s]", ylabel="torque [N m]", title=title)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    return _finish(fig, data, path)


def plot_torques(data: PlotData, path: Path) -> Path:
    """Fig. 11 style: the total driving torque of each motor [N m]."""
    fig, axes = _plt().subplots(1, 3, figsize=(15, 4))
    for i, ax in enumerate(axes):
        _curve(ax, data, "tau", i, color=_LEG_COLOURS[i])
        ax.set(xlabel="t [s]", ylabel="torque tau [N m]", title=f"({'abc'[i]}) Linear module {i + 1}")
        ax.grid(alpha=0.3)
    return _finish(fig, data, path)


def plot_friction_vs_load(data: PlotData, path: Path) -> Path:
    """Friction torque per motor [N m]: (a) with the load over time, (b) against the load."""
    fig, (ax, ax3) = _plt().subplots(1, 2, figsize=(13, 4.2))
    for i in range(3):
        _curve(ax, data, "friction", i, color=_LEG_COLOURS[i], label=f"friction, motor {i + 1}")
    ax.set(xlabel="t [s]", ylabel="friction torque [N m]", title="(a) Over time")
    ax.grid(alpha=0.3)
    ax2 = ax.twinx()
    _curve(ax2, data, "load_N", 0, color="tab:red", alpha=0.5, label="load")
    ax2.set_ylabel("load F [N]")
    lines = ax.get_legend_handles_labels()
    lines2 = ax2.get_legend_handles_labels()
    ax.legend(lines[0] + lines2[0], lines[1] + lines2[1], fontsize=8, loc="upper right")
    for i in range(3):
        ax3.plot(data.scatter_load, np.abs(data.scatter_friction[:, i]), ".", ms=2, color=_LEG_COLOURS[i],
                 label=f"motor {i + 1}")
    ax3.set(xlabel="load F [N]", ylabel="|friction torque| [N m]", title="(b) Against the load")
    ax3.grid(alpha=0.3)
    ax3.legend(fontsize=8, markerscale=4)
    return _finish(fig, data, path)


class PlotCollector:
    """The plots' data, gathered block by block with bounded memory: the curves of the samples
    ``[0, window)`` (one cycle of the built-in motion, or the whole of a motion file) by
    :class:`pkmdyn.report.Curves` (every sample up to its ``PLOT_RAW_MAX``, beyond that an envelope
    of ``PLOT_BINS`` bins), and the friction-against-load scatter: every k-th sample of the window,
    at most :data:`SCATTER_MAX`."""

    def __init__(self, window: int) -> None:
        self.window = window
        self.curves = Curves(window)
        self.envelope = self.curves.mode == "bins"
        self.scatter_step = max(1, -(-window // SCATTER_MAX))
        self.scatter: list[Array] = []

    def add(self, start: int, curves: dict[str, Array], load: Array, friction: Array) -> None:
        """A block from sample ``start``: its ``curves`` (``"t"`` [s] among them), the load [N] and the
        friction torques [N m] of the scatter."""
        idx = np.arange(start, start + load.shape[0])
        pick = (idx < self.window) & (idx % self.scatter_step == 0)
        if pick.any():
            self.scatter.append(np.column_stack([load[pick], friction[pick]]))
        self.curves.add(start, curves["t"], {k: v for k, v in curves.items() if k != "t"})

    def data(self, note: str) -> PlotData:
        d = self.curves.data()
        note = "; ".join(x for x in (note, d.note) if x)
        sc = np.concatenate(self.scatter)
        return PlotData(t=d.t, lo=d.lo, hi=d.hi, envelope=self.envelope, note=note, scatter_load=sc[:, 0],
                        scatter_friction=sc[:, 1:])


def write_figures(data: PlotData, folder: Path) -> dict[str, Path]:
    """The run's five PNG figures in ``folder``, by their file labels."""
    return {"motion_plot": plot_motion_and_load(data, folder / "motion_load.png"),
            "slider_plot": plot_slider_motion(data, folder / "slider_motion.png"),
            "torque_parts_plot": plot_torque_parts(data, folder / "torque_parts.png"),
            "torque_plot": plot_torques(data, folder / "torques.png"),
            "friction_plot": plot_friction_vs_load(data, folder / "friction_vs_load.png")}


def report_plots(data: PlotData) -> list:
    """The report's time plots (:class:`pkmdyn.report.TimePlot`) of the run's plot data: samples,
    or min-max envelopes of bins for long runs."""

    def curves(key: str, names: list[str] | tuple[str, ...], scale: float = 1.0) -> tuple:
        lo, hi = data.lo[key] * scale, data.hi[key] * scale
        if data.envelope:
            return tuple(Curve(n, lo=lo[:, c], hi=hi[:, c]) for c, n in enumerate(names))
        return tuple(Curve(n, lo[:, c]) for c, n in enumerate(names))

    t, note = data.t, data.note
    legs = [f"S{j}{i} (platform {j}, screw {i})" for j in (1, 2) for i in (1, 2, 3)]
    motors = [f"motor {i}" for i in (1, 2, 3)]
    screws = [f"screw {i}" for i in (1, 2, 3)]
    plots = [
        TimePlot("Platform angles", "angle [deg]", t, curves("angles_deg", ("alpha (FE)", "beta (AA)", "gamma (IER)")),
                 note),
        TimePlot("Load", "load [N]", t, curves("load_N", ("load",)), note),
        TimePlot("Slider positions", "position [mm]", t, curves("L", legs, 1e3), note),
        TimePlot("Slider velocities", "velocity [mm/s]", t, curves("Ld", screws, 1e3), note),
        TimePlot("Slider accelerations", "acceleration [m/s^2]", t, curves("Ldd", screws), note),
        TimePlot("Motor torques", "torque [N m]", t, curves("tau", motors), note),
    ]
    for part in PARTS:
        plots.append(TimePlot(f"Motor torques: {part} part", "torque [N m]", t, curves(part, motors), note))
    return plots

"""Plots of PDM results: limb motion in the style of Fig. 19 and the workspace of Fig. 3.

Figures are built on matplotlib's object API with the Agg canvas (no pyplot state, no
display needed). Lengths are shown in millimetres, converted here at the edge.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from numpy.typing import NDArray

from .workspace import Workspace

__all__ = ["plot_limbs", "plot_workspace"]

Array = NDArray[np.float64]
_LIMBS = ("$l_{11}$", "$l_{12}$", "$l_{23}$", "$l_{24}$")
_MM = 1e3


def _save(fig: Figure, path: str | Path) -> Path:
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=120)
    return Path(path)


def plot_limbs(t: Array, extension: Array, ld: Array, ldd: Array, path: str | Path) -> Path:
    """Limb extension ``l - l_home`` [mm], velocity [mm/s] and acceleration [mm/s^2] of the four
    limbs against time ``t`` (n,) [s] (Fig. 19 style); inputs (n, 4) in SI. Returns the path."""
    fig = Figure(figsize=(7.5, 8.0), layout="constrained")
    axes = fig.subplots(3, 1, sharex=True)
    series = ((extension, "displacement [mm]"), (ld, "velocity [mm/s]"), (ldd, "acceleration [mm/s$^2$]"))
    for ax, (data, label) in zip(axes, series):
        for k in range(4):
            ax.plot(t, data[:, k] * _MM, label=_LIMBS[k])
        ax.set_ylabel(label)
        ax.grid(True, alpha=0.3)
    axes[0].legend(ncol=4, loc="best")
    axes[-1].set_xlabel("time [s]")
    fig.suptitle("PDM limb displacement, velocity and acceleration (Eq. 8-9, 37-48)")
    return _save(fig, path)


def plot_workspace(ws: Workspace, path: str | Path) -> Path:
    """Reachable workspace (Fig. 3): (a) boundary of every gamma layer at the parasitic height
    ``z = r0 cos(gamma)`` of P, (b) x-y projection. Returns the written path."""
    fig = Figure(figsize=(13.5, 5.5), layout="constrained")
    grid = fig.add_gridspec(1, 3, width_ratios=(1.0, 0.12, 1.0))
    ax3 = fig.add_subplot(grid[0, 0], projection="3d")
    ax2 = fig.add_subplot(grid[0, 2])
    for k in np.flatnonzero(ws.valid):
        b = np.vstack([ws.boundary[k], ws.boundary[k, :1]]) * _MM
        z = np.full(b.shape[0], ws.z[k] * _MM)
        label = f"$\\gamma$ = {np.degrees(ws.gamma[k]):.0f}°"
        ax3.plot(b[:, 0], b[:, 1], z, lw=1.0)
        ax2.plot(b[:, 0], b[:, 1], lw=0.6, alpha=0.6, label=label)
    proj = np.vstack([ws.projection, ws.projection[:1]]) * _MM
    ax2.plot(proj[:, 0], proj[:, 1], "k", lw=2.0, label="projection boundary")
    ax3.set_xlabel("x [mm]")
    ax3.set_ylabel("y [mm]")
    ax3.set_zlabel("z [mm] (parasitic)", labelpad=8)
    ax3.set_title(f"(a) reachable workspace, $\\alpha$ = {np.degrees(ws.alpha):.0f}°")
    ax2.set_xlabel("x [mm]")
    ax2.set_ylabel("y [mm]")
    ax2.set_aspect("equal")
    ax2.grid(True, alpha=0.3)
    ax2.set_title("(b) projection on the x-y plane")
    ax2.legend(fontsize=7, loc="center left", bbox_to_anchor=(1.0, 0.5))
    return _save(fig, path)

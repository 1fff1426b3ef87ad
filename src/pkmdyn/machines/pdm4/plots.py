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

__all__ = ["plot_limbs", "plot_workspace", "workspace_figure", "plot_forces", "plot_overconstraints"]

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
    return _save(workspace_figure(ws), path)


def workspace_figure(ws: Workspace) -> Figure:
    """The figure of :func:`plot_workspace`, not yet saved."""
    from matplotlib import colormaps
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    fig = Figure(figsize=(13.5, 5.5), layout="constrained")
    grid = fig.add_gridspec(1, 3, width_ratios=(1.0, 0.12, 1.0))
    ax3 = fig.add_subplot(grid[0, 0], projection="3d")
    ax2 = fig.add_subplot(grid[0, 2])
    # one colour per gamma layer from a continuous map (a 10-colour cycle repeats beyond 10 layers),
    # the same in both views, read off one colour bar
    deg = np.degrees(ws.gamma)
    norm = Normalize(float(deg.min()), float(deg.max()) if deg.max() > deg.min() else float(deg.min()) + 1.0)
    cmap = colormaps["viridis"]
    for k in np.flatnonzero(ws.valid):
        b = np.vstack([ws.boundary[k], ws.boundary[k, :1]]) * _MM
        z = np.full(b.shape[0], ws.z[k] * _MM)
        colour = cmap(norm(deg[k]))
        ax3.plot(b[:, 0], b[:, 1], z, lw=1.0, color=colour)
        ax2.plot(b[:, 0], b[:, 1], lw=0.8, alpha=0.85, color=colour)
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
    ax2.legend(fontsize=8, loc="upper right")
    bar = fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax2, shrink=0.85)
    bar.set_label("$\\gamma$ of the layer [deg]")
    return fig


def plot_forces(t: Array, force: Array, path: str | Path) -> Path:
    """Actuator forces [N] of the four limbs against time (Fig. 20/21 style); ``force`` (n, 4),
    the axial force of each cylinder on its piston (positive: pushes the limb longer)."""
    fig = Figure(figsize=(7.5, 4.5), layout="constrained")
    ax = fig.subplots()
    for k in range(4):
        ax.plot(t, force[:, k], label=_LIMBS[k])
    ax.set_xlabel("time [s]")
    ax.set_ylabel("actuator force [N]")
    ax.grid(True, alpha=0.3)
    ax.legend(ncol=4, loc="best")
    ax.set_title("PDM actuator forces, Newton-Euler (Eq. 49-62)")
    return _save(fig, path)


def plot_overconstraints(t: Array, redundant: Array, path: str | Path) -> Path:
    """The nine over-constrained reaction components (Fig. 22 style): force along z [N] and
    moments about x and y [N m] at R32, R21 (crank 1 - piston 1) and R22; ``redundant`` (n, 9)
    in the order of ``paper.REDUNDANT_LABELS``. SI units, as in the files."""
    fig = Figure(figsize=(12.0, 7.0), layout="constrained")
    axes = fig.subplots(2, 3, sharex=True)
    for c, (joint, col) in enumerate((("R32", 2), ("R21", 0), ("R22", 1))):
        data = redundant[:, 3 * col:3 * col + 3]
        axes[0, c].plot(t, data[:, 0], color="C0", label="$f_z$")
        axes[0, c].set_ylabel("force [N]")
        axes[0, c].set_title(f"{joint}: $f_z$")
        axes[1, c].plot(t, data[:, 1], color="C1", label="$m_x$")
        axes[1, c].plot(t, data[:, 2], color="C2", label="$m_y$")
        axes[1, c].set_ylabel("moment [N m]")
        axes[1, c].set_title(f"{joint}: $m_x$, $m_y$")
        axes[1, c].legend(loc="best")
        axes[1, c].set_xlabel("time [s]")
        for ax in axes[:, c]:
            ax.grid(True, alpha=0.3)
    fig.suptitle("Reactions in the over-constrained directions (Eq. 70), unique by link compliance (Eq. 83)")
    return _save(fig, path)

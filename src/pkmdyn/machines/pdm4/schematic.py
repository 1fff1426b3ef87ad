"""Schematic of the reconstructed PDM layout at a pose: top, side and front views.

Drawn from the model alone (joint positions from :func:`inverse_position`), so the picture
always matches the parameters that produced it. Regenerate ``docs/pdm4_schematic.png`` with
``python -m pkmdyn.machines.pdm4.schematic docs/pdm4_schematic.png``.
"""

from __future__ import annotations

import sys
import textwrap
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import NDArray

from .kinematics import inverse_position
from .params import PdmModel, default_params_path, load_params

__all__ = ["draw_schematic", "schematic_figure"]

Array = NDArray[np.float64]
_MM = 1e3
_VIEWS = (("top view (x-y), looking down -z", 0, 1), ("side view (y-z), looking along -x", 1, 2),
          ("front view (x-z), looking along +y", 0, 2))


def _points(model: PdmModel, q: Array) -> tuple[dict[str, Array], list[tuple[str, str, str]], Array]:
    pos = inverse_position(model, q.reshape(1, 4), check_strokes=False)
    pts: dict[str, Array] = {}
    for i in range(2):
        k = i + 1
        pts[f"R1{k}"] = model.R1[i]
        pts[f"R2{k}"] = pos.R2[0, i]
        pts[f"R3{k}"] = pos.R3[0, i]
        pts[f"R4{k}"] = model.R4[i]
        pts[f"S2{k + 2}"] = model.S[i]
        pts[f"U2{k + 2}"] = pos.U[0, i]
    pts["C (R4)"] = pos.C[0]
    pts["P"] = pos.P[0]
    T = pos.T[0]
    pts["R4 axis -"] = pos.C[0] - 0.06 * T[:, 0]
    pts["R4 axis +"] = pos.C[0] + 0.06 * T[:, 0]
    links = [
        ("R11", "R21", "C0"), ("R12", "R22", "C0"), ("R21", "R31", "C1"), ("R22", "R32", "C1"),
        ("R31", "R32", "C2"), ("R41", "R21", "C3"), ("R42", "R22", "C3"),
        ("S23", "U23", "C4"), ("S24", "U24", "C4"), ("C (R4)", "P", "C5"),
        ("R4 axis -", "R4 axis +", "C5"), ("U23", "U24", "C5"),
        ("R11", "R12", "0.5"),
    ]
    return pts, links, T


def draw_schematic(model: PdmModel, path: str | Path, q: Array | None = None) -> Path:
    """Draw the mechanism at pose ``q`` (4,) (home when None) with every joint labelled.

    Colours: cranks r2i, couplers r3i, output link r4, RPR limbs, SPU limbs, platform (with
    the R4 axis and the offset r0 to P); grey: the ground line R11-R12.
    """
    fig = schematic_figure(model, q)
    fig.savefig(path, dpi=110)
    return Path(path)


def schematic_figure(model: PdmModel, q: Array | None = None) -> Figure:
    """The figure of :func:`draw_schematic` (with its Agg canvas), not yet saved."""
    q = np.zeros(4) if q is None else np.asarray(q, dtype=float)
    pts, links, _ = _points(model, q)
    fig = Figure(figsize=(15.0, 8.0), layout="constrained")
    grid = fig.add_gridspec(2, 2, width_ratios=(1.25, 1.0))
    axes = [fig.add_subplot(grid[:, 0]), fig.add_subplot(grid[0, 1]), fig.add_subplot(grid[1, 1])]
    names = {"C0": "crank r2i", "C1": "coupler r3i", "C2": "output link r4", "C3": "RPR limb",
             "C4": "SPU limb", "C5": "platform: R4 axis, U23-U24, r0 to P", "0.5": "ground R11-R12"}
    for ax, (title, a, b) in zip(axes, _VIEWS):
        seen = set()
        for p0, p1, colour in links:
            xy = np.array([pts[p0], pts[p1]]) * _MM
            label = names.get(colour) if colour not in seen else None
            seen.add(colour)
            style = {"C2": (5, 3), "C5": (1.5, 4)}.get(colour, (3 if colour in ("C3", "C4") else 2, 2))
            ax.plot(xy[:, a], xy[:, b], color=colour, lw=style[0], zorder=style[1], label=label,
                    ls="--" if colour == "C5" else "-")
        groups: dict[tuple[float, float], list[str]] = {}
        for name, p in pts.items():
            if name.startswith("R4 axis"):
                continue
            ground = name[:2] in ("R1", "R4", "S2")
            ax.plot(p[a] * _MM, p[b] * _MM, "s" if ground else "o", color="k", ms=6 if ground else 4, zorder=5)
            groups.setdefault((round(p[a] * _MM, 1), round(p[b] * _MM, 1)), []).append(name)
        for (u, v), members in groups.items():
            offset = (2, -13) if members[0].startswith("U2") and a == 0 else (4, 5)
            ax.annotate("/".join(members), (u, v), textcoords="offset points", xytext=offset, fontsize=8, zorder=6)
        ax.annotate("", xy=(60, 0), xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": "0.3"})
        ax.annotate("", xy=(0, 60), xytext=(0, 0), arrowprops={"arrowstyle": "->", "color": "0.3"})
        axis_names = "xyz"
        ax.text(62, -12, axis_names[a], color="0.3")
        ax.text(-12, 62, axis_names[b], color="0.3")
        ax.set_xlabel(f"{axis_names[a]} [mm]")
        ax.set_ylabel(f"{axis_names[b]} [mm]")
        ax.set_title(title)
        ax.set_aspect("equal")
        ax.grid(True, alpha=0.3)
    # the legend below every axis (constrained layout keeps room for it), never over an axis label
    fig.legend(*axes[0].get_legend_handles_labels(), fontsize=8, loc="outside lower center", ncol=6)
    deg = np.degrees(q[2:])
    # the parameter file by name in the title; its folder, however long, wrapped on its own lines
    source = Path(model.source)
    builtin = source == default_params_path()
    name = f"built-in {source.name}" if builtin else source.name
    where = "" if builtin or source.name == model.source else "\n".join(
        textwrap.wrap(f"parameters: {model.source}", 150))
    fig.suptitle(
        f"4-DOF PDM, reconstructed layout ({name}); pose x = {q[0] * _MM:g} mm, "
        f"y = {q[1] * _MM:g} mm, alpha = {deg[0]:g} deg, gamma = {deg[1]:g} deg\n"
        "squares: ground joints; base frame A at the home position of C; revolute axes R1i-R4i along z"
        + (f"\n{where}" if where else ""), fontsize=11)
    FigureCanvasAgg(fig)
    return fig


if __name__ == "__main__":  # pragma: no cover
    out = sys.argv[1] if len(sys.argv) > 1 else "pdm4_schematic.png"
    print(draw_schematic(load_params(sys.argv[2] if len(sys.argv) > 2 else None), out))

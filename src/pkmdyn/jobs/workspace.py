"""``pkmdyn workspace``: a machine and a grid of task poses in; ``workspace.json``, ``workspace.csv``,
``workspace.png`` and ``report.html`` out (``docs/workspace.md``). The numbers come from
:mod:`pkmdyn.multibody.analyses.workspace`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import ParameterError
from ..io import write_csv, write_json
from ..multibody.analyses.task_grid import parse_grid, parse_pose, parse_ranges
from ..multibody.analyses.workspace import (
    Workspace,
    check_centre,
    workspace,
    workspace_document,
)
from ..multibody.description.schema import LIMIT_KEYS
from ..multibody.dynamics.actuators import effective_limits
from ..multibody.model.compiler import MechanismModel
from ..params_util import parse_limit_options
from ..report import Output, Report, write_output
from ._files import JobResult, prepare

__all__ = ["job"]


def job(machine: str, grid: str, pose: str, orientation_range: str | None, threshold: float, centre: str | None,
        refine: int, out_dir: Path, announce: Callable[[Mapping[str, Path]], None] | None = None,
        limit_items: tuple[str, ...] = ()) -> JobResult:
    """The reachable workspace of ``machine`` on the grid ``grid`` (``NAME=LOW:HIGH:COUNT,...``) with
    the other task coordinates held at ``pose`` (over ``orientation_range`` where given), inside
    where every singularity measure is at least ``threshold``; the inscribed cube and cylinder
    about ``centre`` (``V1,V2,...``; default the pose's); ``refine`` steps along each boundary edge;
    ``limit_items``: ``--limit KEY=VALUE`` over the description's ``[limits]`` (the grid's poses:
    ``max_workspace_poses``)."""
    limits = parse_limit_options(limit_items, LIMIT_KEYS)
    p = prepare(machine, out_dir, limits=limits)
    model = p.model
    eff = effective_limits(model, limits)
    axes = parse_grid(model, grid, max_axes=3, max_points=int(eff["max_workspace_poses"]),
                      limit_key="max_workspace_poses", limits=eff)
    base = parse_pose(model, pose, eff)
    ranges = None if orientation_range is None else parse_ranges(model, orientation_range, eff)
    c = None
    if centre is not None:
        try:
            c = np.array([float(v) for v in centre.split(",")])
        except ValueError:
            raise ParameterError(f"--centre {centre!r}: expected numbers separated by commas") from None
        c = check_centre(c, len(axes))
    ws = workspace(model, axes, base, threshold, c, ranges, refine=refine)
    doc = workspace_document(model, ws)

    report = Report(f"{model.name}: workspace", summary=doc, parameters=p.text, images=["map"],
                    notes=["definitions: docs/workspace.md"])

    def make(out: Path) -> Output:
        files = {"workspace": out / "workspace.json", "poses": out / "workspace.csv", "map": out / "workspace.png"}
        write_json(files["workspace"], doc)
        write_csv(files["poses"], ws.columns())
        workspace_png(files["map"], model, ws)
        return Output(files, report=report)

    files, _ = write_output(out_dir, p.inputs, make, announce)
    shapes = ("" if ws.cube_half_width is None else
              f"; inscribed cube half-width {ws.cube_half_width:.4g}, cylinder radius {ws.cylinder_radius:.4g}")
    lines = (f"{doc['inside']} of {doc['poses']} poses inside (reached: {doc['reached']}); size "
             f"{ws.size:.6g} +- {ws.size_error:.2g} {ws.unit}{shapes}",)
    warnings = ()
    if doc["size_is_lower_bound"]:
        warnings = (f"the workspace reaches the grid's edge along {', '.join(doc['inside_at_grid_edge'])}: "
                    "its size is a lower bound (widen --grid there)",)
    return JobResult(files, doc, lines, warnings, report=report)


def workspace_png(path, model: MechanismModel, ws: Workspace) -> None:
    """Write :func:`workspace_figure` to ``path``."""
    import matplotlib.pyplot as plt

    fig = workspace_figure(model, ws)
    fig.savefig(path, dpi=100)
    plt.close(fig)


def workspace_figure(model: MechanismModel, ws: Workspace) -> Any:
    """The workspace's map: the smallest singularity measure over the inside poses (blank
    outside); a three-axis grid as up to six slices along its last axis. The layout is
    constrained, so no slice's title reaches the axis labels of the row above."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [f"{model.task_names[i]} [{model.task_units[i]}]" for i, _ in ws.axes]
    vals = np.where(ws.inside, ws.measure, np.nan)
    shape = tuple(len(v) for _, v in ws.axes)
    if len(ws.axes) == 1:
        fig, ax = plt.subplots(figsize=(7, 4), layout="constrained")
        ax.plot(ws.axes[0][1], vals, "o-", ms=3)
        ax.set_xlabel(names[0])
        ax.set_ylabel("smallest singularity measure")
    else:
        grid = vals.reshape(shape)
        if len(ws.axes) == 2:
            slices, titles = [grid], [""]
        else:
            ks = np.unique(np.linspace(0, shape[2] - 1, min(6, shape[2])).round().astype(int))
            slices = [grid[:, :, k] for k in ks]
            titles = [f"{names[2]} = {ws.axes[2][1][k]:.4g}" for k in ks]
        cols = min(3, len(slices))
        rows = -(-len(slices) // cols)
        fig, axs = plt.subplots(rows, cols, figsize=(4.6 * cols, 4.0 * rows), squeeze=False, layout="constrained")
        for a, g, title in zip(axs.flat, slices, titles):
            mesh = a.pcolormesh(ws.axes[0][1], ws.axes[1][1], np.ma.masked_invalid(g).T, shading="auto",
                                vmin=0.0, vmax=float(np.nanmax(vals)) if np.isfinite(vals).any() else 1.0)
            a.set_xlabel(names[0])
            a.set_ylabel(names[1])
            a.set_title(title)
            a.set_aspect("equal" if model.task_units[ws.axes[0][0]] == model.task_units[ws.axes[1][0]] else "auto")
        for a in list(axs.flat)[len(slices):]:
            a.axis("off")
        fig.colorbar(mesh, ax=axs, label="smallest singularity measure")
    fig.suptitle(f"{model.name}: workspace ({int(ws.inside.sum())} of {len(ws.x)} poses inside; "
                 f"size {ws.size:.4g} +- {ws.size_error:.2g} {ws.unit})")
    return fig

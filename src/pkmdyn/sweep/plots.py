"""Plots of a sweep for a designer: Pareto front, metric against parameter, scatter matrix.

Feasible designs are blue, the Pareto set red, designs that are valid but break a constraint
(or a limit) light grey; designs without metrics are not drawn. Large sweeps are thinned to
at most :data:`MAX_POINTS` points per plot (the Pareto set is always drawn whole).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..io import atomic_file
from .space import SweepSpace

__all__ = ["sweep_plots", "MAX_POINTS"]

MAX_POINTS = 20_000
_MAX_PARAMS = 6  # parameters shown in the scatter matrix and against the metrics


def _column(table: Any, name: str) -> NDArray[np.float64]:
    col = table.column(name).to_numpy(zero_copy_only=False)
    return np.asarray([np.nan if v is None else v for v in col], dtype=float) if col.dtype == object else col.astype(float)


def _thin(idx: NDArray[np.int64]) -> NDArray[np.int64]:
    if idx.size <= MAX_POINTS:
        return idx
    return idx[np.linspace(0, idx.size - 1, MAX_POINTS).round().astype(np.int64)]


def _save(fig: Any, path: Path) -> Path:
    import matplotlib.pyplot as plt

    with atomic_file(path, notify=None) as tmp:
        fig.savefig(tmp, dpi=110, format="png")
    plt.close(fig)
    return path


def sweep_plots(out: Path, table: Any, space: SweepSpace, front: NDArray[np.int64]) -> dict[str, Path]:
    """Write the three plots into ``out``; returns ``{label: path}``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    status = np.asarray(table.column("status").to_pylist(), dtype=object)
    ok = np.flatnonzero(status == "ok")
    other = np.flatnonzero(np.isin(status, ["infeasible", "limit", "singular"]))
    params = [p.key for p in space.parameters][:_MAX_PARAMS]
    objectives = [m for m, _ in space.objectives]
    metrics = list(dict.fromkeys(objectives + [b.metric for b in space.constraints]))[:4]
    files: dict[str, Path] = {}

    def scatter(ax: Any, x: str, y: str) -> None:
        for idx, kw in ((_thin(other), dict(c="0.8", s=4, label="constraint or limit broken")),
                        (_thin(ok), dict(c="tab:blue", s=5, label="feasible")),
                        (front, dict(c="tab:red", s=12, label="Pareto set"))):
            if idx.size:
                ax.scatter(_column(table, x)[idx], _column(table, y)[idx], rasterized=True, **kw)

    # Pareto front: the first two objectives (one objective: against the first parameter)
    fig, ax = plt.subplots(figsize=(6.4, 4.8))
    x, y = (objectives[0], objectives[1]) if len(objectives) > 1 else (params[0], objectives[0])
    scatter(ax, x, y)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.set_title(f"{len(front)} Pareto designs of {len(ok)} feasible, {len(status)} in all")
    ax.legend(loc="best", fontsize=8)
    ax.grid(True, alpha=0.3)
    fig.tight_layout()
    files["pareto_plot"] = _save(fig, out / "pareto_front.png")

    # each objective and constrained metric against each parameter
    fig, axes = plt.subplots(len(metrics), len(params), figsize=(2.6 * len(params) + 1, 2.2 * len(metrics) + 0.6),
                             squeeze=False)
    for r, m in enumerate(metrics):
        for c, p in enumerate(params):
            ax = axes[r, c]
            scatter(ax, p, m)
            if r == len(metrics) - 1:
                ax.set_xlabel(p, fontsize=8)
            if c == 0:
                ax.set_ylabel(m, fontsize=8)
            ax.tick_params(labelsize=7)
    fig.tight_layout()
    files["metric_plot"] = _save(fig, out / "metric_vs_parameter.png")

    # scatter matrix of the parameters (which regions are feasible, where the front lies)
    k = len(params)
    fig, axes = plt.subplots(k, k, figsize=(2.2 * k + 0.6, 2.2 * k + 0.6), squeeze=False)
    for r in range(k):
        for c in range(k):
            ax = axes[r, c]
            if r == c:
                vals = _column(table, params[r])
                ax.hist(vals[ok], bins=30, color="tab:blue", alpha=0.6)
                if front.size:
                    ax.hist(vals[front], bins=30, color="tab:red", alpha=0.8)
            else:
                scatter(ax, params[c], params[r])
            if r == k - 1:
                ax.set_xlabel(params[c], fontsize=7)
            if c == 0:
                ax.set_ylabel(params[r], fontsize=7)
            ax.tick_params(labelsize=6)
    fig.tight_layout()
    files["scatter_matrix_plot"] = _save(fig, out / "scatter_matrix.png")
    return files


def convergence_plot(path: Path, generations: list[dict]) -> Path:
    """An NSGA-II run's convergence: the hypervolume of the feasible Pareto set after each
    generation (``summary.json`` ``generations``)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    g = [r["generation"] for r in generations]
    fig, ax = plt.subplots(figsize=(7, 4))
    ax.plot(g, [r["hypervolume"] for r in generations], "o-", ms=3)
    ax.set_xlabel("generation")
    ax.set_ylabel("hypervolume (objectives scaled to [0, 1], reference 1.1)")
    ax.set_title("NSGA-II convergence")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

"""Reachable workspace of the PDM by boundary search, section 2.2 and Fig. 3.

For each platform angle gamma (a layer; alpha held fixed) the set of reachable x-y positions
of the platform point P is bounded by rays from a reachable centre: each ray is walked
outward in coarse steps until the first unreachable pose, then the crossing is bisected.
Reachable means :func:`~pkmdyn.machines.pdm4.kinematics.reachable`: both six-bar loops close
with a transmission angle of at least ``min_transmission``, and every limb extension lies
within ``+- stroke_limit`` (50 mm in the paper). The height of P is the parasitic
``z = r0 cos(gamma)`` (the z axis of Fig. 3(a)). The x-y projection (Fig. 3(b)) is the same
search with "reachable at any of the layers" as the test.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...io import write_csv
from .kinematics import reachable
from .params import PdmModel

__all__ = ["Workspace", "boundary_search", "reachable_workspace", "write_workspace_csv"]

Array = NDArray[np.float64]
_BISECTIONS = 40


@dataclass(frozen=True)
class Workspace:
    """Boundary of the reachable workspace. ``alpha`` [rad]; ``gamma`` (L,) [rad] layers;
    ``z`` (L,) [m] height of P; ``valid`` (L,) layers with any reachable pose;
    ``directions`` (D,) [rad] ray directions in the x-y plane; ``centre`` (L, 2) [m];
    ``boundary`` (L, D, 2) [m] x-y of the boundary on every ray (NaN on invalid layers);
    ``at_limit`` (L, D) rays that reached ``max_radius`` without leaving the workspace;
    ``projection`` (D, 2) [m] boundary of the x-y projection of all layers."""

    alpha: float
    gamma: Array
    z: Array
    valid: Array
    directions: Array
    centre: Array
    boundary: Array
    at_limit: Array
    projection: Array

    def area(self) -> Array:
        """Enclosed x-y area of every layer [m^2] (shoelace formula; 0 for invalid layers)."""
        x, y = self.boundary[..., 0], self.boundary[..., 1]
        a = 0.5 * np.abs(np.sum(x * np.roll(y, -1, axis=-1) - np.roll(x, -1, axis=-1) * y, axis=-1))
        return np.where(self.valid, a, 0.0)


def boundary_search(
    inside: Callable[[Array], Array], centre: Array, directions: Array, step: float, max_radius: float
) -> tuple[Array, Array]:
    """Boundary of a planar region along rays from ``centre`` (m, 2) in ``directions`` (D,).

    ``inside`` maps points (k, m, 2) to a mask (k, m). Each ray is sampled every ``step`` up to
    ``max_radius``; the first outside sample and the last inside one before it are bisected
    ``40`` times. Returns boundary points (m, D, 2) and a mask (m, D) of rays that never left.
    """
    radii = np.arange(0.0, max_radius + 0.5 * step, step)
    dirs = np.stack([np.cos(directions), np.sin(directions)], axis=-1)  # (D, 2)
    pts = centre[:, None, None, :] + radii[None, None, :, None] * dirs[None, :, None, :]
    m, d, r = pts.shape[:3]
    ok = inside(pts.reshape(m, d * r, 2)).reshape(m, d, r)
    first_out = np.where(~ok.all(axis=-1), np.argmax(~ok, axis=-1), r)
    at_limit = first_out == r
    lo = radii[np.clip(first_out - 1, 0, r - 1)]
    hi = np.where(at_limit, lo, radii[np.clip(first_out, 0, r - 1)])
    for _ in range(_BISECTIONS):
        mid = 0.5 * (lo + hi)
        inn = inside(centre[:, None, :] + mid[..., None] * dirs[None]).reshape(m, d)
        lo = np.where(inn, mid, lo)
        hi = np.where(inn, hi, mid)
    return centre[:, None, :] + lo[..., None] * dirs[None], at_limit


def _pose(model: PdmModel, xy: Array, gamma: Array) -> Array:
    """Poses (..., 4) from x-y points (..., 2) and one gamma per leading row."""
    g = np.broadcast_to(gamma.reshape((-1,) + (1,) * (xy.ndim - 2)), xy.shape[:-1])
    return np.stack([xy[..., 0], xy[..., 1], np.full(xy.shape[:-1], model.workspace.alpha_rad), g], axis=-1)


def _centres(model: PdmModel, gammas: Array, grid: int = 41) -> tuple[Array, Array]:
    """A reachable centre for every layer: the reachable grid point nearest to the centroid
    of the reachable grid points. Returns centres (L, 2) and a validity mask (L,)."""
    r = model.workspace.max_radius_m
    g = np.linspace(-r, r, grid)
    xy = np.stack(np.meshgrid(g, g, indexing="ij"), axis=-1).reshape(1, -1, 2)
    xy = np.broadcast_to(xy, (gammas.size,) + xy.shape[1:])
    ok = reachable(model, _pose(model, xy, gammas).reshape(-1, 4)).reshape(gammas.size, -1)
    valid = ok.any(axis=1)
    centroid = np.where(valid[:, None], (ok[..., None] * xy).sum(1) / np.maximum(ok.sum(1), 1)[:, None], 0.0)
    dist = np.where(ok, np.linalg.norm(xy - centroid[:, None], axis=-1), np.inf)
    best = xy[np.arange(gammas.size), np.argmin(dist, axis=1)]
    # the origin is preferred when it is reachable (rays then start at the home position)
    home_ok = reachable(model, _pose(model, np.zeros((gammas.size, 1, 2)), gammas).reshape(-1, 4))
    return np.where(home_ok[:, None], 0.0, best), valid


def reachable_workspace(model: PdmModel, progress: bool | None = None) -> Workspace:
    """Boundary search over the gamma layers of ``model.workspace`` (section 2.2, Fig. 3).

    ``progress``: tqdm progress bar over the layers (``None``: only on a terminal).
    """
    ws = model.workspace
    gammas = np.asarray(ws.gamma_rad, dtype=float)
    directions = np.linspace(0.0, 2.0 * np.pi, ws.directions, endpoint=False)
    centres, valid = _centres(model, gammas)
    boundary = np.full((gammas.size, directions.size, 2), np.nan)
    at_limit = np.zeros((gammas.size, directions.size), dtype=bool)
    disable = None if progress is None else not progress
    for k in tqdm(range(gammas.size), desc="workspace layers", unit="layer", disable=disable):
        if not valid[k]:
            continue

        def inside(xy: Array, g: float = float(gammas[k])) -> Array:
            return reachable(model, _pose(model, xy, np.array([g])).reshape(-1, 4)).reshape(xy.shape[:-1])

        b, lim = boundary_search(inside, centres[k:k + 1], directions, ws.radial_step_m, ws.max_radius_m)
        boundary[k], at_limit[k] = b[0], lim[0]

    def inside_any(xy: Array) -> Array:
        flat = xy.reshape(-1, 2)
        poses = _pose(model, np.broadcast_to(flat, (gammas.size,) + flat.shape), gammas)
        return reachable(model, poses.reshape(-1, 4)).reshape(gammas.size, -1).any(axis=0).reshape(xy.shape[:-1])

    if valid.any():
        start = centres[valid].mean(axis=0, keepdims=True)
        if not inside_any(start[None])[0, 0]:
            start = centres[valid][:1]
        proj, _ = boundary_search(inside_any, start, directions, ws.radial_step_m, ws.max_radius_m)
        projection = proj[0]
    else:
        projection = np.full((directions.size, 2), np.nan)
    return Workspace(
        alpha=ws.alpha_rad, gamma=gammas, z=model.r0 * np.cos(gammas), valid=valid,
        directions=directions, centre=centres, boundary=boundary, at_limit=at_limit, projection=projection,
    )


def write_workspace_csv(path: str | Path, ws: Workspace) -> None:
    """Boundary points of the valid layers: ``gamma_rad, alpha_rad, direction_rad, x_m, y_m,
    z_m`` (one row per ray and layer)."""
    k = np.flatnonzero(ws.valid)
    nd = ws.directions.size
    write_csv(path, {
        "gamma_rad": np.repeat(ws.gamma[k], nd),
        "alpha_rad": np.full(k.size * nd, ws.alpha),
        "direction_rad": np.tile(ws.directions, k.size),
        "x_m": ws.boundary[k, :, 0].reshape(-1),
        "y_m": ws.boundary[k, :, 1].reshape(-1),
        "z_m": np.repeat(ws.z[k], nd),
    })


def write_projection_csv(path: str | Path, ws: Workspace) -> None:
    """Boundary of the x-y projection: ``direction_rad, x_m, y_m``."""
    write_csv(path, {"direction_rad": ws.directions, "x_m": ws.projection[:, 0], "y_m": ws.projection[:, 1]})

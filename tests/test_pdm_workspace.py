"""Workspace boundary search (section 2.2, Fig. 3): boundary points separate reachable from
unreachable poses; the projection contains every layer."""

from __future__ import annotations

import numpy as np
import pytest

from pkmdyn.machines.pdm4 import inverse_position, load_params, reachable
from pkmdyn.machines.pdm4.workspace import boundary_search, reachable_workspace, write_workspace_csv

MODEL = load_params()


@pytest.fixture(scope="module")
def ws():
    return reachable_workspace(MODEL, progress=False)


def _poses(xy, gamma):
    return np.column_stack([xy[:, 0], xy[:, 1], np.full(len(xy), MODEL.workspace.alpha_rad), np.full(len(xy), gamma)])


def test_boundary_points_separate_inside_from_outside(ws):
    assert ws.valid.all() and not ws.at_limit.any()
    for k in range(ws.gamma.size):
        c = ws.centre[k]
        b = ws.boundary[k]
        inner = c + (b - c) * (1 - 1e-4)
        outer = c + (b - c) * (1 + 1e-3) + 1e-6 * (b - c) / np.linalg.norm(b - c, axis=1, keepdims=True)
        assert reachable(MODEL, _poses(inner, ws.gamma[k])).all()
        assert not reachable(MODEL, _poses(outer, ws.gamma[k])).any()


def test_boundary_is_set_by_a_stroke_or_a_transmission_limit(ws):
    k = int(np.argmin(np.abs(ws.gamma)))
    pos = inverse_position(MODEL, _poses(ws.boundary[k], ws.gamma[k]), check_strokes=False)
    stroke_margin = MODEL.stroke_limit - np.abs(pos.l - MODEL.home_lengths).max(axis=1)
    trans_margin = np.abs(np.sin(pos.theta2 - pos.theta1)).min(axis=1) - np.sin(MODEL.min_transmission)
    assert np.all(np.minimum(stroke_margin, trans_margin) < 1e-6)
    assert np.all(np.minimum(stroke_margin, trans_margin) >= -1e-12)
    # most of the boundary is the +-50 mm stroke limit of section 2.2
    assert np.mean(stroke_margin < 1e-6) > 0.5


def test_projection_contains_every_layer(ws):
    r_proj = np.linalg.norm(ws.projection - ws.projection.mean(0), axis=1)
    assert r_proj.min() > 0
    poly = np.vstack([ws.projection, ws.projection[:1]])
    from matplotlib.path import Path

    outline = Path(poly)
    pts = ws.boundary[ws.valid].reshape(-1, 2)
    assert outline.contains_points(pts, radius=1e-4).mean() > 0.97
    assert np.all(ws.area() > 0) and np.allclose(ws.z, MODEL.r0 * np.cos(ws.gamma))


def test_boundary_search_on_a_disc():
    def inside(xy):
        return np.linalg.norm(xy - np.array([0.3, -0.2]), axis=-1) <= 0.5

    dirs = np.linspace(0, 2 * np.pi, 16, endpoint=False)
    b, lim = boundary_search(inside, np.array([[0.3, -0.2]]), dirs, 0.07, 2.0)
    assert not lim.any()
    assert np.allclose(np.linalg.norm(b[0] - [0.3, -0.2], axis=1), 0.5, atol=1e-10)


def test_workspace_csv(tmp_path, ws):
    path = tmp_path / "ws.csv"
    write_workspace_csv(path, ws)
    header = path.read_text().splitlines()[0]
    assert header == "gamma_rad,alpha_rad,direction_rad,x_m,y_m,z_m"
    assert len(path.read_text().splitlines()) == 1 + ws.valid.sum() * ws.directions.size

"""Plotly figures of a report: the animated 3D scene, time plots with a time marker, the topology graph.

Lengths are shown in millimetres (converted here, at the edge); coordinates travel as 32-bit
floats (0.1 um at a metre), which halves the page's data.
"""

from __future__ import annotations

import base64
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ._scene import Scene
from ._topology import Topology, layered_layout

__all__ = ["Curve", "TimePlot", "scene_figure", "time_figure", "topology_figure", "decimate_minmax", "MAX_PLOT_POINTS"]

Array = NDArray[np.float64]
_MM = 1e3
#: most points of one curve on the page; a longer curve keeps the minimum and maximum of each bin
MAX_PLOT_POINTS = 4000
_EFFORT_SCALE = "RdBu_r"
_LINK = "#34495e"
_FACE = "#8fb3d9"
_ACTUATOR = "#e67e22"


@dataclass(frozen=True)
class Curve:
    """One curve of a time plot: ``y (m,)`` against the plot's ``t``; with ``lo, hi`` instead
    (an envelope: minimum and maximum per bin) a band is drawn."""

    name: str
    y: Array | None = None
    lo: Array | None = None
    hi: Array | None = None


@dataclass(frozen=True)
class TimePlot:
    """A plot against time ``t (m,)`` [s]: its curves, title and y-axis label (with unit)."""

    title: str
    y_label: str
    t: Array
    curves: tuple[Curve, ...]
    note: str = ""


def decimate_minmax(t: Array, ys: Sequence[Array], max_points: int = MAX_PLOT_POINTS) -> tuple[Array, list[Array], bool]:
    """About ``max_points`` points per plot: beyond, the samples are cut into equal bins and each
    bin keeps, for every curve, the sample of its minimum and of its maximum (so peaks survive);
    all curves share the kept samples. Returns ``t``, the curves, and whether samples were dropped."""
    n = t.shape[0]
    if n <= max_points:
        return t, list(ys), False
    bins = max(1, max_points // (2 * max(1, len(ys))))
    edges = np.linspace(0, n, bins + 1).astype(int)
    keep = [np.array([0, n - 1])]
    for y in ys:
        for b in range(bins):
            seg = y[edges[b]:edges[b + 1]]
            keep.append(edges[b] + np.array([int(np.argmin(seg)), int(np.argmax(seg))]))
    idx = np.unique(np.concatenate(keep))
    return t[idx], [y[idx] for y in ys], True


def _polylines(scene: Scene, bodies: Sequence[tuple[tuple[int, ...], bool]]) -> Array:
    """Point indices of the polylines, ``-1`` between two bodies (a gap in the line)."""
    idx: list[int] = []
    for pts, closed in bodies:
        idx += [*pts, pts[0]] if closed and len(pts) > 2 else list(pts)
        idx.append(-1)
    return np.asarray(idx, dtype=int)


def _coords(points: Array, idx: Array) -> tuple[Array, Array, Array]:
    """x, y, z [mm] (float32) of ``points (p, 3)`` at ``idx``, NaN where ``idx`` is -1."""
    sel = points[np.maximum(idx, 0)] * _MM
    sel[idx < 0] = np.nan
    sel = sel.astype(np.float32)
    return sel[:, 0], sel[:, 1], sel[:, 2]


def _fan(scene: Scene) -> tuple[Array, Array, Array, Array]:
    """Vertex indices and fan triangles (i, j, k) of the filled bodies."""
    verts: list[int] = []
    tri: list[tuple[int, int, int]] = []
    for b in scene.bodies:
        if not b.filled or len(b.points) < 3:
            continue
        base = len(verts)
        verts += list(b.points)
        tri += [(base, base + k, base + k + 1) for k in range(1, len(b.points) - 1)]
    t = np.asarray(tri, dtype=int).reshape(-1, 3)
    return np.asarray(verts, dtype=int), t[:, 0], t[:, 1], t[:, 2]


def _effort_range(scene: Scene) -> tuple[float, str, bool]:
    """Colour range +-M, colour-bar title and whether efforts are normalised (mixed units)."""
    units = {a.unit for a in scene.actuators}
    if len(units) == 1:
        m = max(float(np.max(np.abs(a.effort))) for a in scene.actuators)
        return m, f"effort [{units.pop()}]", False
    return 1.0, "effort / peak", True


def _actuator_colours(scene: Scene, m: float, normalised: bool) -> list[list[str]]:
    """The colour of each actuated chain at each frame (``[frame][actuator]``) on the diverging
    scale over ``[-m, m]`` (one fixed colour when every effort is zero, e.g. a machine shown at
    rest): every frame's in one call of plotly's sampler, which checks the scale once a call."""
    from plotly.colors import sample_colorscale

    n = scene.t.shape[0]
    na = len(scene.actuators)
    if m <= 0 or not na:
        return [[_ACTUATOR] * na for _ in range(n)]
    vals = np.empty((n, na))
    for i, a in enumerate(scene.actuators):
        e = np.asarray(a.effort, dtype=float)[:n]
        if normalised:
            e = e / (float(np.max(np.abs(a.effort))) or 1.0)
        vals[:, i] = np.clip(0.5 + 0.5 * e / m, 0.0, 1.0)
    flat = sample_colorscale(_EFFORT_SCALE, [float(v) for v in vals.ravel()])
    return [flat[k * na:(k + 1) * na] for k in range(n)]


def scene_figure(scene: Scene, title: str, frame_s: float | None = None) -> dict:
    """The 3D figure of ``scene`` as a plotly figure dictionary: one frame per sample with a time
    slider, play buttons at three speeds and pause; actuated chains coloured by their effort
    (diverging scale, zero white). ``frame_s``: seconds of motion per frame at speed 1 (default:
    the mean sample spacing). ``layout.meta`` says whether speed 1 is real time.

    Built as plain dictionaries (plotly's figure format), not validated objects: hundreds of
    frames as ``graph_objects`` take seconds to build; the browser tests check what is drawn.
    """
    from plotly.colors import get_colorscale

    n = scene.t.shape[0]
    moving = [b for b in scene.bodies if not b.ground and b.line]
    link_idx = _polylines(scene, [(b.points, b.closed) for b in moving])
    act_idx = [np.asarray(a.points, dtype=int) for a in scene.actuators]
    verts, fi, fj, fk = _fan(scene)
    joint_pts = np.asarray(scene.joint_points or range(len(scene.point_names)), dtype=int)
    ground = [b for b in scene.bodies if b.ground]
    ground_line = _polylines(scene, [(b.points, b.closed) for b in ground if b.line])
    ground_pts = np.asarray(sorted({p for b in ground for p in b.points}), dtype=int)
    m, cbar_title, normalised = _effort_range(scene) if scene.actuators else (0.0, "", False)
    names = [scene.point_names[k] for k in joint_pts]
    colours = _actuator_colours(scene, m, normalised)

    def moving_traces(k: int) -> list[dict]:
        P = scene.points[k]
        x, y, z = _coords(P, link_idx)
        traces = [{"type": "scatter3d", "x": x, "y": y, "z": z, "mode": "lines", "name": "links",
                   "line": {"color": _LINK, "width": 7}, "hoverinfo": "skip"}]
        vx, vy, vz = _coords(P, verts)
        traces.append({"type": "mesh3d", "x": vx, "y": vy, "z": vz, "i": fi, "j": fj, "k": fk, "color": _FACE,
                       "opacity": 0.55, "name": "platforms", "hoverinfo": "skip", "showlegend": True,
                       "flatshading": True})
        # one trace per actuated chain in one colour: plotly.js draws a per-vertex colour array on a
        # gapped 3D line with warnings, so the colour is sampled here from the scale
        for a, idx, colour in zip(scene.actuators, act_idx, colours[k]):
            ax, ay, az = _coords(P, idx)
            traces.append({"type": "scatter3d", "x": ax, "y": ay, "z": az, "mode": "lines", "name": a.label,
                           "line": {"width": 12, "color": colour}, "showlegend": False, "hoverinfo": "text",
                           "hovertext": f"{a.label}: {float(a.effort[k]):.4g} {a.unit}"})
        jx, jy, jz = _coords(P, joint_pts)
        traces.append({"type": "scatter3d", "x": jx, "y": jy, "z": jz, "mode": "markers", "name": "joints",
                       "text": names, "marker": {"size": 3.5, "color": "#111111"},
                       "hovertemplate": "%{text}<br>x %{x:.1f} mm<br>y %{y:.1f} mm<br>z %{z:.1f} mm<extra></extra>"})
        return traces

    gx, gy, gz = _coords(scene.points[0], ground_pts)
    static = [{"type": "scatter3d", "x": gx, "y": gy, "z": gz, "mode": "markers", "name": "ground joints",
               "text": [scene.point_names[k] for k in ground_pts], "hovertemplate": "%{text} (ground)<extra></extra>",
               "marker": {"size": 5, "symbol": "square", "color": "#7f8c8d"}}]
    lx, ly, lz = _coords(scene.points[0], ground_line)
    static.append({"type": "scatter3d", "x": lx, "y": ly, "z": lz, "mode": "lines", "name": "ground",
                   "line": {"color": "#95a5a6", "width": 3}, "hoverinfo": "skip"})
    if scene.actuators and m > 0:  # the colour bar of the actuated chains (an invisible marker carries it)
        p0 = scene.points[0, 0] * _MM
        static.append({"type": "scatter3d", "x": [float(p0[0])], "y": [float(p0[1])], "z": [float(p0[2])],
                       "mode": "markers", "name": "actuator effort", "showlegend": False, "hoverinfo": "skip",
                       "marker": {"size": 0.1, "opacity": 0.0, "color": [0.0],
                                  "colorscale": get_colorscale(_EFFORT_SCALE),  # plotly.js knows no "_r" names
                                  "cmin": -m, "cmax": m, "showscale": True,
                                  "colorbar": {"title": {"text": cbar_title}, "len": 0.6, "x": 1.0}}})
    if scene.path_point is not None:
        px, py, pz = _coords(scene.points[:, scene.path_point], np.arange(n))
        static.append({"type": "scatter3d", "x": px, "y": py, "z": pz, "mode": "lines",
                       "name": f"path of {scene.point_names[scene.path_point]}",
                       "line": {"color": "#e67e22", "width": 2}, "hoverinfo": "skip"})
    first = len(static)
    movers = list(range(first, first + 3 + len(scene.actuators)))
    # a frame carries only what changes (plotly merges it into the traces): positions, colours, hover
    keep = ("type", "x", "y", "z", "line", "hovertext")
    frames = [{"data": [{key: v for key, v in tr.items() if key in keep} for tr in moving_traces(k)],
               "traces": movers, "name": str(k)} for k in range(n)]
    lo = scene.points.reshape(-1, 3).min(axis=0) * _MM
    hi = scene.points.reshape(-1, 3).max(axis=0) * _MM
    span = np.maximum(hi - lo, 1e-3 * max(float(np.max(hi - lo)), 1.0))
    pad = 0.06 * float(np.max(span))
    lo, hi = lo - pad, hi + pad
    ratio = (hi - lo) / float(np.max(hi - lo))
    if frame_s is None:
        frame_s = float((scene.t[-1] - scene.t[0]) / max(n - 1, 1)) if n > 1 else 0.1
    base_ms = float(np.clip(1e3 * frame_s, 30.0, 400.0))
    realtime = abs(base_ms - 1e3 * frame_s) < 1e-6

    def play(speed: float) -> dict:
        return {"label": f"\u25b6 \u00d7{speed:g}", "method": "animate",
                "args": [None, {"frame": {"duration": base_ms / speed, "redraw": True}, "fromcurrent": True,
                                "transition": {"duration": 0}, "mode": "immediate"}]}

    pause = {"label": "\u275a\u275a pause", "method": "animate",
             "args": [[None], {"frame": {"duration": 0, "redraw": False}, "mode": "immediate",
                               "transition": {"duration": 0}}]}
    steps = [{"label": f"{float(scene.t[k]):.4g}", "value": str(k), "method": "animate",
              "args": [[str(k)], {"frame": {"duration": 0, "redraw": True}, "mode": "immediate",
                                  "transition": {"duration": 0}}]} for k in range(n)]
    axis = [{"title": {"text": f"{c} [mm]"}, "range": [float(lo[i]), float(hi[i])], "autorange": False,
             "showbackground": True, "backgroundcolor": "#e5ecf6", "gridcolor": "white", "zerolinecolor": "white"}
            for i, c in enumerate("xyz")]
    layout = {
        "title": {"text": title, "x": 0.02},
        "height": 680,
        "margin": {"l": 0, "r": 0, "t": 50, "b": 10},
        "legend": {"x": 0.0, "y": 0.95, "bgcolor": "rgba(255,255,255,0.7)"},
        "scene": {"xaxis": axis[0], "yaxis": axis[1], "zaxis": axis[2], "aspectmode": "manual",
                  "aspectratio": {"x": float(ratio[0]), "y": float(ratio[1]), "z": float(ratio[2])},
                  "camera": {"eye": {"x": 1.5, "y": -1.5, "z": 0.9}}, "uirevision": "keep"},
        "updatemenus": [{"type": "buttons", "direction": "left", "x": 0.02, "y": 0.02, "xanchor": "left",
                         "yanchor": "bottom", "pad": {"r": 4, "t": 4}, "showactive": False,
                         "buttons": [play(0.25), play(1.0), play(4.0), pause]}],
        "sliders": [{"active": 0, "x": 0.32, "len": 0.66, "y": 0.0, "yanchor": "bottom", "pad": {"t": 0, "b": 4},
                     "currentvalue": {"prefix": f"{scene.frame_label} = ",
                                      "suffix": f" {scene.frame_unit}" if scene.frame_unit else "", "visible": True},
                     "transition": {"duration": 0}, "steps": steps}],
        "uirevision": "keep",
        "meta": {"realtime": realtime, "frame_ms": base_ms},
    }
    return {"data": [*static, *moving_traces(0)], "layout": layout, "frames": frames}


def typed_array(values: Any, dtype: str = "f4") -> dict:
    """``values`` as plotly.js's typed-array form (``{"dtype", "bdata"}``: the little-endian bytes
    in base64), some three times smaller in a page than a list of decimals; ``dtype`` ``"f4"``
    (single precision, ample for a drawn curve) or ``"f8"``."""
    a = np.ascontiguousarray(np.asarray(values, dtype="<" + dtype))
    return {"dtype": dtype, "bdata": base64.b64encode(a.tobytes()).decode("ascii")}


def time_figure(plot: TimePlot, t0: float) -> dict:
    """A time plot with a vertical marker at ``t0`` (moved with the 3D view's time slider), as a
    plotly figure dictionary (plotly's figure format, written as built: validating it would load
    plotly's whole schema for a handful of line traces)."""
    colours = ("#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd", "#8c564b", "#e377c2", "#7f7f7f",
               "#bcbd22", "#17becf")
    t = typed_array(plot.t, "f8")
    data: list[dict] = []
    for c, curve in enumerate(plot.curves):
        col = colours[c % len(colours)]
        if curve.y is not None:
            data.append({"type": "scatter", "x": t, "y": typed_array(curve.y), "name": curve.name,
                         "mode": "lines", "line": {"color": col, "width": 1.4}})
        else:
            data.append({"type": "scatter", "x": t, "y": typed_array(curve.lo), "mode": "lines",
                         "line": {"color": col, "width": 0.6}, "legendgroup": curve.name, "showlegend": False,
                         "name": curve.name + " (min)"})
            data.append({"type": "scatter", "x": t, "y": typed_array(curve.hi), "mode": "lines",
                         "line": {"color": col, "width": 0.6}, "fill": "tonexty", "legendgroup": curve.name,
                         "name": curve.name + " (min-max)"})
    layout = {
        "title": {"text": plot.title + (f"<br><sup>{plot.note}</sup>" if plot.note else ""), "x": 0.02},
        "height": 330, "margin": {"l": 60, "r": 10, "t": 60 if plot.note else 40, "b": 70},
        "xaxis": {"title": {"text": "t [s]"}}, "yaxis": {"title": {"text": plot.y_label}},
        "legend": {"orientation": "h", "y": -0.3, "x": 0.0},
        "shapes": [{"type": "line", "xref": "x", "yref": "paper", "x0": t0, "x1": t0, "y0": 0, "y1": 1,
                    "line": {"color": "#c0392b", "width": 1.5, "dash": "dot"}}],
        "uirevision": "keep",
    }
    return {"data": data, "layout": layout}


_KIND_COLOUR = {"R": "#1f77b4", "P": "#d62728", "U": "#2ca02c", "S": "#9467bd", "C": "#ff7f0e"}
_KIND_NAME = {"R": "revolute (R)", "P": "prismatic (P)", "U": "universal (U)", "S": "spherical (S)",
              "C": "cylindrical (C)"}


def topology_figure(top: Topology, loops: Sequence[Sequence[str]]) -> "go.Figure":  # noqa: F821
    """The topology graph: bodies as nodes (ground on top), joints as edges coloured by type;
    actuated joints thick, cut joints (one per independent loop) dashed."""
    import plotly.graph_objects as go

    pos = layered_layout(top)
    fig = go.Figure()
    in_loops = {j: [k + 1 for k, lp in enumerate(loops) if j in lp] for j, *_ in top.joints}
    shown: set[tuple[str, bool, bool]] = set()
    mids = []
    for name, kind, a, b in top.joints:
        act, cut = name in top.actuated, name in top.cuts
        (x0, y0), (x1, y1) = pos[a], pos[b]
        key = (kind, act, cut)
        label = _KIND_NAME.get(kind, kind) + (", actuated" if act else "") + (", cut" if cut else "")
        fig.add_trace(go.Scatter(x=[x0, x1], y=[y0, y1], mode="lines", name=label, legendgroup=label,
                                 showlegend=key not in shown, hoverinfo="skip",
                                 line={"color": _KIND_COLOUR.get(kind, "#555555"), "width": 6 if act else 2.5,
                                       "dash": "dash" if cut else "solid"}))
        shown.add(key)
        loops_of = ", ".join(str(k) for k in in_loops[name]) or "none"
        mids.append((0.5 * (x0 + x1), 0.5 * (y0 + y1), name,
                     f"{name}: {_KIND_NAME.get(kind, kind)}<br>{a} - {b}<br>actuated: {'yes' if act else 'no'}"
                     f"<br>cut joint: {'yes' if cut else 'no'}<br>in loop(s): {loops_of}"))
    fig.add_trace(go.Scatter(x=[m[0] for m in mids], y=[m[1] for m in mids], mode="text", text=[m[2] for m in mids],
                             textfont={"size": 10, "color": "#333333"}, hovertext=[m[3] for m in mids],
                             hoverinfo="text", showlegend=False, name="joints"))
    bodies = list(top.bodies)
    fig.add_trace(go.Scatter(
        x=[pos[b][0] for b in bodies], y=[pos[b][1] for b in bodies], mode="markers+text", text=bodies,
        textposition="top center", name="bodies", hoverinfo="text",
        marker={"size": [20 if b == top.ground else 14 for b in bodies],
                "symbol": ["square" if b == top.ground else "circle" for b in bodies],
                "color": ["#7f8c8d" if b == top.ground else "#ecf0f1" for b in bodies],
                "line": {"color": "#2c3e50", "width": 1.5}}))
    fig.update_layout(title={"text": "Topology: bodies (nodes) and joints (edges)", "x": 0.02}, height=560,
                      xaxis={"visible": False, "range": [-0.05, 1.05]}, yaxis={"visible": False},
                      margin={"l": 10, "r": 10, "t": 50, "b": 10}, plot_bgcolor="white",
                      legend={"x": 1.0, "y": 1.0, "xanchor": "right"})
    return fig

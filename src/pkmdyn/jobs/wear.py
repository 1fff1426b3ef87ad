"""The wear job: a described mechanism, a motion and spherical joints in; ``wear.json``,
``markers_<joint>_on_cup.csv``, ``markers_<joint>_on_head.csv``, ``tracks.npz`` and one
``wear_<joint>.png`` per joint out (``docs/wear.md``).
The numbers come from :mod:`pkmdyn.multibody.analyses.wear`."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..io import write_csv, write_json
from ..multibody.analyses.wear import (
    ASPECT_LIMIT,
    SlideTracks,
    WearOptions,
    head_radius,
    joint_index,
    joint_wear,
    marker_count,
    pole_rotation,
)
from ..multibody.description.schema import LIMIT_KEYS
from ..multibody.dynamics.actuators import effective_limits
from ..multibody.kinematics.inverse import solve_kinematics
from ..multibody.kinematics.motion import default_motion, read_task_motion
from ..report import Output, Report, write_output
from ..params_util import check_limit, parse_limit_options
from ._files import JobResult, prepare

__all__ = ["job", "wear_file", "wear_document", "write_wear_files", "tracks_figure"]

Array = NDArray[np.float64]


def wear_document(model: Any, joint: str, on_cup: SlideTracks, on_head: SlideTracks, what: str,
                  opts: WearOptions) -> dict[str, Any]:
    """One joint's entry of ``wear.json`` (``docs/wear.md``)."""
    j = joint_index(model, joint)
    bodies = ("ground" if model.joint_child[j] < 0 else model.body_names[model.joint_child[j]],
              "ground" if model.joint_parent[j] < 0 else model.body_names[model.joint_parent[j]])
    head, cup = bodies if opts.head == "child" else bodies[::-1]
    return {
        "joint": joint, "head_body": head, "cup_body": cup,
        "head_radius_m": float(np.linalg.norm(on_cup.points[0, 0])),
        "load": what, "cycles": opts.cycles,
        "marker_grid": {"spacing_deg": opts.spacing_deg, "cap_deg": opts.cap_deg,
                        "pole": None if opts.pole is None else [float(v) for v in opts.pole],
                        "markers": int(len(on_cup.weights))},
        "wear_factor_mm3_N_m": opts.wear_factor_mm3_N_m,
        "cross_shear_law": opts.cross_shear_law,
        "aspect_ratio_limit": ASPECT_LIMIT,
        "tracks_on_cup": on_cup.summary(),
        "tracks_on_head": on_head.summary(),
        # the cup wears: each cup point's wear from what slides over it (the cup's markers)
        "wear_volume_mm3_per_million_cycles": float(on_head.wear_per_million_cycles),
    }


def _projection(points: Array, pole: Array) -> tuple[Array, Array]:
    """Orthographic coordinates (.., 2) of unit points viewed along ``pole``."""
    B = pole_rotation(pole)
    return points @ B[:, 0], points @ B[:, 1]


def _png(path: Path, joint: str, on_cup: SlideTracks, on_head: SlideTracks) -> Path:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import LineCollection

    fig, axes = plt.subplots(1, 3, figsize=(15, 5))
    pole = on_cup.pole
    r = float(np.linalg.norm(on_cup.points[0, 0]))
    for ax, tr, title in ((axes[0], on_cup, "head markers' tracks on the cup"),
                          (axes[1], on_head, "cup markers' tracks on the head")):
        x, y = _projection(tr.points / r, pole)
        segs = [np.stack([x[:, k], y[:, k]], axis=1) for k in range(x.shape[1])]
        lc = LineCollection(segs, array=tr.cross_shear, cmap="viridis", linewidths=1.2)
        lc.set_clim(0.0, 0.5)
        ax.add_collection(lc)
        ax.add_patch(plt.Circle((0, 0), 1.0, fill=False, color="0.6", lw=0.8))
        ax.set_xlim(-1.05, 1.05)
        ax.set_ylim(-1.05, 1.05)
        ax.set_aspect("equal")
        ax.set_title(title)
        ax.set_xlabel("viewed along the pole (unit sphere)")
        fig.colorbar(lc, ax=ax, label="cross-shear")
    x, y = _projection(on_head.markers, pole)
    sc = axes[2].scatter(x, y, c=on_head.wear * 1e6 / on_head.cycles, cmap="magma", s=40)
    axes[2].add_patch(plt.Circle((0, 0), 1.0, fill=False, color="0.6", lw=0.8))
    axes[2].set_xlim(-1.05, 1.05)
    axes[2].set_ylim(-1.05, 1.05)
    axes[2].set_aspect("equal")
    axes[2].set_title("wear over the cup (per point, Archard)")
    fig.colorbar(sc, ax=axes[2], label="mm^3 per million cycles (whole load on that track)")
    fig.suptitle(f"joint {joint}: slide tracks and wear (aspect ratio > {ASPECT_LIMIT:g}: "
                 f"{100 * np.mean(on_cup.aspect_ratio > ASPECT_LIMIT):.0f} % of the tracks on the cup)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def wear_file(model: Any, results: list[tuple[str, SlideTracks, SlideTracks, str]], opts: WearOptions,
              extra: dict[str, Any] | None = None) -> dict[str, Any]:
    """The document ``wear.json`` holds: the mechanism, ``extra`` and each joint's entry."""
    return {"mechanism": model.name, "definitions": "docs/wear.md", **(extra or {}),
            "joints": [wear_document(model, j, c, h, w, opts) for j, c, h, w in results]}


def write_wear_files(out: Path, model: Any, results: list[tuple[str, SlideTracks, SlideTracks, str]],
                     opts: WearOptions, extra: dict[str, Any] | None = None, plots: bool = True) -> dict[str, Path]:
    """``wear.json`` (:func:`wear_file`), the markers' tables, ``tracks.npz`` and (``plots``) the PNGs
    into the folder ``out``."""
    files: dict[str, Path] = {}
    files["wear"] = out / "wear.json"
    write_json(files["wear"], wear_file(model, results, opts, extra))
    arrays: dict[str, Array] = {}
    for j, on_cup, on_head, _ in results:
        for surface, tr in (("cup", on_cup), ("head", on_head)):
            files[f"markers_{j}_on_{surface}"] = out / f"markers_{j}_on_{surface}.csv"
            write_csv(files[f"markers_{j}_on_{surface}"], tr.columns())
            arrays[f"{j}__on_{surface}_points_m"] = tr.points
        if plots:
            files[f"png_{j}"] = _png(out / f"wear_{j}.png", j, on_cup, on_head)
    files["tracks"] = out / "tracks.npz"
    np.savez_compressed(files["tracks"], **arrays)
    return files


def tracks_figure(joint: str, tracks: SlideTracks, max_points: int = 60) -> dict:
    """A 3D view of the head's markers' tracks on the cup (each track at most ``max_points``
    points, evenly spaced), coloured by cross-shear, on the sphere [mm]: a plotly figure
    dictionary (plotly's figure format, written as built)."""
    n = tracks.points.shape[0]
    idx = np.unique(np.linspace(0, n - 1, min(n, max_points)).round().astype(int))
    P = np.round(tracks.points[idx] * 1e3, 3)  # [mm], to a micrometre: a light page
    xs, ys, zs, cs = [], [], [], []
    for k in range(P.shape[1]):
        xs += list(P[:, k, 0]) + [None]
        ys += list(P[:, k, 1]) + [None]
        zs += list(P[:, k, 2]) + [None]
        cs += [float(tracks.cross_shear[k])] * len(idx) + [float(tracks.cross_shear[k])]
    r = float(np.linalg.norm(tracks.points[0, 0])) * 1e3
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 36), np.linspace(0, np.pi, 18))
    sphere = {"type": "surface", "x": (r * np.cos(u) * np.sin(v)).tolist(), "y": (r * np.sin(u) * np.sin(v)).tolist(),
              "z": (r * np.cos(v)).tolist(),
              "opacity": 0.15, "showscale": False, "colorscale": [[0, "#999"], [1, "#999"]], "hoverinfo": "skip"}
    lines = {"type": "scatter3d", "x": xs, "y": ys, "z": zs, "mode": "lines", "name": "tracks",
             "line": {"color": cs, "colorscale": "Viridis", "cmin": 0.0, "cmax": 0.5, "width": 3,
                      "colorbar": {"title": {"text": "cross-shear"}}}}
    return {"data": [sphere, lines],
            "layout": {"title": {"text": f"{joint}: the head's markers' tracks on the cup [mm]"}, "height": 560,
                       "scene": {"aspectmode": "data", "xaxis": {"title": {"text": "x [mm]"}},
                                 "yaxis": {"title": {"text": "y [mm]"}}, "zaxis": {"title": {"text": "z [mm]"}}}}}


def job(machine: str, joints: tuple[str, ...], out_dir: Path, *, motion_path: Path | None = None,
        opts: WearOptions = WearOptions(), announce: Callable[[Mapping[str, Path]], None] | None = None,
        limit_items: tuple[str, ...] = ()) -> JobResult:
    """``pkmdyn wear``: the slide tracks and wear of ``machine``'s spherical ``joints`` along the
    motion file ``motion_path`` (default: the machine's default motion) with the settings ``opts``,
    into ``out_dir`` (``docs/wear.md``); ``limit_items``: ``--limit KEY=VALUE`` over the
    description's ``[limits]`` (the tracks' size: ``max_wear_track_points``, markers x samples)."""
    limits = parse_limit_options(limit_items, LIMIT_KEYS)
    p = prepare(machine, out_dir, {"--motion": motion_path}, limits)
    model = p.model
    cap = int(effective_limits(model, limits)["max_wear_track_points"])
    markers = marker_count(opts.spacing_deg, opts.cap_deg)  # counted, not built: bounded before anything grows
    what = f"wear: the markers (--spacing-deg {opts.spacing_deg:g}, --cap-deg {opts.cap_deg:g})"
    check_limit(markers, cap, what, "max_wear_track_points", file="the description")
    opts = replace(opts, max_markers=cap)
    for j in joints:
        head_radius(model, j, opts.radius_m)
    if motion_path is not None:
        motion = read_task_motion(model, Path(motion_path).absolute())
    elif p.entry is not None:
        motion = p.entry.default_motion()
    else:
        motion = default_motion(model)
    check_limit(markers * len(motion.t), cap, f"{what} ({markers:,}) x the samples ({len(motion.t):,})",
                "max_wear_track_points",
                file="the description")
    kin = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
    results = [(j, *joint_wear(model, kin, j, opts, motion.loads)) for j in dict.fromkeys(joints)]
    extra = {"motion": str(motion_path) if motion_path else "the machine's default motion"}
    doc = wear_file(model, results, opts, extra)

    report = Report(f"{model.name}: slide tracks and wear", summary={j["joint"]: j for j in doc["joints"]},
                    parameters=p.text, notes=["definitions: docs/wear.md"],
                    figures=[(f"{j}: tracks on the cup", tracks_figure(j, c)) for j, c, _, _ in results])

    def make(out: Path) -> Output:
        files = write_wear_files(out, model, results, opts, extra)
        return Output(files, report=replace(report, images=[k for k, f in files.items() if f.suffix == ".png"]))

    files, output = write_output(out_dir, p.inputs, make, announce)
    lines = []
    for j, on_cup, on_head, what in results:
        s = on_cup.summary()
        lines.append(f"{j}: {s['markers']} markers; load: {what}; sliding distance per cycle "
                     f"{1e3 * s['sliding_distance_per_cycle_m']['mean']:.4g} mm (mean); aspect ratio median "
                     f"{s['aspect_ratio']['median']:.4g}, share above 5.5: "
                     f"{100 * s['share_aspect_ratio_above_5_5']:.0f} %; cross-shear mean {s['cross_shear']['mean']:.3g}; "
                     f"wear {on_head.wear_per_million_cycles:.4g} mm^3 per million cycles")
    return JobResult(files, doc, tuple(lines), report=output.report)

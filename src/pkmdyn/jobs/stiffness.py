"""The stiffness job: poses, a motion or a grid of poses in; ``stiffness.json``, ``results.csv``
(a motion), ``grid.csv`` and ``stiffness_map.png`` (a grid) and ``report.html`` out
(``docs/stiffness.md``). The numbers come from :func:`pkmdyn.multibody.analyses.stiffness.stiffness` and
:func:`pkmdyn.multibody.analyses.stiffness.deflection`."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError, PkmdynError
from ..io import write_csv, write_json
from ..multibody.analyses.stiffness import (
    ROTORS,
    Stiffness,
    StiffnessDataMissing,
    compliance_sources,
    deflection,
    internal_force_stiffness,
    metric_columns,
    reaction_route,
    stiffness,
)
from ..multibody.analyses.task_grid import grid_poses, parse_grid, parse_pose
from ..multibody.columns import model_summary
from ..multibody.description.schema import LIMIT_KEYS
from ..multibody.dynamics.actuators import effective_limits
from ..multibody.dynamics.newton_euler import joint_reactions
from ..multibody.kinematics.inverse import (
    MechanismKinematics,
    reachable,
    reference_task,
    solve_kinematics,
)
from ..multibody.kinematics.motion import default_motion as one_cycle
from ..multibody.kinematics.motion import read_task_motion
from ..multibody.model.compiler import MechanismModel
from ..params_util import parse_limit_options
from ..report import Output, Report, scene_from_joints, write_output
from ._files import JobResult, prepare

__all__ = ["job", "pose_document", "run_stiffness", "MAX_GRID_POINTS"]

Array = NDArray[np.float64]

#: the most poses a stiffness grid may hold
MAX_GRID_POINTS = 10_000
#: the samples of a motion whose stiffness and deflection are computed at once
MOTION_CHUNK = 2048
#: the lowest modes drawn in the report
DRAWN_MODES = 3


def _unit_of(model: MechanismModel, i: int, j: int) -> str:
    """Unit of ``K_task[i, j]``: the generalised force of coordinate i per unit of coordinate j."""
    force = "N" if model.task_units[i] == "m" else "N m"
    return f"{force}/{'m' if model.task_units[j] == 'm' else 'rad'}"


def _finite_or_none(v: float) -> float | None:
    return float(v) if math.isfinite(v) else None


def pose_document(model: MechanismModel, st: Stiffness, s: int) -> dict[str, Any]:
    """One pose's entry of ``stiffness.json`` (``docs/stiffness.md``)."""
    names = [f"{n}_{u}" for n, u in zip(model.task_names, model.task_units)]
    nt = model.nt
    return {
        "task": {k: float(v) for k, v in zip(names, st.x[s])},
        "K_task": [[float(st.K_task[s, i, j]) for j in range(nt)] for i in range(nt)],
        "K_task_units": [[_unit_of(model, i, j) for j in range(nt)] for i in range(nt)],
        "eigen_stiffness": [{"value": float(st.eigenvalues[s, k]),
                             "direction": {n: float(v) for n, v in zip(names, st.eigenvectors[s, :, k])}}
                            for k in range(nt)],
        "compliance_at_task_point": {
            "order": ["rx_rad", "ry_rad", "rz_rad", "x_m", "y_m", "z_m"],
            "per": ["mx_Nm", "my_Nm", "mz_Nm", "fx_N", "fy_N", "fz_N"],
            "matrix": [[float(v) for v in row] for row in st.C_point[s]],
        },
        "min_stiffness_N_m": _finite_or_none(st.min_stiffness[s]),
        "min_stiffness_direction": [float(v) for v in st.min_stiffness_direction[s]],
        "min_rot_stiffness_Nm_rad": _finite_or_none(st.min_rot_stiffness[s]),
        "min_rot_stiffness_direction": [float(v) for v in st.min_rot_stiffness_direction[s]],
        "M_task": [[float(st.M_task[s, i, j]) for j in range(nt)] for i in range(nt)],
        "frequencies_Hz": [float(f) for f in st.frequencies[s]],
        "rotors": st.rotors,
        "frequencies_rotors_held_Hz": [float(f) for f in st.frequencies_rotors_held[s]],
        "frequencies_rotors_moving_Hz": [float(f) for f in st.frequencies_rotors_moving[s]],
        "modes": [{"frequency_Hz": float(st.frequencies[s, k]),
                   "shape": {n: float(v) for n, v in zip(names, st.modes[s, :, k])},
                   "modal_mass": float(st.modal_mass[s, k]),
                   "modal_stiffness": float(st.modal_stiffness[s, k])} for k in range(nt)],
    }


def _internal_force(model: MechanismModel, doc: dict[str, Any]) -> None:
    """A redundantly actuated mechanism's pose entries gain ``internal_force``: its internal
    force holding still at the pose by its ``[actuation]`` (a preload, a least peak), and
    ``K_internal``, the task stiffness that force adds with the drives holding their efforts
    (:func:`~pkmdyn.multibody.analyses.stiffness.internal_force_stiffness`; docs/stiffness.md)."""
    entries = [e for e in (*doc.get("poses", []), doc.get("worst")) if e is not None]
    if not entries:
        return
    x = np.array([[e["task"][f"{n}_{u}"] for n, u in zip(model.task_names, model.task_units)] for e in entries])
    z = np.zeros_like(x)
    kin = solve_kinematics(model, x, z, z)
    internal = joint_reactions(model, kin, overconstrained=reaction_route(model), split=True).shares.internal
    K = internal_force_stiffness(model, x, internal)
    nt = model.nt
    for e, ui, Ki in zip(entries, internal, K):
        e["internal_force"] = {nm: float(v) for nm, v in zip(model.actuator_names, ui)}
        e["K_internal"] = [[float(Ki[i, j]) for j in range(nt)] for i in range(nt)]


def _head(model: MechanismModel, what: str, rotors: str) -> dict[str, Any]:
    return {
        "mechanism": model.name,
        "what": what,
        "method": "force method: least complementary energy of the compliant members with the actuators locked "
                  "(Menabrea), displacements by Castigliano (docs/stiffness.md)",
        "sources": compliance_sources(model),
        "task_coordinates": [f"{n}_{u}" for n, u in zip(model.task_names, model.task_units)],
        "rotors": rotors,
        "mass_matrix": (f"rigid bodies, drives' rotors {rotors}"
                        + (" (their reflected inertia included)" if rotors == "moving" else "")
                        + ", elastic members massless; frequencies_rotors_held_Hz and "
                          "frequencies_rotors_moving_Hz give both conventions (docs/stiffness.md)"),
    }


def _mode_scene(model: MechanismModel, kin: MechanismKinematics, st: Stiffness, s: int) -> tuple[Array, Array, list[str]]:
    """Frames of the lowest modes at pose ``s`` (each one swing, 16 frames): times, joint points
    and one note per mode. The amplitude moves the largest coordinate by 5 % of the length
    scale (or 0.05 rad)."""
    frames, notes = [], []
    scale = np.array([model.length_scale if u == "m" else 1.0 for u in model.task_units])
    phase = np.sin(np.linspace(0.0, 2.0 * np.pi, 17)[:-1])
    for k in range(min(DRAWN_MODES, model.nt)):
        phi = st.modes[s, :, k]
        c = 0.05 / max(float(np.max(np.abs(phi) / scale)), 1e-300)
        x = kin.x[s] + np.outer(phase, c * phi)
        try:
            mk = solve_kinematics(model, x, q_start=kin.q[s])
        except PkmdynError:
            continue
        frames.append(mk.joint_point)
        notes.append(f"mode {k + 1}: {st.frequencies[s, k]:.6g} Hz")
    if not frames:
        return np.zeros(0), np.zeros((0, len(model.joint_names), 3)), notes
    jp = np.concatenate(frames)
    return np.arange(jp.shape[0], dtype=float), jp, notes


def _report(model: MechanismModel, kin: MechanismKinematics, st: Stiffness, s: int, summary: dict,
            text: str, images: list[str]) -> Report:

    t, jp, notes = _mode_scene(model, kin, st, s)
    scene = None
    if t.size:
        summ = model_summary(model)
        joints = [(j["name"], j["type"], j["body_a"], j["body_b"]) for j in summ["joints"]]
        scene = scene_from_joints(t, jp, joints)
    return Report(f"{model.name}: stiffness and natural frequencies", scene=scene, summary=summary,
                  parameters=text, images=images,
                  notes=[f"lowest modes at pose {s + 1}: " + "; ".join(notes)] if notes else [],
                  scene_note="Each of the lowest modes swings once, 16 frames each, in frequency order "
                             "(amplitude exaggerated: 5 % of the length scale).")


def _map_png(path: Path, model: MechanismModel, axes: list[tuple[int, Array]], ok: Array, kt: Array, f1: Array) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [f"{model.task_names[i]} [{model.task_units[i]}]" for i, _ in axes]
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.5))
    for a, vals, label in ((ax[0], kt, "min translational stiffness [N/m]"), (ax[1], f1, "lowest frequency [Hz]")):
        if len(axes) == 1:
            v = np.where(ok, vals, np.nan)
            a.plot(axes[0][1], v, "o-", ms=3)
            a.set_xlabel(names[0])
            a.set_ylabel(label)
        else:
            v = np.ma.masked_invalid(np.where(ok, vals, np.nan).reshape(len(axes[0][1]), len(axes[1][1])))
            m = a.pcolormesh(axes[0][1], axes[1][1], v.T, shading="auto")
            fig.colorbar(m, ax=a, label=label)
            a.set_xlabel(names[0])
            a.set_ylabel(names[1])
        a.set_title(label)
    fig.suptitle(f"{model.name}: stiffness over the grid (blank: unreachable or singular)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def run_stiffness(model: MechanismModel, out: Path, *, poses: Array | None = None, motion: Any = None,
                  grid: list[tuple[int, Array]] | None = None, description_text: str = "", rotors: str = "held"
                  ) -> tuple[dict[str, Any], Output]:
    """Write the stiffness job's files into the (temporary) folder ``out``; exactly one of
    ``poses (n, nt)``, ``motion`` (a task motion, its loads included) or ``grid`` (axes of
    :func:`parse_grid`); the modes with the drives' rotors ``rotors`` (``"held"``, ``"moving"``).
    Returns the document written to ``stiffness.json`` and the output (the files written, label ->
    path, and the report's content, :func:`pkmdyn.report.write_output`)."""
    files: dict[str, Path] = {}
    images: list[str] = []
    if grid is not None:
        x = grid_poses(model, grid)
        ok = reachable(model, x)
        keep = np.flatnonzero(ok)
        results: dict[int, tuple[MechanismKinematics, Stiffness]] = {}
        for s in keep:
            try:
                kin1 = solve_kinematics(model, x[s:s + 1])
                results[int(s)] = (kin1, stiffness(model, kin1, sample_offset=int(s), rotors=rotors))
            except StiffnessDataMissing:
                raise
            except PkmdynError:  # singular, or not reached alone from the reference pose
                ok[s] = False
        if not results:
            raise ParameterError("--grid: no pose of the grid is reachable and away from a singularity")
        kt = np.full(len(x), np.inf)
        kr = np.full(len(x), np.inf)
        f1 = np.zeros(len(x))
        for s, (_, st1) in results.items():
            kt[s], kr[s], f1[s] = st1.min_stiffness[0], st1.min_rot_stiffness[0], st1.frequencies[0, 0]
        cols: dict[str, Array] = {f"{n}_{u}": x[ok, i] for i, (n, u) in enumerate(zip(model.task_names, model.task_units))}
        cols.update(metric_columns(kt[ok], kr[ok], f1[ok]))
        files["grid"] = out / "grid.csv"
        write_csv(files["grid"], cols)
        files["map"] = out / "stiffness_map.png"
        _map_png(files["map"], model, grid, ok, kt, f1)
        images.append("map")
        worst = min(results, key=lambda s: (kt[s], f1[s]))
        doc = _head(model, "grid", rotors)
        doc["grid"] = {"axes": {f"{model.task_names[i]}_{model.task_units[i]}": [float(v) for v in vals]
                                for i, vals in grid},
                       "poses": int(len(x)), "evaluated": int(ok.sum()), "left_out": int((~ok).sum())}
        doc["poses"] = [dict(pose_document(model, results[s][1], 0), index=int(s)) for s in sorted(results)]
        doc["worst"] = dict(pose_document(model, results[worst][1], 0), index=int(worst))
        kin, st, s0 = results[worst][0], results[worst][1], 0
    elif motion is not None:
        kin_all = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
        over = reaction_route(model)
        n_all = len(kin_all)
        kt, kr, f1 = np.empty(n_all), np.empty(n_all), np.empty(n_all)
        dx = np.empty((n_all, model.nt))
        worst: tuple[float, int, int, Any, Any] | None = None
        for a in range(0, n_all, MOTION_CHUNK):  # the structure's matrices grow with the samples: in chunks
            b = min(a + MOTION_CHUNK, n_all)
            kin_c = kin_all.rows(a, b)
            named = {k: np.asarray(v)[a:b] for k, v in motion.loads.items()}
            st_c = stiffness(model, kin_c, sample_offset=a, rotors=rotors)
            reac = joint_reactions(model, kin_c, named=named, overconstrained=over, sample_offset=a)
            dx[a:b] = deflection(model, kin_c, reac, named=named, sample_offset=a)
            kt[a:b], kr[a:b], f1[a:b] = st_c.min_stiffness, st_c.min_rot_stiffness, st_c.frequencies[:, 0]
            k = int(np.argmin(np.where(np.isfinite(st_c.min_stiffness), st_c.min_stiffness, np.inf)))
            if worst is None or st_c.min_stiffness[k] < worst[0]:
                worst = (float(st_c.min_stiffness[k]), a + k, k, kin_c, st_c)
        cols = {"t_s": np.asarray(motion.t, dtype=float)}
        for i, (n, u) in enumerate(zip(model.task_names, model.task_units)):
            cols[f"{n}_{u}"] = kin_all.x[:, i]
        for i, (n, u) in enumerate(zip(model.task_names, model.task_units)):
            cols[f"{n}_deflection_{u}"] = dx[:, i]
        cols.update(metric_columns(kt, kr, f1))
        files["results"] = out / "results.csv"
        write_csv(files["results"], cols)
        assert worst is not None
        _, i0, s0, kin, st = worst
        doc = _head(model, "motion", rotors)
        doc["samples"] = int(n_all)
        doc["max_deflection"] = {f"{n}_{u}": float(np.abs(dx[:, i]).max())
                                 for i, (n, u) in enumerate(zip(model.task_names, model.task_units))}
        doc["lowest_frequency_Hz"] = float(f1.min())
        doc["worst"] = dict(pose_document(model, st, s0), index=i0, t_s=float(motion.t[i0]))
    else:
        x = np.atleast_2d(reference_task(model) if poses is None else poses)
        kin = solve_kinematics(model, x)
        st = stiffness(model, kin, rotors=rotors)
        doc = _head(model, "poses", rotors)
        doc["poses"] = [pose_document(model, st, s) for s in range(len(kin))]
        s0 = 0
    if model.na > model.nt:
        _internal_force(model, doc)
    files["stiffness"] = out / "stiffness.json"
    write_json(files["stiffness"], doc)
    summary = {k: v for k, v in doc.items() if k not in ("poses",)}
    if "worst" not in summary:
        summary["pose"] = doc["poses"][0]
    return doc, Output(files, report=_report(model, kin, st, s0, summary, description_text, images))


def job(machine: str, out_dir: Path, *, poses: tuple[str, ...] = (), motion_path: Path | None = None,
        default_motion: bool = False, grid: str | None = None, limit_items: tuple[str, ...] = (),
        announce: Callable[[Mapping[str, Path]], None] | None = None, rotors: str = "held") -> JobResult:
    """``pkmdyn stiffness``: ``machine`` at the task poses ``poses`` (``NAME=VALUE,...`` each; none:
    the reference pose), along the motion file ``motion_path`` or its ``default_motion``, or over
    ``grid`` (``NAME=LOW:HIGH:COUNT`` on one or two task coordinates), into ``out_dir``; the modes
    with the drives' rotors ``rotors`` (``"held"`` or ``"moving"``; both frequency sets in the file)."""
    if rotors not in ROTORS:
        raise ParameterError(f"--rotors {rotors!r}: one of {', '.join(ROTORS)}")
    limits = parse_limit_options(limit_items, LIMIT_KEYS)
    given = [o for o, v in (("--pose", poses), ("--motion", motion_path), ("--default-motion", default_motion),
                            ("--grid", grid)) if v]
    if len(given) > 1:
        raise ParameterError(f"{' and '.join(given)} exclude each other: give poses, a motion or a grid")
    p = prepare(machine, out_dir, {"--motion": motion_path}, limits)
    model = p.model
    kw: dict[str, Any] = {}
    eff = effective_limits(model, limits)
    if poses:
        kw["poses"] = np.stack([parse_pose(model, s, eff) for s in poses])
    elif motion_path is not None:
        kw["motion"] = read_task_motion(model, Path(motion_path).absolute())
    elif default_motion:
        kw["motion"] = one_cycle(model)
    elif grid is not None:
        kw["grid"] = parse_grid(model, grid, max_axes=2, max_points=MAX_GRID_POINTS, limits=eff)
    held: dict[str, Any] = {}

    def make(out: Path) -> Output:
        held["doc"], written = run_stiffness(model, out, description_text=p.text, rotors=rotors, **kw)
        return written

    files, output = write_output(out_dir, p.inputs, make, announce)
    doc = held["doc"]
    pose = doc.get("worst") or doc["poses"][0]
    k = pose["min_stiffness_N_m"]
    kr = pose["min_rot_stiffness_Nm_rad"]
    lines = (f"{'worst pose' if 'worst' in doc else 'pose'}: "
             + ", ".join(f"{n} = {v + 0.0:.6g}" for n, v in pose.get("task", {}).items()),
             f"  translational stiffness, worst direction: {'rigid' if k is None else f'{k:.6g} N/m'}; "
             f"rotational: {'rigid' if kr is None else f'{kr:.6g} N m/rad'}",
             f"  natural frequencies (rotors {rotors}): "
             + ", ".join(f"{f:.6g}" for f in pose.get("frequencies_Hz", [])) + " Hz")
    return JobResult(files, doc, lines, report=output.report)

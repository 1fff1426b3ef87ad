"""The whole PDM job behind ``pkmdyn pdm run``: parameters and motion in, files out.

Files written to the output folder (formats in docs/pdm4.md):
``results.csv`` (one row per sample: kinematics, actuator forces, the over-constrained
reactions), ``model.json`` (gravity, bodies, joints), ``bodies.npz`` (every body's motion and
every joint's reaction wrench), ``summary.json``, ``mobility.json`` (Eq. 1 and the screw
analysis), ``geometry.json`` (the joint positions the layout derives), ``workspace.csv`` and
``workspace_xy.csv`` (boundary search), and unless plots are off ``limbs.png``,
``forces.png``, ``overconstraints.png``, ``workspace.png`` and ``schematic.png``. Everything is
computed before the output folder is touched, and the folder is written whole through
:func:`pkmdyn.report.write_output`.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...analysis.mobility import analyse
from ...errors import PkmdynError
from ...io import check_output_dir, open_table_writer, write_json
from ...multibody import load_mechanism, solve_kinematics
from ...multibody.dynamics.newton_euler import joint_reactions
from ...params_util import check_limit, parse_limit_options
from ...report import JobResult, Output, write_output
from ...profiles.pdm_motion import PdmMotion, cycloidal_motion, read_pdm_motion
from . import paper
from .description import pdm_description
from .kinematics import inverse_position, mechanism_joints
from .paper import BODY_NAMES, JOINTS, LIMB_LABELS, REDUNDANT_LABELS
from .params import LIMIT_KEYS, PdmModel, TrajectorySettings, load_params
from .plots import plot_forces, plot_limbs, plot_overconstraints, plot_workspace
from .report import run_report
from .schematic import draw_schematic
from .workspace import reachable_workspace, write_projection_csv, write_workspace_csv

__all__ = ["run_pdm", "compute", "EngineResults", "mobility_summary", "geometry_summary", "model_summary", "trajectory_with",
           "CHUNK"]

Array = NDArray[np.float64]
#: samples per block of the kinematics loop (one progress-bar step per block)
CHUNK = 2000
def model_summary(model: PdmModel) -> dict[str, Any]:
    """``model.json``: gravity, every body (mass, inertia about its centre of mass in its own
    frame) and every joint (type and the two bodies; the reaction is what ``body_a`` exerts
    on ``body_b``), in the order of ``bodies.npz``."""
    return {
        "source": model.source,
        "gravity_m_s2": model.gravity,
        "body_frames": "origin at the centre of mass; x along the link (docs/pdm4.md, body frames)",
        "bodies": [{"name": name, "mass_kg": float(model.mass[b]), "inertia_kgm2": model.inertia[b]}
                   for b, name in enumerate(BODY_NAMES)],
        "joints": [{"name": name, "type": typ, "body_a": a, "body_b": b} for name, typ, a, b in JOINTS],
        "material": {"youngs_modulus_Pa": model.youngs_modulus_Pa, "poisson_ratio": model.poisson_ratio,
                     "section_outer_m": {n: float(model.section_outer[b]) for b, n in enumerate(BODY_NAMES)},
                     "section_inner_m": {n: float(model.section_inner[b]) for b, n in enumerate(BODY_NAMES)}},
    }


def trajectory_with(model: PdmModel, stroke_x_m: float | None = None, stroke_y_m: float | None = None,
                    stroke_alpha_deg: float | None = None, stroke_gamma_deg: float | None = None,
                    period_s: float | None = None, peak_y_accel_m_s2: float | None = None) -> TrajectorySettings:
    """The Eq. 84 settings of ``model`` with the given amplitudes/period replaced.

    ``peak_y_accel_m_s2`` sets the period instead: the cycloid peaks at
    ``|y_ddot|max = 2 pi |S_y| / T^2``, so ``T = sqrt(2 pi |S_y| / a)``. Raises
    :class:`~pkmdyn.errors.PkmdynError` naming the option for a non-finite or out-of-range value.
    """
    tr = model.trajectory
    strokes = list(tr.strokes)
    for k, (opt, v, scale, lim) in enumerate((("--stroke-x-m", stroke_x_m, 1.0, 10.0),
                                              ("--stroke-y-m", stroke_y_m, 1.0, 10.0),
                                              ("--stroke-alpha-deg", stroke_alpha_deg, math.pi / 180, 360.0),
                                              ("--stroke-gamma-deg", stroke_gamma_deg, math.pi / 180, 360.0))):
        if v is None:
            continue
        if not math.isfinite(v) or abs(v) > lim:
            raise PkmdynError(f"{opt}: must be a finite number within +-{lim:g}, got {v!r}")
        strokes[k] = v * scale
    period = tr.period_s
    if period_s is not None and peak_y_accel_m_s2 is not None:
        raise PkmdynError("--period-s and --peak-y-accel: give one of them, not both")
    if period_s is not None:
        if not math.isfinite(period_s) or not 1e-3 <= period_s <= 1e6:
            raise PkmdynError(f"--period-s: must be within 0.001 .. 1e6 s, got {period_s!r}")
        period = period_s
    if peak_y_accel_m_s2 is not None:
        if not math.isfinite(peak_y_accel_m_s2) or not 0 < peak_y_accel_m_s2 <= 1e3:
            raise PkmdynError(f"--peak-y-accel: must be within 0 .. 1000 m/s^2 (exclusive of 0), got {peak_y_accel_m_s2!r}")
        if strokes[1] == 0:
            raise PkmdynError("--peak-y-accel: the y stroke S_y is zero, so no period gives that acceleration")
        period = math.sqrt(2.0 * math.pi * abs(strokes[1]) / peak_y_accel_m_s2)
        if not 1e-3 <= period <= 1e6:
            raise PkmdynError(f"--peak-y-accel: implies a period of {period:.6g} s, outside 0.001 .. 1e6 s")
    return TrajectorySettings(strokes=tuple(strokes), period_s=period, samples=tr.samples)  # type: ignore[arg-type]


def mobility_summary(model: PdmModel, q: Array) -> dict[str, Any]:
    """``mobility.json`` content: joint counts, Eq. 1 and the screw analysis at pose ``q``."""
    rep = analyse(mechanism_joints(model, q), "ground", "platform")
    return {
        "joint_counts": rep.joint_counts,
        "moving_links": rep.moving_links,
        "independent_loops": rep.loops_count,
        "dof": rep.output_dof,
        "mobility_screw": rep.mobility,
        "t": rep.eq1_overconstraints,
        "t_formula": "t = 3S + 4U + 5R + 5P + A - 6n (Eq. 1), A = dof",
        "t_screw": rep.overconstraints,
        "kutzbach_mobility": rep.kutzbach,
        "pose_evaluated": {"x_m": q[0], "y_m": q[1], "alpha_rad": q[2], "gamma_rad": q[3]},
        "wrench_order": "fx, fy, fz, mx, my, mz in the base frame, moments about its origin",
        "overconstrained_subchains": [
            {"joints": list(lp.joints), "twist_rank": lp.twist_rank, "overconstraints": lp.overconstraints,
             "directions": list(lp.directions), "constraint_wrenches": lp.wrenches.tolist()}
            for lp in rep.loops if lp.overconstraints
        ],
        "other_loops": [{"joints": list(lp.joints), "twist_rank": lp.twist_rank, "overconstraints": 0}
                        for lp in rep.loops if not lp.overconstraints],
    }


def geometry_summary(model: PdmModel) -> dict[str, Any]:
    """``geometry.json`` content: the derived joint positions [m] of the layout (base frame A,
    U joints and P in the platform frame relative to C) and the limb lengths at home."""
    return {
        "source": model.source,
        "R1_m": {"R11": model.R1[0], "R12": model.R1[1]},
        "R4_m": {"R41": model.R4[0], "R42": model.R4[1]},
        "S_m": {"S23": model.S[0], "S24": model.S[1]},
        "U_platform_m": {"U23": model.U_local[0], "U24": model.U_local[1]},
        "R3_output_link_m": {"R31": model.R3_local[0], "R32": model.R3_local[1]},
        "P_platform_m": model.P_local,
        "U1_axis_platform": model.U1_local,
        "home_lengths_m": {"l11": model.home_lengths[0], "l12": model.home_lengths[1],
                           "l23": model.home_lengths[2], "l24": model.home_lengths[3]},
        "assembly_branch": list(model.branch),
    }


@dataclasses.dataclass(frozen=True)
class EngineResults:
    """A motion of the PDM through the generic engine: the ``results.csv`` columns ``cols``, the
    ``bodies.npz`` arrays ``npz`` and the limbs' Jacobian ``limb_jacobian`` (n, 4, 4)
    ``dl/dq`` (rows l11, l12, l23, l24; columns x, y, alpha, gamma) [m/m, m/rad]."""

    cols: dict[str, Array]
    npz: dict[str, Array]
    limb_jacobian: Array


def compute(model: PdmModel, motion: PdmMotion, progress: bool | None = None) -> EngineResults:
    """``results.csv`` columns, ``bodies.npz`` arrays and the limbs' Jacobian, in blocks of
    ``CHUNK`` samples (``progress``: a bar per block, None: on a terminal when there is more than
    one block), through the generic engine: the kinematics of the PDM's description
    (:func:`pkmdyn.multibody.solve_kinematics`, each block warm-started from the last one) and
    its joint reactions, unique by the links' compliance
    (:func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`), in the paper's names (:mod:`.paper`).
    The paper's geometry checks each block first (Eq. 2-9: a six-bar loop that cannot close, a
    limb beyond its stroke), so that a message names the limb."""

    m = load_mechanism(pdm_description(model))
    limbs = [m.actuator_names.index(n) for n in paper.LIMBS]
    blocks, arrays, jac = [], [], []
    starts = range(0, len(motion), CHUNK)
    q_start = None
    disable = (None if len(starts) > 1 else True) if progress is None else not progress
    for s in tqdm(starts, desc="pdm dynamics", unit="block", disable=disable):
        part = motion.slice(s, s + CHUNK)
        inverse_position(model, part.q, part.t)
        kin = solve_kinematics(m, part.q, part.qd, part.qdd, part.t, q_start=q_start, sample_offset=s)
        q_start = kin.q[-1]
        reac = joint_reactions(m, kin, sample_offset=s)
        wrenches = paper.paper_wrenches(m, kin, reac)
        blocks.append({**paper.results_columns(m, kin, model.home_lengths),
                       **paper.dynamics_columns(m, kin, reac, wrenches, model.U1_local)})
        arrays.append(paper.bodies_arrays(m, kin, wrenches))
        jac.append(kin.J_ax[:, limbs])
    cols = {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}
    npz = {k: np.concatenate([b[k] for b in arrays]) for k in arrays[0]}
    npz["t"] = motion.t
    for k, v in npz.items():
        if not np.all(np.isfinite(v)):
            raise PkmdynError(f"bodies.npz: {k} has a non-finite value; refusing to write it")
    return EngineResults(cols, npz, np.concatenate(jac))


def _check_plausible(model: PdmModel, cols: dict[str, Array]) -> None:
    """Limb speeds, accelerations and actuator forces of every sample against ``[limits]`` (a
    motion squeezed into too short a time, or a unit error, is caught here)."""
    t = cols["t_s"]
    for fmt, key, what, unit in (("ld{}_m_s", "max_limb_speed_m_s", "speed", "m/s"),
                                 ("ldd{}_m_s2", "max_limb_acceleration_m_s2", "acceleration", "m/s^2"),
                                 ("f{}_N", "max_actuator_force_N", "actuator force", "N")):
        a = np.abs(np.stack([cols[fmt.format(k)] for k in range(1, 5)], axis=-1))
        r, k = np.unravel_index(int(np.argmax(a)), a.shape)
        check_limit(float(a[r, k]), getattr(model, key),
                    f"t = {t[r]:.6g} s (sample {r + 1}): {LIMB_LABELS[k]} {what}", key, unit)


def _summary(cols: dict[str, Array], n: int, mob: dict[str, Any]) -> dict[str, Any]:
    def peak(name: str) -> float:
        return float(np.abs(cols[name]).max())

    return {
        "samples": n,
        "max_abs_actuator_force_N": {f"f{k}_N": peak(f"f{k}_N") for k in range(1, 5)},
        "max_abs_overconstrained_reaction": {label: peak(label) for label in REDUNDANT_LABELS},
        "max_abs_u_joint_torque_Nm": {k: peak(k) for k in ("U23_torque_Nm", "U24_torque_Nm")},
        "max_loop_residual_m": float(cols["loop_residual_m"].max()),
        "t": mob["t"],
    }


def run_pdm(params_path: str | Path | None, motion_path: str | Path | None, out_dir: str | Path,
            plots: bool = True, trajectory: dict[str, float | None] | None = None,
            report: Callable[[dict[str, Path]], None] | None = None,
            limits: tuple[str, ...] | dict[str, Any] | None = None, html_report: bool = True) -> JobResult:
    """Run the PDM kinematics and dynamics and write every result file into ``out_dir``.

    ``params_path``: TOML parameters (None: built-in defaults); ``motion_path``: motion CSV
    (None: the Eq. 84 cycloidal motion of the ``[trajectory]`` section, with the overrides of
    ``trajectory``, the keyword arguments of :func:`trajectory_with`); ``html_report``: also write
    ``report.html`` (:mod:`pkmdyn.report`). Returns the result: the files (label -> path), the summary
    ``summary.json`` holds and the report's content. User errors raise
    :class:`~pkmdyn.errors.PkmdynError` subclasses naming the file (full path), key, row,
    sample time or limb; they are raised before ``out_dir`` is touched (which must pass the output
    rule, :func:`pkmdyn.io.check_output_dir`, checked first). ``report`` is called with the files'
    final paths before they move into place. ``limits`` overrides ``[limits]`` of the parameter
    file (``{key: value}`` or ``("key=value", ...)``, the keys of
    :data:`~pkmdyn.machines.pdm4.params.LIMIT_KEYS`): the motion's duration, limb speeds and
    accelerations and the actuator forces of every sample are checked against them.
    """
    inputs = {"--params": params_path, "--motion": motion_path}
    check_output_dir(out_dir, inputs)
    model = load_params(params_path)
    if limits:
        items = [f"{k}={v}" for k, v in limits.items()] if isinstance(limits, dict) else list(limits)
        model = dataclasses.replace(model, **parse_limit_options(items, LIMIT_KEYS))
    overrides = {k: v for k, v in (trajectory or {}).items() if v is not None}
    if motion_path is None:
        tr = trajectory_with(model, **overrides) if overrides else model.trajectory
        motion = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
        motion_source = f"Eq. 84 cycloidal motion, strokes {tr.strokes}, period {tr.period_s:g} s"
    else:
        if overrides:
            raise PkmdynError("--motion: the trajectory options (--stroke-*, --period-s, --peak-y-accel) "
                              "apply to the built-in Eq. 84 motion only")
        motion = read_pdm_motion(Path(motion_path).absolute(), max_rows=model.max_samples)
        motion_source = str(motion_path)
    source = "motion" if motion_path is None else str(Path(motion_path).absolute())
    check_limit(float(motion.t[-1] - motion.t[0]), model.max_duration_s, f"{source}: duration", "max_duration_s", "s")
    res = compute(model, motion)
    cols, npz = res.cols, res.npz
    _check_plausible(model, cols)
    mob = mobility_summary(model, motion.q[0])
    ws = reachable_workspace(model)

    def make(out: Path) -> Output:  # only now: a user error above leaves nothing behind
        files = _write(model, out, cols, npz, mob, ws, plots)
        images = [k for k, p in files.items() if p.suffix == ".png"]
        rep = run_report(model, params_path, motion_source, cols, npz, images) if html_report else None
        return Output(files, _summary(cols, len(motion), mob), rep)

    final, output = write_output(out_dir, inputs, make, report)
    return JobResult(final, output.summary or {}, report=output.report)


def _write(model: PdmModel, out: Path, cols: dict[str, Array], npz: dict[str, Array], mob: dict[str, Any],
           ws: Any, plots: bool) -> dict[str, Path]:
    """Write every file of a run into the (temporary) folder ``out``."""
    files: dict[str, Path] = {"results": out / "results.csv"}
    with open_table_writer(files["results"], "csv") as table:  # the shortest exact form of each number
        table.write(cols)
    files["mobility"] = out / "mobility.json"
    write_json(files["mobility"], mob)
    files["geometry"] = out / "geometry.json"
    write_json(files["geometry"], geometry_summary(model))
    files["workspace"] = out / "workspace.csv"
    write_workspace_csv(files["workspace"], ws)
    files["workspace_xy"] = out / "workspace_xy.csv"
    write_projection_csv(files["workspace_xy"], ws)
    files["model"] = out / "model.json"
    write_json(files["model"], model_summary(model))
    files["bodies"] = out / "bodies.npz"
    try:
        np.savez_compressed(files["bodies"], body_names=np.array(BODY_NAMES),
                            joint_names=np.array([j[0] for j in JOINTS]), **npz)
    except OSError as exc:
        raise PkmdynError(f"{files['bodies']}: cannot write file ({exc.strerror or type(exc).__name__})") from None
    if plots:

        ext = np.stack([cols[f"s{k}_m"] for k in range(1, 5)], axis=-1)
        ld = np.stack([cols[f"ld{k}_m_s"] for k in range(1, 5)], axis=-1)
        ldd = np.stack([cols[f"ldd{k}_m_s2"] for k in range(1, 5)], axis=-1)
        files["limbs_plot"] = plot_limbs(cols["t_s"], ext, ld, ldd, out / "limbs.png")
        files["workspace_plot"] = plot_workspace(ws, out / "workspace.png")
        files["schematic"] = draw_schematic(model, out / "schematic.png")
        force = np.stack([cols[f"f{k}_N"] for k in range(1, 5)], axis=-1)
        files["forces_plot"] = plot_forces(cols["t_s"], force, out / "forces.png")
        red = np.stack([cols[label] for label in REDUNDANT_LABELS], axis=-1)
        files["overconstraints_plot"] = plot_overconstraints(cols["t_s"], red, out / "overconstraints.png")
    return files

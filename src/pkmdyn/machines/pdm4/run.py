"""The whole PDM job behind ``pkmdyn pdm run``: parameters and motion in, files out.

Files written to the output folder (formats in docs/pdm4.md):
``results.csv`` (one row per sample), ``mobility.json`` (Eq. 1 and the screw analysis),
``geometry.json`` (the joint positions the layout derives), ``workspace.csv`` and
``workspace_xy.csv`` (boundary search), and unless plots are off ``limbs.png``,
``workspace.png`` and ``schematic.png``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...analysis.mobility import analyse
from ...io import make_out_dir, write_csv, write_json
from ...profiles.pdm_motion import PdmMotion, cycloidal_motion, read_pdm_motion
from .kinematics import BODY_NAMES, PdmKinematics, inverse_kinematics, mechanism_joints
from .params import PdmModel, load_params
from .workspace import reachable_workspace, write_projection_csv, write_workspace_csv

__all__ = ["run_pdm", "results_columns", "mobility_summary", "geometry_summary", "CHUNK"]

Array = NDArray[np.float64]
#: samples per block of the kinematics loop (one progress-bar step per block)
CHUNK = 2000
_XYZ = "xyz"
_EULER = ("alpha", "beta", "gamma")


def _vec(cols: dict[str, Array], prefix: str, unit: str, v: Array) -> None:
    for c in range(3):
        cols[f"{prefix}{_XYZ[c]}_{unit}"] = v[:, c]


def results_columns(model: PdmModel, kin: PdmKinematics) -> dict[str, Array]:
    """The columns of ``results.csv`` for one block of samples (names in docs/pdm4.md)."""
    cols: dict[str, Array] = {"t_s": kin.t}
    for k, name in enumerate(("x_m", "y_m", "alpha_rad", "gamma_rad")):
        cols[name] = kin.q[:, k]
    for k in range(4):
        cols[f"l{k + 1}_m"] = kin.pos.l[:, k]
        cols[f"ld{k + 1}_m_s"] = kin.ld[:, k]
        cols[f"ldd{k + 1}_m_s2"] = kin.ldd[:, k]
    for k, name in enumerate(("xd_m_s", "yd_m_s", "alphad_rad_s", "gammad_rad_s")):
        cols[name] = kin.qd[:, k]
    for k, name in enumerate(("xdd_m_s2", "ydd_m_s2", "alphadd_rad_s2", "gammadd_rad_s2")):
        cols[name] = kin.qdd[:, k]
    cols["z_m"] = kin.pos.P[:, 2]
    for k in range(4):
        cols[f"s{k + 1}_m"] = kin.pos.l[:, k] - model.home_lengths[k]
    for i in range(2):
        for sym, v, vd, vdd in ((f"crank{i + 1}_theta", kin.pos.theta1, kin.theta1d, kin.theta1dd),
                                (f"coupler{i + 1}_theta", kin.pos.theta2, kin.theta2d, kin.theta2dd),
                                (f"rpr{i + 1}_phi", kin.rpr_angle, kin.rpr_angle_d, kin.rpr_angle_dd)):
            cols[f"{sym}_rad"] = v[:, i]
            cols[f"{sym}d_rad_s"] = vd[:, i]
            cols[f"{sym}dd_rad_s2"] = vdd[:, i]
    for j in range(2):
        for e in range(3):
            base = f"spu{j + 3}_{_EULER[e]}"
            cols[f"{base}_rad"] = kin.euler[:, j, e]
            cols[f"{base}d_rad_s"] = kin.euler_d[:, j, e]
            cols[f"{base}dd_rad_s2"] = kin.euler_dd[:, j, e]
    for name in BODY_NAMES:
        b = kin.body(name)
        _vec(cols, f"{name}_p", "m", b.p)
        _vec(cols, f"{name}_v", "m_s", b.v)
        _vec(cols, f"{name}_a", "m_s2", b.a)
        _vec(cols, f"{name}_w", "rad_s", b.w)
        _vec(cols, f"{name}_wd", "rad_s2", b.wd)
    cols["loop_residual_m"] = kin.residual
    return cols


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


def _kinematics_columns(model: PdmModel, motion: PdmMotion) -> dict[str, Array]:
    """``results.csv`` columns, computed in blocks of ``CHUNK`` samples (progress bar on a
    terminal when there is more than one block)."""
    blocks = []
    starts = range(0, len(motion), CHUNK)
    for s in tqdm(starts, desc="pdm kinematics", unit="block", disable=None if len(starts) > 1 else True):
        blocks.append(results_columns(model, inverse_kinematics(model, motion.slice(s, s + CHUNK))))
    return {k: np.concatenate([b[k] for b in blocks]) for k in blocks[0]}


def run_pdm(params_path: str | Path | None, motion_path: str | Path | None, out_dir: str | Path,
            plots: bool = True) -> dict[str, Any]:
    """Run the PDM kinematics and write every result file into ``out_dir``.

    ``params_path``: TOML parameters (None: built-in defaults); ``motion_path``: motion CSV
    (None: the Eq. 84 cycloidal motion of the ``[trajectory]`` section). Returns a summary
    ``{"files": {label: path}, "samples": n, "max_loop_residual_m": ..., "t": ...}``.
    User errors raise :class:`~pkmdyn.errors.PkmdynError` subclasses naming the key, row,
    sample time or limb.
    """
    model = load_params(params_path)
    if motion_path is None:
        tr = model.trajectory
        motion = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    else:
        motion = read_pdm_motion(motion_path)
    cols = _kinematics_columns(model, motion)
    mob = mobility_summary(model, motion.q[0])
    ws = reachable_workspace(model)
    out = make_out_dir(out_dir)  # only now: a user error above leaves nothing behind
    files: dict[str, Path] = {"results": out / "results.csv"}
    write_csv(files["results"], cols)
    files["mobility"] = out / "mobility.json"
    write_json(files["mobility"], mob)
    files["geometry"] = out / "geometry.json"
    write_json(files["geometry"], geometry_summary(model))
    files["workspace"] = out / "workspace.csv"
    write_workspace_csv(files["workspace"], ws)
    files["workspace_xy"] = out / "workspace_xy.csv"
    write_projection_csv(files["workspace_xy"], ws)
    if plots:
        from .plots import plot_limbs, plot_workspace
        from .schematic import draw_schematic

        ext = np.stack([cols[f"s{k}_m"] for k in range(1, 5)], axis=-1)
        ld = np.stack([cols[f"ld{k}_m_s"] for k in range(1, 5)], axis=-1)
        ldd = np.stack([cols[f"ldd{k}_m_s2"] for k in range(1, 5)], axis=-1)
        files["limbs_plot"] = plot_limbs(cols["t_s"], ext, ld, ldd, out / "limbs.png")
        files["workspace_plot"] = plot_workspace(ws, out / "workspace.png")
        files["schematic"] = draw_schematic(model, out / "schematic.png")
    return {
        "files": files,
        "samples": len(motion),
        "max_loop_residual_m": float(cols["loop_residual_m"].max()),
        "t": mob["t"],
    }

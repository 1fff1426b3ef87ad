"""The hip simulator's main job: parameters + motion -> kinematics -> dynamics -> files.

Data flows one way: file -> validated model -> motion -> kinematics -> dynamics -> results ->
files and plots. Samples are processed in chunks so that memory stays bounded on long runs.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray
from tqdm import tqdm

from ...io import make_out_dir, write_csv, write_json
from ...profiles.iso14242 import IsoCycle, iso14242_motion
from ...profiles.orientation import OrientationMotion, read_motion_csv
from ...spatial import euler_kinematics
from . import plots
from .dynamics import PARTS, HipTorques, inverse_dynamics
from .kinematics import DEFAULT_SINGULARITY_THRESHOLD, platform_kinematics
from .params import HipModel, load_params

__all__ = ["HipResults", "torques_batched", "simulate", "results_columns", "summary", "run_hip", "DEFAULT_CHUNK"]

Array = NDArray[np.float64]

DEFAULT_CHUNK = 4096  # samples per block: keeps the working set of a block in cache


def torques_batched(
    model: HipModel, t: Array, R: Array, omega: Array, omega_dot: Array, load: Array, chunk: int = DEFAULT_CHUNK
) -> Array:
    """Motor torques ``(n, 3)`` [N m] from the platform motion, in blocks of ``chunk`` samples.

    The lean path for controllers and sweeps: no conditioning check, only the total torque.
    """
    out = np.empty((t.shape[0], 3))
    for s in range(0, t.shape[0], chunk):
        sl = slice(s, s + chunk)
        kin = platform_kinematics(model, t[sl], R[sl], omega[sl], omega_dot[sl], check_conditioning=False)
        out[sl] = inverse_dynamics(model, kin, load[sl]).tau
    return out


@dataclass(frozen=True)
class HipResults:
    """Everything a run writes, per sample; shapes as in :class:`HipKinematics` and :class:`HipTorques`."""

    t: Array
    L: Array  #: (n, 2, 3) [m]
    Ld: Array  #: (n, 2, 3) [m/s]
    Ldd: Array  #: (n, 2, 3) [m/s^2]
    det_Ja: Array  #: (n, 2)
    det_Jb: Array  #: (n, 2) [m^3]
    cond_J: Array  #: (n,)
    torques: HipTorques


def simulate(
    model: HipModel,
    motion: OrientationMotion,
    chunk: int = 20_000,
    progress: bool = False,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
) -> HipResults:
    """Kinematics and dynamics along ``motion``, ``chunk`` samples at a time."""
    n = len(motion)
    pieces: list[tuple] = []
    starts = range(0, n, chunk)
    bar = tqdm(starts, desc="hip: kinematics + dynamics", unit="chunk", disable=not progress or None, leave=False)
    for s in bar:
        sl = slice(s, min(s + chunk, n))
        R, w, wd = euler_kinematics(
            model.geometry.euler_sequence, motion.angles[sl], motion.rates[sl], motion.accels[sl]
        )
        kin = platform_kinematics(model, motion.t[sl], R, w, wd, singularity_threshold)
        tq = inverse_dynamics(model, kin, motion.load[sl])
        pieces.append((kin.L, kin.Ld, kin.Ldd, kin.det_Ja, kin.det_Jb, kin.cond_J, tq))
    cat = lambda k: np.concatenate([p[k] for p in pieces])  # noqa: E731
    torques = HipTorques(**{f: np.concatenate([getattr(p[6], f) for p in pieces]) for f in HipTorques.__dataclass_fields__})
    n_pl = model.geometry.h.shape[0]
    return HipResults(
        t=motion.t,
        L=cat(0),
        Ld=cat(1),
        Ldd=cat(2),
        det_Ja=np.repeat(cat(3)[:, None], n_pl, axis=1),
        det_Jb=np.repeat(cat(4)[:, None], n_pl, axis=1),
        cond_J=cat(5),
        torques=torques,
    )


def results_columns(res: HipResults) -> dict[str, Array]:
    """The spec's results-file columns (``docs/file_formats.md``), in order."""
    cols: dict[str, Array] = {"t_s": res.t}
    for j in range(res.L.shape[1]):
        for i in range(3):
            cols[f"L{j + 1}{i + 1}_m"] = res.L[:, j, i]
            cols[f"Ld{j + 1}{i + 1}_m_s"] = res.Ld[:, j, i]
            cols[f"Ldd{j + 1}{i + 1}_m_s2"] = res.Ldd[:, j, i]
    for j in range(res.L.shape[1]):
        cols[f"detJa{j + 1}"] = res.det_Ja[:, j]
        cols[f"detJb{j + 1}"] = res.det_Jb[:, j]
    tq = res.torques
    for i in range(3):
        cols[f"tau{i + 1}_Nm"] = tq.tau[:, i]
        for part in PARTS:
            cols[f"tau{i + 1}_{part}_Nm"] = getattr(tq, part)[:, i]
    cols["condJ"] = res.cond_J
    return cols


def summary(res: HipResults) -> dict:
    """Per-slider and per-motor maxima (JSON-ready, unit-suffixed keys)."""
    sliders = {}
    for j in range(res.L.shape[1]):
        for i in range(3):
            sliders[f"S{j + 1}{i + 1}"] = {
                "max_position_m": float(res.L[:, j, i].max()),
                "min_position_m": float(res.L[:, j, i].min()),
                "max_abs_velocity_m_s": float(np.abs(res.Ld[:, j, i]).max()),
                "max_abs_acceleration_m_s2": float(np.abs(res.Ldd[:, j, i]).max()),
            }
    motors = {}
    tq = res.torques
    for i in range(3):
        m = {"max_abs_tau_Nm": float(np.abs(tq.tau[:, i]).max())}
        for part in PARTS:
            m[f"max_abs_tau_{part}_Nm"] = float(np.abs(getattr(tq, part)[:, i]).max())
        m["max_abs_tau_hip_friction_Nm"] = float(np.abs(tq.hip_friction[:, i]).max())
        motors[f"motor{i + 1}"] = m
    return {
        "samples": int(res.t.shape[0]),
        "duration_s": float(res.t[-1] - res.t[0]),
        "sliders": sliders,
        "motors": motors,
        "min_abs_detJa": float(np.abs(res.det_Ja).min()),
        "min_abs_detJb_m3": float(np.abs(res.det_Jb).min()),
        "max_condJ": float(res.cond_J.max()),
        "max_abs_power_W": float(np.abs(tq.power).max()),
    }


def run_hip(
    out_dir: str | Path,
    params_path: str | Path | None = None,
    motion_path: str | Path | None = None,
    cycles: float = 1.0,
    samples_per_cycle: int = 1000,
    make_plots: bool = True,
    progress: bool = False,
    singularity_threshold: float = DEFAULT_SINGULARITY_THRESHOLD,
) -> tuple[dict[str, Path], list[str]]:
    """Run the whole job; returns the files written and the warnings raised on the way.

    Nothing is written until every input has been read and every sample computed, so a
    user error leaves ``out_dir`` untouched.
    """
    model = load_params(params_path)
    if motion_path is None:
        motion = iso14242_motion(cycles, samples_per_cycle, IsoCycle())
    else:
        motion = read_motion_csv(motion_path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = simulate(model, motion, progress=progress, singularity_threshold=singularity_threshold)
    messages = [str(w.message) for w in caught]
    out = make_out_dir(out_dir)
    files = {"results": out / "results.csv", "summary": out / "summary.json"}
    write_csv(files["results"], results_columns(res))
    summ = summary(res)
    summ["parameters"] = str(params_path) if params_path else "built-in (paper Tables 1-2)"
    summ["motion"] = str(motion_path) if motion_path else f"built-in ISO 14242-1 model, {cycles:g} cycle(s)"
    summ["warnings"] = messages
    write_json(files["summary"], summ)
    if make_plots:
        files["motion_plot"] = plots.plot_motion_and_load(motion, out / "motion_load.png")
        files["slider_plot"] = plots.plot_slider_motion(res.t, res.L, res.Ld, res.Ldd, out / "slider_motion.png")
        tq = res.torques
        parts = {"(a) platform": tq.platform, "(b) lever": tq.lever, "(c) slider": tq.slider, "(d) screw": tq.screw}
        files["torque_parts_plot"] = plots.plot_torque_parts(res.t, parts, out / "torque_parts.png")
        files["torque_plot"] = plots.plot_torques(res.t, tq.tau, out / "torques.png")
        files["friction_plot"] = plots.plot_friction_vs_load(res.t, motion.load, tq.friction, out / "friction_vs_load.png")
    return files, messages

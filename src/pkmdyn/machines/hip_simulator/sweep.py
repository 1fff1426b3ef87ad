"""The hip simulator's sweep adapter: what ``pkmdyn sweep --machine hip`` evaluates per design.

The functions of :class:`pkmdyn.sweep_protocol.SweepAdapter`. Every design performs the same
platform motion (the built-in ISO 14242-1 cycle, 500 samples by default, or a motion file),
so its rotations, angular velocities and accelerations are computed once (:func:`prepare`)
and every design runs the batched closed forms of this machine over all samples at once:
the kinematics of Eq. (1)-(6) and the inverse dynamics with friction of Eq. (7)-(16).
Metrics, formulas and units: ``docs/sweep.md``; every one can be recomputed from the public
:func:`~pkmdyn.machines.hip_simulator.inverse_kinematics` and
:func:`~pkmdyn.machines.hip_simulator.inverse_dynamics`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from ...errors import LimitError, MotionError, PkmdynError, SingularityError, UnreachablePoseError
from ...params_util import Section, check_limit, read_toml, validate
from .iso_fit import iso_cycle_preset
from ...profiles.iso14242 import iso14242_block, iso14242_samples, iso14242_times
from ...profiles.orientation import OrientationMotion, read_motion_csv
from ...spatial import euler_kinematics, euler_to_matrix
from ...sweep_protocol import DesignOutcome, MetricInfo, time_integral, time_mean
from .dynamics import inverse_dynamics
from .kinematics import _platform_kinematics
from .params import HipModel, default_params_dict, model_from_dict
from .run import _check_motion_limits

__all__ = ["NAME", "HipSweepContext", "base_description", "check_description", "metrics", "prepare", "evaluate",
           "evaluate_one", "zero_pose_lever_directions", "WORKSPACE_SEED"]

NAME = "hip"
Array = NDArray[np.float64]
#: seed of the scrambled Sobol orientations of the orientation workspace (fixed: the same
#: orientations for every design and every sweep with the same settings)
WORKSPACE_SEED = 14242


class _Motion(Section):
    file: str | None = None
    cycles: Annotated[float, Field(gt=0.0, le=1e6)] = 1.0
    samples_per_cycle: Annotated[int, Field(ge=2, le=10_000_000)] = 500
    motion_model: Literal["default", "paper-fit", "paper-fit-zxy"] = "default"
    singularity_threshold: Annotated[float, Field(ge=0.0, le=1.0)] = 1e-3
    workspace_max_angle_deg: Annotated[float, Field(gt=0.0, le=90.0)] = 30.0
    workspace_points: Annotated[int, Field(ge=0, le=1_000_000)] = 256


@dataclass(frozen=True)
class HipSweepContext:
    """The design-independent part of the evaluation.

    ``t (n,)`` [s]; ``R (n, 3, 3)``, ``omega, omega_dot (n, 3)`` [rad/s, rad/s^2] the platform
    motion in the base frame; ``load (n,)`` [N]; ``cycles``: cycles the motion spans (1 for a
    motion file); ``threshold``: the least admissible 1/cond(J); ``R_ws (m, 3, 3)``: the
    orientations of the orientation workspace (``m = 0``: not computed).
    """

    t: Array
    R: Array
    omega: Array
    omega_dot: Array
    load: Array
    cycles: float
    threshold: float
    R_ws: Array
    workspace_max_angle_deg: float


_METRICS = (
    MetricInfo("gci", "-", "(1/T) int 1/cond(J) dt along the motion (trapezoid rule); J = J_a^-1 J_b, Eq. (3)"),
    MetricInfo("min_inverse_condition", "-", "min over samples of 1/cond(J) = sigma_min / sigma_max"),
    MetricInfo("orientation_workspace_fraction", "-",
               "share of m fixed Sobol orientations, Euler angles in +-workspace_max_angle_deg, where every leg "
               "reaches (Eq. 1) and 1/cond(J) >= singularity_threshold"),
    MetricInfo("max_spherical_angle_deg", "deg",
               "max over samples and legs of the angle between the lever direction in the platform frame, R^T e_i, "
               "and its direction at the zero pose"),
    MetricInfo("max_universal_angle_deg", "deg",
               "max over samples and legs of the angle between the lever direction e_i and its direction at "
               "the zero pose (base frame)"),
    MetricInfo("stroke_m", "m", "max over legs of (max L_i - min L_i) along the motion, Eq. (2)"),
    MetricInfo("slider_min_m", "m", "lowest slider position (lower platform's sliders), Eq. (2)"),
    MetricInfo("slider_max_m", "m", "highest slider position (upper platform's sliders), Eq. (2)"),
    MetricInfo("peak_torque_Nm", "N m", "max over samples and motors of |tau_i|, Eq. (14) with friction"),
    MetricInfo("rms_torque_Nm", "N m", "max over motors of sqrt((1/T) int tau_i^2 dt)"),
    MetricInfo("peak_drive_force_N", "N", "peak_torque_Nm * 2 pi / p: the axial force of the linear module"),
    MetricInfo("peak_slider_speed_m_s", "m/s", "max |Ld_i|, Eq. (3)"),
    MetricInfo("peak_slider_acceleration_m_s2", "m/s^2", "max |Ldd_i|, Eq. (5)"),
    MetricInfo("peak_motor_speed_rad_s", "rad/s", "max |theta_dot_i| = max |Ld_i| 2 pi / p"),
    MetricInfo("rms_motor_speed_rad_s", "rad/s", "max over motors of sqrt((1/T) int theta_dot_i^2 dt)"),
    MetricInfo("peak_power_W", "W", "max over samples of sum_i tau_i theta_dot_i"),
    MetricInfo("motor_energy_per_cycle_J", "J", "(1/c) int sum_i |tau_i theta_dot_i| dt, c cycles of the motion"),
    MetricInfo("friction_energy_per_cycle_J", "J",
               "(1/c) int sum_i tau_f,i theta_dot_i dt: the work the motors spend on every joint's friction"),
)


def base_description(params_path: Path | None) -> dict[str, Any]:
    """The parameter file as a dict (``None``: the built-in paper parameters)."""
    return default_params_dict() if params_path is None else read_toml(params_path)


def check_description(description: Mapping[str, Any], source: str) -> None:
    """The validation of :func:`~pkmdyn.machines.hip_simulator.load_params`."""
    model_from_dict(dict(description), source)


def _options(options: Mapping[str, Any]) -> _Motion:
    return validate(_Motion, dict(options), "[motion]")


def metrics(options: Mapping[str, Any], description: Mapping[str, Any] | None = None) -> tuple[MetricInfo, ...]:
    """Every metric; the orientation workspace only when ``workspace_points`` > 0."""
    points = options.get("workspace_points", 256)
    if points == 0 and not isinstance(points, bool):
        return tuple(m for m in _METRICS if m.name != "orientation_workspace_fraction")
    return _METRICS


def _motion(opt: _Motion, model: HipModel, base_dir: Path) -> tuple[OrientationMotion, float]:
    lim = model.limits
    if opt.file is not None:
        given = opt.model_fields_set & {"cycles", "samples_per_cycle", "motion_model"}
        if given:
            raise MotionError(f"[motion] {sorted(given)[0]}: applies to the built-in cycle, not to file")
        path = Path(opt.file) if Path(opt.file).is_absolute() else base_dir / opt.file
        motion = read_motion_csv(path, max_rows=lim.max_samples)
        _check_motion_limits(lambda k: f"{path}: row {k + 1}", motion, lim)
        return motion, 1.0
    cycle = iso_cycle_preset(opt.motion_model)
    n = iso14242_samples(opt.cycles, opt.samples_per_cycle, lim.max_samples)
    motion = iso14242_block(iso14242_times(n, opt.cycles, cycle), cycle)
    _check_motion_limits(lambda k: f"built-in motion, sample {k + 1}", motion, lim)
    return motion, opt.cycles


def _workspace_rotations(sequence: str, points: int, max_angle_deg: float) -> Array:
    from scipy.stats import qmc

    if points == 0:
        return np.zeros((0, 3, 3))
    u = qmc.Sobol(3, scramble=True, rng=np.random.default_rng(WORKSPACE_SEED)).random_base2(
        max(0, math.ceil(math.log2(points))))[:points]
    return euler_to_matrix(sequence, np.deg2rad(max_angle_deg) * (2.0 * u - 1.0))


def prepare(description: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path) -> HipSweepContext:
    """Check the ``[motion]`` options and compute the motion every design performs.

    The base description must itself be valid: its Euler sequence and ``[limits]`` apply to
    the motion (angles and load are checked against them here, before any design).
    """
    opt = _options(options)
    model = model_from_dict(dict(description), "base parameters")
    motion, cycles = _motion(opt, model, base_dir)
    seq = model.geometry.euler_sequence
    R, w, wd = euler_kinematics(seq, motion.angles, motion.rates, motion.accels)
    return HipSweepContext(t=motion.t, R=R, omega=w, omega_dot=wd, load=motion.load, cycles=cycles,
                           threshold=opt.singularity_threshold,
                           R_ws=_workspace_rotations(seq, opt.workspace_points, opt.workspace_max_angle_deg),
                           workspace_max_angle_deg=opt.workspace_max_angle_deg)


def zero_pose_lever_directions(model: HipModel) -> Array:
    """Unit lever directions (b -> a) at the zero pose ``(3, 3)`` [leg, xyz], base frame = platform frame."""
    g = model.geometry
    dx = g.r_a[:, 0] - g.A[:, 0]
    dy = g.r_a[:, 1] - g.A[:, 1]
    return np.stack([dx, dy, np.sqrt(g.l * g.l - dx * dx - dy * dy)], axis=-1) / g.l


def _angle(a: Array, b: Array) -> Array:
    """Angle [rad] between unit vectors along the last axis (accurate near 0 and pi)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def _inverse_condition(J: Array) -> Array:
    """``1 / cond(J) = sigma_min / sigma_max`` of 3 x 3 matrices ``J (..., 3, 3)``, batched.

    The squared singular values are the eigenvalues of ``A = J^T J``, found in closed form
    (the trigonometric solution of the characteristic cubic of a symmetric 3 x 3 matrix):
    with ``q = tr(A) / 3``, ``p^2 = |A - q I|_F^2 / 6``, ``r = det((A - q I) / p) / 2``,
    ``phi = acos(r) / 3``: ``lambda_max = q + 2 p cos(phi)``, ``lambda_min = q + 2 p cos(phi + 2 pi / 3)``.
    Some 3x faster than a batched SVD; agrees with ``np.linalg.cond`` to about 1e-10 for
    1/cond(J) >= 1e-3 (the absolute error of ``lambda_min`` is ``~ eps lambda_max``).
    """
    A = np.einsum("...ki,...kj->...ij", J, J)
    a00, a11, a22 = A[..., 0, 0], A[..., 1, 1], A[..., 2, 2]
    a01, a02, a12 = A[..., 0, 1], A[..., 0, 2], A[..., 1, 2]
    q = (a00 + a11 + a22) / 3.0
    b00, b11, b22 = a00 - q, a11 - q, a22 - q
    off = a01 * a01 + a02 * a02 + a12 * a12
    p = np.sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0)
    det = b00 * (b11 * b22 - a12 * a12) - a01 * (a01 * b22 - a12 * a02) + a02 * (a01 * a12 - b11 * a02)
    safe = np.where(p > 0.0, p, 1.0)
    r = np.clip(0.5 * det / (safe * safe * safe), -1.0, 1.0)
    phi = np.arccos(r) / 3.0
    lam_max = q + 2.0 * p * np.cos(phi)
    lam_min = np.maximum(q + 2.0 * p * np.cos(phi + 2.0 * np.pi / 3.0), 0.0)
    return np.sqrt(lam_min / lam_max)


def _workspace_fraction(model: HipModel, R_ws: Array, threshold: float) -> float:
    """Share of the orientations ``R_ws`` every leg reaches with 1/cond(J) >= threshold (Eq. 1, 3)."""
    g = model.geometry
    r = np.einsum("mxk,ik->mix", R_ws, g.r_a)  # (m, leg, xyz), platform centre o_j at the origin
    dx = r[..., 0] - g.A[:, 0]
    dy = r[..., 1] - g.A[:, 1]
    reach2 = g.l * g.l - dx * dx - dy * dy
    ok = np.all(reach2 > 0.0, axis=1)
    if not ok.any():
        return 0.0
    e = np.stack([dx[ok], dy[ok], np.sqrt(reach2[ok])], axis=-1) / g.l
    J = np.cross(r[ok], e) / e[..., 2:3]
    good = _inverse_condition(J) >= threshold
    return float(np.count_nonzero(good)) / R_ws.shape[0]


def evaluate_one(description: Mapping[str, Any], ctx: HipSweepContext) -> DesignOutcome:
    """One design: validated model -> kinematics -> dynamics -> metrics (``docs/sweep.md``)."""
    try:
        model = model_from_dict(dict(description), "design")
    except PkmdynError as exc:
        return DesignOutcome("invalid", str(exc))
    g = model.geometry
    try:
        kin = _platform_kinematics(model, ctx.t, ctx.R, ctx.omega, ctx.omega_dot, check_conditioning=False)
        tq = inverse_dynamics(model, kin, ctx.load)
    except UnreachablePoseError as exc:
        return DesignOutcome("unreachable", str(exc))
    except SingularityError as exc:
        return DesignOutcome("singular", str(exc))
    t = ctx.t
    inv_cond = _inverse_condition(kin.J)
    gear = g.p / (2.0 * math.pi)
    Ld, Ldd = kin.Ld[:, -1], kin.Ldd[:, -1]
    theta_dot = Ld / gear
    L = kin.L
    e0 = zero_pose_lever_directions(model)
    e_platform = np.einsum("nji,nkj->nki", kin.R, kin.e_lever)  # R^T e, per leg
    peak_tau = float(np.abs(tq.tau).max())
    power = np.sum(tq.tau * theta_dot, axis=1)
    m: dict[str, float] = {
        "gci": float(time_mean(inv_cond, t)),
        "min_inverse_condition": float(inv_cond.min()),
        "max_spherical_angle_deg": math.degrees(float(_angle(e_platform, e0).max())),
        "max_universal_angle_deg": math.degrees(float(_angle(kin.e_lever, e0).max())),
        "stroke_m": float((L[:, 1].max(axis=0) - L[:, 1].min(axis=0)).max()),
        "slider_min_m": float(L[:, 1].min()),
        "slider_max_m": float(L[:, 0].max()),
        "peak_torque_Nm": peak_tau,
        "rms_torque_Nm": float(np.sqrt(time_mean(tq.tau**2, t)).max()),
        "peak_drive_force_N": peak_tau / gear,
        "peak_slider_speed_m_s": float(np.abs(Ld).max()),
        "peak_slider_acceleration_m_s2": float(np.abs(Ldd).max()),
        "peak_motor_speed_rad_s": float(np.abs(theta_dot).max()),
        "rms_motor_speed_rad_s": float(np.sqrt(time_mean(theta_dot**2, t)).max()),
        "peak_power_W": float(power.max()),
        "motor_energy_per_cycle_J": float(time_integral(np.abs(tq.tau * theta_dot).sum(axis=1), t)) / ctx.cycles,
        "friction_energy_per_cycle_J": float(time_integral(np.sum(tq.friction * theta_dot, axis=1), t)) / ctx.cycles,
    }
    if ctx.R_ws.shape[0]:
        m["orientation_workspace_fraction"] = _workspace_fraction(model, ctx.R_ws, ctx.threshold)
    k = int(np.argmin(inv_cond))
    if not inv_cond[k] >= ctx.threshold:
        return DesignOutcome("singular", f"t = {t[k]:.6g} s (sample {k + 1}): 1/cond(J) = {inv_cond[k]:.3g} is below "
                                         f"the singularity threshold {ctx.threshold:g}", m)
    lim = model.limits
    try:
        check_limit(m["peak_slider_speed_m_s"], lim.max_slider_speed_m_s, "slider speed", "max_slider_speed_m_s",
                    "m/s", option=False)
        check_limit(m["peak_slider_acceleration_m_s2"], lim.max_slider_acceleration_m_s2, "slider acceleration",
                    "max_slider_acceleration_m_s2", "m/s^2", option=False)
    except LimitError as exc:
        return DesignOutcome("limit", str(exc), m)
    return DesignOutcome("ok", "", m)


def evaluate(descriptions: Sequence[Mapping[str, Any]], context: HipSweepContext) -> list[DesignOutcome]:
    """Each design of a batch by itself (:func:`evaluate_one`): rows never depend on the batch."""
    with np.errstate(all="ignore"):  # a non-finite metric becomes the status "nonfinite", not a warning
        return [evaluate_one(d, context) for d in descriptions]

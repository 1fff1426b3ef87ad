"""The hip simulator swept on the engine: what ``pkmdyn sweep --machine hip`` evaluates per design.

The hooks of :class:`pkmdyn.multibody.analyses.designs.GeneratedSweep`: a design is a hip parameter file
(``docs/file_formats.md``; its schema is :func:`~.params.model_from_dict`'s), turned into the
mechanism description of :func:`~.description.hip_description` and evaluated by the engine
(:func:`pkmdyn.multibody.analyses.designs.evaluate_model`: the description's structure compiled once for
the sweep, its numbers per design; kinematics along the motion, the least singularity measures
with ``[motion] engine_measures = true``, the motor efforts with every joint reaction and the friction, the hip-joint and thrust-bearing
friction driven by the hydraulic load, the named load ``hydraulic_N``). Every design performs
the same motion: the built-in ISO 14242-1 cycle (500 samples by default) or a hip motion file.

This module says what is the hip's own: the ``[motion]`` options, and the metrics under the
names and units of ``docs/sweep.md``, computed from the engine's results (the sliders are the
actuated joints ``P_i``, the motors the drives ``motor_i`` with their lead screws, the lever
directions the line from each universal to each spherical joint). The orientation workspace
is the one metric not taken from the engine's kinematics: the reach and conditioning of Eq. (1)
and (3) at fixed orientations, on the parameter file's geometry.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any, Literal

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from ...errors import LimitError, MotionError
from ...multibody import TaskMotion
from ...multibody.analyses.designs import GeneratedMotion
from ...multibody.dynamics.actuators import motor_efforts
from ...params_util import Section, check_limit, validate
from ...profiles.iso14242 import iso14242_block, iso14242_samples, iso14242_times
from ...profiles.orientation import read_motion_csv
from ...spatial import euler_to_matrix
from ...sweep_protocol import DesignOutcome, MetricInfo, time_integral, time_mean
from .description import hip_description
from .paper import euler_rate_map, iso_cycle_preset
from .params import HipModel, check_motion_limits, default_params_dict, model_from_dict

__all__ = ["NAME", "HipMotionData", "default_params", "check_params", "description", "motion", "metrics",
           "design_metrics", "WORKSPACE_SEED"]

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
    #: the engine's least singularity measures (``min_inverse_measure``, ``min_direct_measure``,
    #: ``min_constraint_measure``): reported only (the status comes from 1/cond(J)), and the
    #: largest stage of a design, so not computed unless asked for
    engine_measures: bool = False


@dataclass(frozen=True)
class HipMotionData:
    """The hip's design-independent data: ``E_inv (n, 3, 3)`` the Euler rates per platform
    angular velocity at each sample (``J = J_ax E_inv``, Eq. 3: slider speed per angular
    velocity); ``cycles``: cycles the motion spans (1 for a motion file); ``threshold``: the
    least admissible 1/cond(J); ``R_ws (m, 3, 3)``: the orientations of the orientation
    workspace (``m = 0``: not computed)."""

    E_inv: Array
    cycles: float
    threshold: float
    R_ws: Array


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
#: the engine's metrics kept under their own names: its singularity measures (``[motion]
#: engine_measures = true``) and every joint's reaction (the engine's conditioning index, efforts, speeds and energies are the hip's
#: above, in the hip's terms: motor torques and speeds, per cycle)
_ENGINE_KEPT = ("min_inverse_measure", "min_direct_measure", "min_constraint_measure")


def _kept(name: str) -> bool:
    """Whether the engine's metric ``name`` is a column of the hip's sweep."""
    return name in _ENGINE_KEPT or name.startswith(("peak_force_", "peak_moment_"))


def default_params() -> dict[str, Any]:
    """The built-in parameter file (the paper's Tables 1-2) as a dict."""
    return default_params_dict()


def check_params(params: Mapping[str, Any], source: str) -> None:
    """The validation of :func:`~pkmdyn.machines.hip_simulator.load_params`."""
    model_from_dict(dict(params), source)


def description(params: Mapping[str, Any]) -> dict[str, Any]:
    """The mechanism description of a parameter file (:func:`~.description.hip_description`)."""
    return hip_description(model_from_dict(dict(params), "design"))


def _orientation_motion(opt: _Motion, model: HipModel, base_dir: Path) -> tuple[Any, float]:

    lim = model.limits
    if opt.file is not None:
        given = opt.model_fields_set & {"cycles", "samples_per_cycle", "motion_model"}
        if given:
            raise MotionError(f"[motion] {sorted(given)[0]}: applies to the built-in cycle, not to file")
        path = Path(opt.file) if Path(opt.file).is_absolute() else base_dir / opt.file
        mo = read_motion_csv(path, max_rows=lim.max_samples)
        check_motion_limits(lambda k: f"{path}: row {k + 1}", mo, model.limits)
        return mo, 1.0
    cycle = iso_cycle_preset(opt.motion_model)
    n = iso14242_samples(opt.cycles, opt.samples_per_cycle, lim.max_samples)
    mo = iso14242_block(iso14242_times(n, opt.cycles, cycle), cycle)
    check_motion_limits(lambda k: f"built-in motion, sample {k + 1}", mo, model.limits)
    return mo, opt.cycles


def _workspace_rotations(sequence: str, points: int, max_angle_deg: float) -> Array:
    from scipy.stats import qmc

    if points == 0:
        return np.zeros((0, 3, 3))
    u = qmc.Sobol(3, scramble=True, rng=np.random.default_rng(WORKSPACE_SEED)).random_base2(
        max(0, math.ceil(math.log2(points))))[:points]
    return euler_to_matrix(sequence, np.deg2rad(max_angle_deg) * (2.0 * u - 1.0))


def motion(params: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path) -> Any:
    """Check the ``[motion]`` options and build the motion every design performs: the platform's
    Euler angles (the description's task) with the hydraulic load as ``hydraulic_N``.

    The base parameters must themselves be valid: their Euler sequence and ``[limits]`` apply
    to the motion (angles and load are checked against them here, before any design)."""

    opt = validate(_Motion, dict(options), "[motion]")
    model = model_from_dict(dict(params), "base parameters")
    mo, cycles = _orientation_motion(opt, model, base_dir)
    seq = model.geometry.euler_sequence
    E = euler_rate_map(seq, mo.angles)  # the angular velocity of a unit rate of angle k: column k
    data = HipMotionData(E_inv=np.linalg.inv(E), cycles=cycles, threshold=opt.singularity_threshold,
                         R_ws=_workspace_rotations(seq, opt.workspace_points, opt.workspace_max_angle_deg))
    task = TaskMotion(mo.t, mo.angles, mo.rates, mo.accels, {"hydraulic_N": mo.load})
    # the hip's singularity threshold is on its own 1/cond(J) (design_metrics): the engine's
    # measures, when asked for, are reported, never a design's status
    return GeneratedMotion(task, 0.0, data, measures=opt.engine_measures)


def metrics(options: Mapping[str, Any], engine: tuple[MetricInfo, ...]) -> tuple[MetricInfo, ...]:
    """The hip's metrics (the orientation workspace only when ``workspace_points`` > 0), then
    the engine's singularity measures (with ``engine_measures = true``) and every joint's peak
    reaction force and moment."""
    points = options.get("workspace_points", 256)
    own = _METRICS
    if points == 0 and not isinstance(points, bool):
        own = tuple(m for m in _METRICS if m.name != "orientation_workspace_fraction")
    measures = options.get("engine_measures", False) is True
    return own + tuple(m for m in engine if _kept(m.name) and (measures or m.name not in _ENGINE_KEPT))


def _angle(a: Array, b: Array) -> Array:
    """Angle [rad] between vectors along the last axis (accurate near 0 and pi; any lengths)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def _inverse_condition(J: Array) -> Array:
    """``1 / cond(J) = sigma_min / sigma_max`` of 3 x 3 matrices ``J (..., 3, 3)``, batched.

    The squared singular values are the eigenvalues of ``A = J^T J``, found in closed form
    (the trigonometric solution of the characteristic cubic of a symmetric 3 x 3 matrix):
    with ``q = tr(A) / 3``, ``p^2 = |A - q I|_F^2 / 6``, ``r = det((A - q I) / p) / 2``,
    ``phi = acos(r) / 3``: ``lambda_max = q + 2 p cos(phi)``, ``lambda_min = q + 2 p cos(phi + 2 pi / 3)``.
    Agrees with ``np.linalg.cond`` to about 1e-10 for 1/cond(J) >= 1e-3 (the absolute error of
    ``lambda_min`` is ``~ eps lambda_max``).
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
    """Share of the orientations ``R_ws`` every leg reaches with 1/cond(J) >= threshold: the
    loop closure of each lever (Eq. 1: the lever reaches its slider's screw) and the
    conditioning of ``J`` (Eq. 3) at each orientation, on the parameter file's geometry."""
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


def _kinematic_metrics(state: Any, data: HipMotionData) -> tuple[dict[str, float], Array]:
    """The metrics of the engine's kinematics, and 1/cond(J) at every sample."""
    model, kin = state.model, state.kin
    t = state.motion.t
    names = model.joint_names
    up = model.body_names.index("upper")
    J = np.einsum("nat,ntk->nak", kin.J_ax, data.E_inv)  # slider speed per platform angular velocity
    inv_cond = _inverse_condition(J)
    m: dict[str, float] = {"gci": float(time_mean(inv_cond, t)), "min_inverse_condition": float(inv_cond.min())}
    U = [names.index(f"U_upper_{i + 1}") for i in range(3)]
    S = [names.index(f"S_upper_{i + 1}") for i in range(3)]
    e = kin.joint_point[:, S] - kin.joint_point[:, U]  # (n, leg, xyz): the levers, U -> S
    levers = [model.body_names.index(f"lever_upper_{i + 1}") for i in range(3)]
    # each lever's direction at the zero pose (the reference configuration), from its body frame
    e0 = np.einsum("lij,lkj,lk->li", model.R0[levers], kin.R[0, levers], e[0])
    e_platform = np.einsum("nji,nkj->nki", kin.R[:, up], e)  # R^T e, per leg
    m["max_spherical_angle_deg"] = math.degrees(float(_angle(e_platform, e0).max()))
    m["max_universal_angle_deg"] = math.degrees(float(_angle(e, e0).max()))
    L_upper = kin.joint_point[:, U, 2]  # slider heights: the universal joints' centres
    L_lower = kin.joint_point[:, [names.index(f"U_lower_{i + 1}") for i in range(3)], 2]
    m["stroke_m"] = float((L_lower.max(axis=0) - L_lower.min(axis=0)).max())
    m["slider_min_m"] = float(L_lower.min())
    m["slider_max_m"] = float(L_upper.max())
    m["peak_slider_speed_m_s"] = float(np.abs(kin.act_qd).max())
    m["peak_slider_acceleration_m_s2"] = float(np.abs(kin.act_qdd).max())
    theta_dot = kin.act_qd * model.drive_ratio
    m["peak_motor_speed_rad_s"] = float(np.abs(theta_dot).max())
    m["rms_motor_speed_rad_s"] = float(np.sqrt(time_mean(theta_dot**2, t)).max())
    return m, inv_cond


def _effort_metrics(state: Any, data: HipMotionData) -> dict[str, float]:
    """The motor torques' metrics (Eq. A1 of :mod:`pkmdyn.multibody.dynamics.actuators`: the joint
    effort through the lead screw, the rotor's inertia, the screw's friction)."""
    model, kin, t = state.model, state.kin, state.motion.t
    me = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, state.u)
    tau, theta_dot = me.effort, me.theta_dot
    peak_tau = float(np.abs(tau).max())
    friction_power = np.sum(me.friction * theta_dot, axis=1)
    if state.reactions is not None:
        friction_power = friction_power + state.reactions.dissipation
    return {
        "peak_torque_Nm": peak_tau,
        "rms_torque_Nm": float(np.sqrt(time_mean(tau**2, t)).max()),
        "peak_drive_force_N": peak_tau * float(model.drive_ratio.max()),
        "peak_power_W": float(np.sum(tau * theta_dot, axis=1).max()),
        "motor_energy_per_cycle_J": float(time_integral(np.abs(tau * theta_dot).sum(axis=1), t)) / data.cycles,
        "friction_energy_per_cycle_J": float(time_integral(friction_power, t)) / data.cycles,
    }


def design_metrics(params: Mapping[str, Any], outcome: DesignOutcome, state: Any, data: HipMotionData
                   ) -> DesignOutcome:
    """One design's outcome in the hip's terms (``docs/sweep.md``): the engine's outcome where
    its kinematics failed; else the hip's metrics, ``singular`` where 1/cond(J) falls below the
    threshold, ``limit`` beyond the design's ``[limits]`` slider speed or acceleration."""
    if state.kin is None:
        return outcome
    m = {k: v for k, v in outcome.metrics.items() if _kept(k)}
    own, inv_cond = _kinematic_metrics(state, data)
    m.update(own)
    if state.u is not None:
        m.update(_effort_metrics(state, data))
    model = model_from_dict(dict(params), "design")
    if data.R_ws.shape[0]:
        m["orientation_workspace_fraction"] = _workspace_fraction(model, data.R_ws, data.threshold)
    t = state.motion.t
    k = int(np.argmin(inv_cond))
    if not inv_cond[k] >= data.threshold:
        return DesignOutcome("singular", f"t = {t[k]:.6g} s (sample {k + 1}): 1/cond(J) = {inv_cond[k]:.3g} is below "
                                         f"the singularity threshold {data.threshold:g}", m)
    lim = model.limits
    try:
        check_limit(m["peak_slider_speed_m_s"], lim.max_slider_speed_m_s, "slider speed", "max_slider_speed_m_s",
                    "m/s", option=False)
        check_limit(m["peak_slider_acceleration_m_s2"], lim.max_slider_acceleration_m_s2, "slider acceleration",
                    "max_slider_acceleration_m_s2", "m/s^2", option=False)
    except LimitError as exc:
        return DesignOutcome("limit", str(exc), m)
    return DesignOutcome(outcome.status, outcome.reason, m)

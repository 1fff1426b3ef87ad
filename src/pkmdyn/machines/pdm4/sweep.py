"""The PDM's sweep adapter: what ``pkmdyn sweep --machine pdm`` evaluates per design.

The functions of :class:`pkmdyn.sweep_protocol.SweepAdapter`. Each design performs the Eq. 84
cycloidal motion of its own ``[trajectory]`` table (so the strokes and the period can be
swept too), or one motion file for all designs. Per design: the validated model
(:func:`~pkmdyn.machines.pdm4.params.params_from_dict`) and the route of ``pkmdyn pdm run``
(:func:`.run.compute`): the paper's geometry check (a pose beyond a stroke or a six-bar that
cannot close is refused), the generic engine's kinematics of every body of the PDM's
description, its joint reactions made unique by link compliance, and the limbs' Jacobian
``dl/dq``. The PDM has no friction model, so it has no friction metric. Metrics, formulas,
units: ``docs/sweep.md``.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from ...errors import PkmdynError, SingularityError, UnreachablePoseError
from ...params_util import Section, read_toml, validate
from ...profiles.pdm_motion import PdmMotion, cycloidal_motion, read_pdm_motion
from ...sweep_protocol import DesignOutcome, MetricInfo, time_integral
from .paper import JOINTS
from .params import default_params_path, params_from_dict
from .run import compute
from .workspace import reachable_workspace

__all__ = ["NAME", "PdmSweepContext", "base_description", "check_description", "metrics", "prepare", "evaluate",
           "evaluate_one", "joint_column"]

NAME = "pdm"
Array = NDArray[np.float64]


class _Motion(Section):
    file: str | None = None
    singularity_threshold: Annotated[float, Field(ge=0.0, le=1.0)] = 1e-3
    characteristic_length_m: Annotated[float, Field(gt=0.0, le=10.0)] | None = None
    workspace: bool = False


@dataclass(frozen=True)
class PdmSweepContext:
    """Design-independent data: the motion of a motion file (``None``: each design's own Eq. 84
    trajectory), the threshold on 1/cond, the characteristic length (``None``: each design's
    output-link length r4) and whether to search the workspace."""

    motion: PdmMotion | None
    threshold: float
    characteristic_length_m: float | None
    workspace: bool


def joint_column(name: str) -> str:
    """A joint's name as it appears in a column (``R21'`` -> ``R21p``)."""
    return name.replace("'", "p")


_BASE_METRICS = (
    MetricInfo("gci", "-", "(1/T) int 1/cond(J') dt; J' = (dl/dq) diag(1, 1, 1/L_c, 1/L_c), dl/dq = B(q)^T, "
               "L_c = characteristic_length_m (default: output_link_length_m)"),
    MetricInfo("min_inverse_condition", "-", "min over samples of 1/cond(J') = sigma_min / sigma_max"),
    MetricInfo("stroke_m", "m", "max over limbs of (max l_k - min l_k) along the motion"),
    MetricInfo("max_extension_m", "m", "max over samples and limbs of |l_k - l_k,home| (at most stroke_limit_m)"),
    MetricInfo("min_transmission_angle_deg", "deg", "min over samples and cranks of asin |sin(theta_2i - theta_1i)|"),
    MetricInfo("peak_force_N", "N", "max over samples and limbs of |f_k| (Newton-Euler, Eq. 49-62)"),
    MetricInfo("rms_force_N", "N", "max over limbs of sqrt((1/T) int f_k^2 dt)"),
    MetricInfo("peak_limb_speed_m_s", "m/s", "max |l_dot_k| (Eq. 37, 44)"),
    MetricInfo("rms_limb_speed_m_s", "m/s", "max over limbs of sqrt((1/T) int l_dot_k^2 dt)"),
    MetricInfo("peak_power_W", "W", "max over samples of sum_k f_k l_dot_k"),
    MetricInfo("motor_energy_per_cycle_J", "J", "int sum_k |f_k l_dot_k| dt over the motion (one Eq. 84 period)"),
)
_JOINT_METRICS = tuple(
    m for name, *_ in JOINTS for m in (
        MetricInfo(f"peak_force_{joint_column(name)}_N", "N", f"max over samples of |f| at joint {name} (Eq. 49-83)"),
        MetricInfo(f"peak_moment_{joint_column(name)}_Nm", "N m",
                   f"max over samples of |m| at joint {name}, about the joint point"),
    )
)
_WORKSPACE_METRIC = MetricInfo("workspace_mean_area_m2", "m^2",
                               "mean over the [workspace] gamma layers of the enclosed x-y area of the reachable "
                               "workspace (boundary search of section 2.2, shoelace formula)")


def base_description(params_path: Path | None) -> dict[str, Any]:
    """The parameter file as a dict (``None``: the built-in parameters)."""
    return read_toml(default_params_path() if params_path is None else params_path)


def check_description(description: Mapping[str, Any], source: str) -> None:
    """The validation of :func:`~pkmdyn.machines.pdm4.load_params`."""
    params_from_dict(dict(description), source)


def metrics(options: Mapping[str, Any], description: Mapping[str, Any] | None = None) -> tuple[MetricInfo, ...]:
    """Every metric; the workspace only with ``workspace = true`` in ``[motion]``."""
    extra = (_WORKSPACE_METRIC,) if options.get("workspace") is True else ()
    return _BASE_METRICS + extra + _JOINT_METRICS


def prepare(description: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path) -> PdmSweepContext:
    """Check the ``[motion]`` options; read the motion file, if any (its rows bounded by the base
    description's ``[limits] max_samples``)."""
    opt = validate(_Motion, dict(options), "[motion]")
    motion = None
    if opt.file is not None:
        model = params_from_dict(dict(description), "base parameters")
        path = Path(opt.file) if Path(opt.file).is_absolute() else base_dir / opt.file
        motion = read_pdm_motion(path, max_rows=model.max_samples)
    return PdmSweepContext(motion=motion, threshold=opt.singularity_threshold,
                           characteristic_length_m=opt.characteristic_length_m, workspace=opt.workspace)


def evaluate_one(description: Mapping[str, Any], ctx: PdmSweepContext) -> DesignOutcome:
    """One design: validated model -> motion -> kinematics, efforts and reactions -> metrics."""
    try:
        model = params_from_dict(dict(description), "design")
        tr = model.trajectory
        motion = ctx.motion if ctx.motion is not None else cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    except PkmdynError as exc:
        return DesignOutcome("invalid", str(exc))
    try:
        res = compute(model, motion, progress=False)
    except UnreachablePoseError as exc:
        return DesignOutcome("unreachable", str(exc))
    except SingularityError as exc:
        return DesignOutcome("singular", str(exc))
    cols = res.cols
    # J' = (dl/dq) diag(1, 1, 1/L_c, 1/L_c), dimensionless: the angular columns [m/rad] over L_c [m]
    length = ctx.characteristic_length_m or model.r4
    J = res.limb_jacobian * np.array([1.0, 1.0, 1.0 / length, 1.0 / length])
    t = motion.t
    T = t[-1] - t[0]
    s = np.linalg.svd(J, compute_uv=False)
    inv_cond = s[:, -1] / s[:, 0]
    f, ld, l = (np.stack([cols[f"{c}{k}_{u}"] for k in range(1, 5)], axis=-1)
                for c, u in (("f", "N"), ("ld", "m_s"), ("l", "m")))
    power = np.sum(f * ld, axis=1)
    transmission = min(float(np.arcsin(np.minimum(np.abs(np.sin(cols[f"coupler{i}_theta_rad"]
                                                                   - cols[f"crank{i}_theta_rad"])), 1.0)).min())
                       for i in (1, 2))
    m: dict[str, float] = {
        "gci": float(time_integral(inv_cond, t) / T),
        "min_inverse_condition": float(inv_cond.min()),
        "stroke_m": float((l.max(axis=0) - l.min(axis=0)).max()),
        "max_extension_m": float(np.abs(l - model.home_lengths).max()),
        "min_transmission_angle_deg": math.degrees(transmission),
        "peak_force_N": float(np.abs(f).max()),
        "rms_force_N": float(np.sqrt(time_integral(f * f, t) / T).max()),
        "peak_limb_speed_m_s": float(np.abs(ld).max()),
        "rms_limb_speed_m_s": float(np.sqrt(time_integral(ld * ld, t) / T).max()),
        "peak_power_W": float(power.max()),
        "motor_energy_per_cycle_J": float(time_integral(np.abs(f * ld).sum(axis=1), t)),
    }
    force = np.linalg.norm(res.npz["joint_force"], axis=-1).max(axis=0)
    moment = np.linalg.norm(res.npz["joint_moment"], axis=-1).max(axis=0)
    for j, (name, *_) in enumerate(JOINTS):
        m[f"peak_force_{joint_column(name)}_N"] = float(force[j])
        m[f"peak_moment_{joint_column(name)}_Nm"] = float(moment[j])
    if ctx.workspace:
        m[_WORKSPACE_METRIC.name] = float(reachable_workspace(model, progress=False).area().mean())
    k = int(np.argmin(inv_cond))
    if not inv_cond[k] >= ctx.threshold:
        return DesignOutcome("singular", f"t = {t[k]:.6g} s (sample {k + 1}): 1/cond(J') = {inv_cond[k]:.3g} is "
                                         f"below the singularity threshold {ctx.threshold:g}", m)
    return DesignOutcome("ok", "", m)


def evaluate(descriptions: Sequence[Mapping[str, Any]], context: PdmSweepContext) -> list[DesignOutcome]:
    """Each design of a batch by itself (:func:`evaluate_one`): rows never depend on the batch."""
    with np.errstate(all="ignore"):  # a non-finite metric becomes the status "nonfinite", not a warning
        return [evaluate_one(d, context) for d in descriptions]

"""The sweep adapter of a described mechanism: what ``pkmdyn sweep --machine NAME|FILE.toml``
evaluates per design of any mechanism description (:class:`pkmdyn.sweep_protocol.SweepAdapter`).

A design is the description with some numbers changed (masses, inertias, joint points and
axes, friction coefficients, the default motion...). Each design performs its own
``[default_motion]`` (so its amplitudes and period can be swept too) or one task-motion file
for all designs. Per design: the validated, compiled model (:func:`pkmdyn.multibody.load_mechanism`'s,
to the last bit: the description validated in full, its structure compiled once for the sweep
and its numbers per design, :func:`pkmdyn.multibody.model.compiler.compile_with`),
the kinematics along the motion (:func:`~pkmdyn.multibody.solve_kinematics`, which refuses a loop
that does not close), the singularity measures (:func:`~pkmdyn.multibody.singularity_measures`),
and the actuator efforts with every joint reaction and the joints' friction
(:func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`; with ``reactions = false`` the efforts
alone, :func:`pkmdyn.multibody.dynamics.newton_euler.inverse_dynamics`). The metrics are named after the
description's actuators and joints; formulas and units: ``docs/sweep.md``.
"""

from __future__ import annotations

import copy
import importlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Annotated, Any

import numpy as np
from numpy.typing import NDArray
from pydantic import Field

from ...errors import (
    LimitError,
    ParameterError,
    PkmdynError,
    SingularityError,
    UnreachablePoseError,
)
from ...params_util import Section, read_toml, validate
from ...sweep_protocol import DesignOutcome, MetricInfo, time_integral, time_mean
from ..description.schema import load_description
from ..dynamics.actuators import (
    check_actuator_rates,
    check_task_rates,
    effective_limits,
    motor_efforts,
)
from ..dynamics.newton_euler import effort_unit, inverse_dynamics, joint_reactions
from ..dynamics.compliance.reactions import ComplianceDataMissing
from ..kinematics.inverse import (
    beyond_limits,
    joint_coordinates,
    limit_bounds,
    limited_joints,
    reference_task,
    solve_kinematics,
)
from ..kinematics.singularity.measures import least_measures, singularity_measures
from ..kinematics.motion import default_motion, read_task_motion
from ..model.compiler import (
    compile_with,
    load_mechanism,
    model_structure,
    structure_key,
)
from .stiffness import compliance_sources, stiffness
from .task_grid import parse_grid, parse_pose, parse_ranges
from .workspace import edges_reached, size_unit, workspace

__all__ = ["DescribedSweep", "DescribedSweepContext", "DesignState", "evaluate_model", "GeneratedMotion",
           "GeneratedSweep", "GeneratedSweepContext"]

Array = NDArray[np.float64]


class _Requirements(Section):
    """``[requirements]`` of a space file: a task region every design must reach (``grid``, the
    ``pkmdyn workspace --grid`` syntax, at the poses ``pose``)."""

    grid: str = Field(max_length=400)
    pose: str = Field(default="", max_length=400)


class _Motion(Section):
    file: str | None = None
    requirements: _Requirements | None = None
    singularity_threshold: Annotated[float, Field(ge=0.0, le=1.0)] = 1e-3
    reactions: bool = True
    #: the stiffness metrics (with a compliance source in the description); false: none
    stiffness: bool = True
    #: a grid of task poses (``pkmdyn workspace --grid``): each design's workspace size on it
    workspace_grid: str | None = Field(default=None, max_length=400)
    #: the poses the grid holds fixed (``--pose``)
    workspace_pose: str = Field(default="", max_length=400)
    #: held coordinates over ranges (``--orientation-range``): the total orientation workspace
    workspace_orientation_range: str | None = Field(default=None, max_length=400)
    #: the least singularity measure over each design's workspace (``workspace_min_measure``)
    workspace_measure: bool = True
    #: steps of each boundary edge for the workspace's size (``pkmdyn workspace --refine``;
    #: 0: inside poses times the cell)
    workspace_refine: Annotated[int, Field(ge=0, le=64)] = 0


@dataclass(frozen=True)
class DescribedSweepContext:
    """Design-independent data: the motion of a motion file (None: each design's own
    ``[default_motion]``), the threshold on the singularity measures, whether the joint
    reactions are computed, and the base description's compiled structure (``template``)."""

    motion: Any
    threshold: float
    reactions: bool
    #: the stiffness metrics the base description has (:func:`_stiffness_metrics`)
    stiffness: tuple[str, ...] = ()
    #: ``[motion] workspace_grid``, ``workspace_pose`` and ``workspace_orientation_range`` (None:
    #: no workspace metrics)
    workspace: tuple[str, str, str | None] | None = None
    #: ``[requirements]`` ``grid`` and ``pose`` (None: no coverage metric)
    required: tuple[str, str, str | None] | None = None
    #: ``[motion] workspace_measure``: the metric ``workspace_min_measure``
    workspace_measure: bool = True
    #: ``[motion] workspace_refine``: the steps of each boundary edge for the size
    workspace_refine: int = 0
    #: the base description's compiled structure (:class:`pkmdyn.multibody.model.compiler.ModelStructure`),
    #: made once in :meth:`DescribedSweep.prepare` and sent with the context to every worker: a
    #: design of the same structure compiles only its numbers (None: every design in full)
    template: Any = None
    #: the conditioning index ``gci`` (the time mean of a singularity measure at every sample);
    #: false: a machine that computes a conditioning index of its own (:class:`GeneratedSweep`)
    gci: bool = True
    #: the least of each singularity measure over the samples (``min_*_measure``, and the status
    #: ``singular`` below ``threshold``); false: a machine whose status comes from a measure of its
    #: own and that does not report the engine's (:attr:`GeneratedMotion.measures`)
    measures: bool = True
    #: the efforts' metrics (``peak_effort_*``, ``rms_*``, ``peak_power_W``, the energies, the limit
    #: margins); false: a machine that computes its own from the efforts (:class:`GeneratedSweep`)
    efforts: bool = True


def _names(description: Mapping[str, Any]) -> tuple[list[tuple[str, str]], list[str], bool, bool, bool]:
    """The actuators (name, effort unit ``N`` or ``Nm``) and the joints of a description, as
    the compiled model names them, whether it has as many actuators as task coordinates
    (the direct singularity measure is defined), whether a joint has limits and whether a
    drive has a rated effort."""

    model = load_mechanism(copy.deepcopy(dict(description)))
    acts = [(name, effort_unit(model, i)) for i, name in enumerate(model.actuator_names)]
    return (acts, list(model.joint_names), model.na == model.nt, bool(limited_joints(model)),
            bool(np.isfinite(model.drive_max_effort).any()) if model.has_drives else False)


def _limit_metrics(model: Any, kin: Any, u: Array) -> dict[str, float]:
    """``joint_limit_margin`` where a joint has limits: the least, over the samples and the
    limited joints, of the distance to the nearer limit over the joint's range (0 at a limit or
    within ``pkmdyn run``'s tolerance beyond it, 0.5 mid-range, negative beyond it);
    ``peak_effort_over_rated`` where a drive has a rated effort: the largest motor effort (Eq.
    A1 of :mod:`pkmdyn.multibody.dynamics.actuators`: transmitted, rotor and motor friction) over its rating, over the
    samples and the rated drives (above 1: beyond it)."""

    out: dict[str, float] = {}
    joints = limited_joints(model)
    if joints:
        c = joint_coordinates(model, kin, joints)
        lo, hi = limit_bounds(model, joints)
        margin = np.minimum(c - lo, hi - c) / (hi - lo)
        # within the tolerance that pkmdyn run allows at a limit (beyond_limits): at the limit, 0
        margin = np.where((margin < 0.0) & ~beyond_limits(model, c, joints), 0.0, margin)
        out["joint_limit_margin"] = float(margin.min())
    if model.has_drives:
        rated = np.isfinite(model.drive_max_effort)
        if rated.any():
            tau = motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, u).effort
            out["peak_effort_over_rated"] = float((np.abs(tau[:, rated]) / model.drive_max_effort[rated]).max())
    return out


def _speed_unit(effort_unit: str) -> str:
    return "m_s" if effort_unit == "N" else "rad_s"


def _mean(x: Array, t: Array) -> float:
    """The time average of ``x (n,)`` over the motion (:func:`~pkmdyn.sweep_protocol.time_mean`);
    the plain mean of a motion of one instant."""
    return float(time_mean(x, t)) if t[-1] > t[0] else float(x.mean())


def _mechanism_name(raw: Any) -> Any:
    """A description's ``[mechanism] name`` as written, or None."""
    mech = raw.get("mechanism") if isinstance(raw, dict) else None
    return mech.get("name") if isinstance(mech, dict) else None


@dataclass(frozen=True, eq=False)
class DescribedSweep:
    """The sweep adapter of the mechanism described by ``path`` (``NAME``: its
    ``[mechanism] name``). The file is read once, here (it may be a pipe)."""

    path: Path
    raw: dict[str, Any] = field(repr=False)
    NAME: str = ""

    @classmethod
    def from_file(cls, path: str | Path) -> DescribedSweep:
        raw = read_toml(path)
        name = _mechanism_name(raw)
        if not isinstance(name, str):
            raise ParameterError(f"{path}: [mechanism] name: missing (a described mechanism names itself)")
        return cls(Path(path), raw, name)

    def base_description(self, params_path: Path | None) -> dict[str, Any]:
        """The description to vary: ``params_path`` (a description file of the same mechanism,
        ``[mechanism] name``: other numbers, the same machine) or the machine's own. A file of
        another mechanism is refused: its sweep would carry this machine's name."""
        if params_path is None:
            return copy.deepcopy(self.raw)
        raw = read_toml(params_path)
        name = _mechanism_name(raw)
        if name != self.NAME:
            raise ParameterError(f"--params {params_path}: [mechanism] name: {name!r} is not {self.NAME!r}, the machine "
                                 "swept; give another mechanism as --machine FILE.toml")
        return raw

    def check_description(self, description: Mapping[str, Any], source: str) -> None:
        """The validation of :func:`pkmdyn.multibody.load_mechanism` (and the model's compilation)."""
        try:
            load_mechanism(copy.deepcopy(dict(description)))
        except PkmdynError as exc:
            raise ParameterError(f"{source}: {exc}") from None

    def metrics(self, options: Mapping[str, Any], description: Mapping[str, Any] | None = None
                ) -> tuple[MetricInfo, ...]:
        """The metrics of the base ``description`` (named after its actuators and joints); the
        joint reactions only with ``reactions = true``, the stiffness metrics only with
        ``stiffness = true``, the workspace's least measure only with ``workspace_measure = true``
        (each the default) in ``[motion]``."""
        acts, joints, direct, limited, rated = _names(self.raw if description is None else description)
        out = [
            MetricInfo("gci", "-", "(1/T) int mu(t) dt, mu = the direct singularity measure where there are as "
                                   "many actuators as task coordinates, else the inverse one"),
            MetricInfo("min_inverse_measure", "-", "min over samples of sigma_min/sigma_max of the scaled "
                                                   "[Phi_q; tau_q] (serial / type I singularity at 0)"),
        ]
        if direct:  # defined with as many actuators as task coordinates only
            out.append(MetricInfo("min_direct_measure", "-", "min over samples of sigma_min/sigma_max of the scaled "
                                                             "[Phi_q; E_a] (parallel / type II singularity at 0)"))
        out.append(MetricInfo("min_constraint_measure", "-", "min over samples of sigma_min/sigma_max of the scaled "
                                                             "Phi_q (constraint singularity at 0)"))
        for unit in sorted({u for _, u in acts}):
            kind = "force" if unit == "N" else "torque"
            out.append(MetricInfo(f"peak_effort_{unit}", unit.replace("Nm", "N m"),
                                  f"max over samples and actuators with a {kind} of |u_k|"))
        for name, unit in acts:
            shown = unit.replace("Nm", "N m")
            sp = _speed_unit(unit)
            out += [
                MetricInfo(f"peak_effort_{name}_{unit}", shown, f"max over samples of |u| of actuator {name}"),
                MetricInfo(f"rms_effort_{name}_{unit}", shown, f"sqrt((1/T) int u^2 dt) of actuator {name}"),
                MetricInfo(f"peak_speed_{name}_{sp}", sp.replace("_", "/"), f"max over samples of |s_dot| of {name}"),
                MetricInfo(f"rms_speed_{name}_{sp}", sp.replace("_", "/"), f"sqrt((1/T) int s_dot^2 dt) of {name}"),
            ]
        out += [
            MetricInfo("peak_power_W", "W", "max over samples of sum_k u_k s_dot_k"),
            MetricInfo("motor_energy_per_cycle_J", "J", "int sum_k |u_k s_dot_k| dt over the motion"),
        ]
        if limited:
            out.append(MetricInfo("joint_limit_margin", "-", "min over samples and limited joints of min(q - lo, "
                                                             "hi - q) / (hi - lo) (negative: beyond a limit)"))
        if rated:
            out.append(MetricInfo("peak_effort_over_rated", "-", "max over samples and rated drives of |motor "
                                                                 "effort| / rated effort (above 1: beyond it)"))
        if options.get("stiffness", True) is True:
            have = _stiffness_metrics(self.raw if description is None else description)
            out += [MetricInfo(name, unit, text) for name, unit, text in _STIFFNESS_METRICS if name in have]
        if options.get("workspace_grid"):
            name, unit = _workspace_size_name(self.raw if description is None else description,
                                              str(options["workspace_grid"]))
            out += [MetricInfo(name, unit, "the size of the workspace on [motion] workspace_grid (inside poses times "
                                           "the grid cell, or from the boundary's crossings of the grid's edges with "
                                           "workspace_refine; docs/workspace.md)"),
                    MetricInfo(name.replace("workspace_size_", "workspace_size_error_", 1), unit,
                               "the size's error estimate (docs/workspace.md, half the cells the boundary "
                               "crosses, or the refined size's)"),
                    MetricInfo("workspace_inside_share", "-", "the share of the grid's poses inside the workspace"),
                    MetricInfo("workspace_at_grid_edge", "-",
                               "1 where an inside pose lies on the grid's edge (the workspace may go on beyond "
                               "the grid: its size is a lower bound), else 0")]
            if options.get("workspace_measure", True) is True:
                out.append(MetricInfo("workspace_min_measure", "-",
                                      "the least singularity measure over the inside poses"))
        if isinstance(options.get("requirements"), dict):
            out.append(MetricInfo("required_region_coverage", "-",
                                  "the share of the [requirements] grid's poses inside the workspace (reached within "
                                  "the joint limits, every singularity measure at least singularity_threshold)"))
        if options.get("reactions", True) is True:
            out.append(MetricInfo("friction_energy_per_cycle_J", "J",
                                  "int (power dissipated by the joints' friction) dt over the motion"))
            for j in joints:
                out += [MetricInfo(f"peak_force_{j}_N", "N", f"max over samples of |f| at joint {j}"),
                        MetricInfo(f"peak_moment_{j}_Nm", "N m",
                                   f"max over samples of |m| at joint {j}, about the joint point")]
        return tuple(out)

    def prepare(self, description: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path
                ) -> DescribedSweepContext:
        """Check the ``[motion]`` options; read the motion file, if any, against the base
        description's task; with reactions, an over-constrained base needs its bodies' sections
        and materials (one line naming what is missing, or ``reactions = false``)."""

        opt = validate(_Motion, dict(options), "[motion]")
        if opt.workspace_refine and (opt.workspace_grid is None or opt.workspace_orientation_range is not None):
            raise ParameterError("[motion] workspace_refine: needs workspace_grid, and not workspace_orientation_range "
                                 "(docs/workspace.md, refined size)")
        try:  # the structure every design of the same structure reuses, and load_mechanism's model
            desc = load_description(copy.deepcopy(dict(description)))
            template = model_structure(structure_key(desc))
            model = compile_with(template, desc)
        except PkmdynError as exc:
            raise ParameterError(f"base description: {exc}") from None
        motion = None
        if opt.file is not None:
            path = Path(opt.file) if Path(opt.file).is_absolute() else base_dir / opt.file
            motion = read_task_motion(model, path)
        if opt.reactions:

            mo = motion if motion is not None else default_motion(model)
            try:
                kin = solve_kinematics(model, mo.x[:1], mo.xd[:1], mo.xdd[:1], mo.t[:1])
                joint_reactions(model, kin, named={k: v[:1] for k, v in mo.loads.items()})
            except ComplianceDataMissing as exc:
                raise ComplianceDataMissing(f"[motion] reactions: {exc}; or set reactions = false") from None
            except PkmdynError:
                pass  # the base design's own trouble is its row's, not the sweep's
        ws = None
        if opt.workspace_grid is not None:
            try:  # refused here, once, when it names no task coordinate
                parse_grid(model, opt.workspace_grid, max_axes=3)
                parse_pose(model, opt.workspace_pose)
                if opt.workspace_orientation_range is not None:
                    parse_ranges(model, opt.workspace_orientation_range)
            except ParameterError as exc:
                raise ParameterError(f"[motion] workspace_grid/workspace_pose/workspace_orientation_range: "
                                     f"{exc}") from None
            ws = (opt.workspace_grid, opt.workspace_pose, opt.workspace_orientation_range)
        req = None
        if opt.requirements is not None:
            try:
                parse_grid(model, opt.requirements.grid, max_axes=3)
                parse_pose(model, opt.requirements.pose)
            except ParameterError as exc:
                raise ParameterError(f"[requirements] {exc}") from None
            req = (opt.requirements.grid, opt.requirements.pose, None)
        return DescribedSweepContext(motion=motion, threshold=opt.singularity_threshold, reactions=opt.reactions,
                                     stiffness=tuple(_stiffness_metrics(description)) if opt.stiffness else (),
                                     workspace=ws, required=req, workspace_measure=opt.workspace_measure,
                                     workspace_refine=opt.workspace_refine, template=template)

    def evaluate(self, descriptions: Sequence[Mapping[str, Any]], context: DescribedSweepContext
                 ) -> list[DesignOutcome]:
        """Each design of a batch by itself (:func:`evaluate_one`): rows never depend on the batch."""
        with np.errstate(all="ignore"):  # a non-finite metric becomes the status "nonfinite", not a warning
            return [evaluate_one(d, context) for d in descriptions]


#: the stiffness metrics (docs/stiffness.md) of a description with a compliance source
_STIFFNESS_METRICS = (
    ("min_stiffness_N_m", "N/m", "min over samples of the task point's translational stiffness in its worst "
                                 "direction with the actuators locked, 1/lambda_max(C_ff)"),
    ("min_rot_stiffness_Nm_rad", "N m/rad", "min over samples of the task body's rotational stiffness in its "
                                            "worst direction, 1/lambda_max(C_mm)"),
    ("lowest_frequency_Hz", "Hz", "min over samples of the lowest natural frequency with the actuators locked"),
)


def _stiffness_metrics(description: Mapping[str, Any]) -> list[str]:
    """The stiffness metrics of a description: none without a compliance source; those finite
    at its reference pose (a Delta's platform with rigid rods does not turn: no rotational one)."""

    try:
        model = load_mechanism(copy.deepcopy(dict(description)))
        if not any(compliance_sources(model).values()):
            return []
        st = stiffness(model, solve_kinematics(model, reference_task(model)[None]))
    except PkmdynError:
        return []
    names = ["lowest_frequency_Hz"]
    if np.isfinite(st.min_stiffness[0]):
        names.append("min_stiffness_N_m")
    if np.isfinite(st.min_rot_stiffness[0]):
        names.append("min_rot_stiffness_Nm_rad")
    return names


def _workspace_size_name(source: Any, grid: str) -> tuple[str, str]:
    """The workspace-size metric's name and unit for a grid of task coordinates
    (:func:`pkmdyn.multibody.analyses.workspace.size_unit`: ``workspace_size_m3`` ...); ``source`` a model or a description."""

    model = source if hasattr(source, "task_units") else None
    if model is None:
        try:
            model = load_mechanism(copy.deepcopy(dict(source)))
        except PkmdynError as exc:
            raise ParameterError(f"[motion] workspace_grid: the base description: {exc}") from None
    try:
        axes = parse_grid(model, grid, max_axes=3)
    except ParameterError as exc:
        raise ParameterError(f"[motion] workspace_grid: {exc}") from None
    unit = size_unit([model.task_units[i] for i, _ in axes])
    return f"workspace_size_{unit}", unit.replace("_", " ")


def _on_grid(model: Any, spec: tuple[str, str, str | None], threshold: float, least: bool, refine: int = 0) -> Any:
    """The workspace of ``model`` on the grid, held pose and orientation range ``spec``
    (``--grid``, ``--pose``, ``--orientation-range`` syntax), with its size (from the boundary's
    crossings of the grid's edges where ``refine``) and least measure (``least``; else only its
    size: :func:`pkmdyn.multibody.analyses.workspace.workspace`, ``measures``, ``refine``)."""

    ranges = None if spec[2] is None else parse_ranges(model, spec[2])
    return workspace(model, parse_grid(model, spec[0], max_axes=3), parse_pose(model, spec[1]), threshold,
                     ranges=ranges, measures="least" if least else "none", refine=refine)


def design_model(description: Mapping[str, Any], ctx: DescribedSweepContext) -> Any:
    """The compiled model of one design: :func:`pkmdyn.multibody.load_mechanism`'s, to the last
    bit. The description is read and validated in full (every error as ``load_mechanism`` says
    it); where it has the structure of the base description (``ctx.template``: the same bodies,
    joints and types, actuators, cut joints, task and loads), the compiled structure is reused
    and only the numbers, the solver's rows and the explicit legs are computed, else (a swept
    value that changes the structure, e.g. a leg count) it is compiled in full
    (:func:`pkmdyn.multibody.model.compiler.compile_with`)."""

    return compile_with(ctx.template, load_description(copy.deepcopy(dict(description))))


def evaluate_one(description: Mapping[str, Any], ctx: DescribedSweepContext) -> DesignOutcome:
    """One design: model (:func:`design_model`) -> motion -> kinematics and singularity measures
    -> efforts (and every joint reaction with the friction) -> metrics."""
    try:
        model = design_model(description, ctx)
        motion = ctx.motion if ctx.motion is not None else default_motion(model)
    except PkmdynError as exc:
        return DesignOutcome("invalid", str(exc))
    return evaluate_model(model, motion, ctx)[0]


@dataclass(frozen=True)
class DesignState:
    """What :func:`evaluate_model` computed for one design, for metrics of a machine's own
    (:class:`GeneratedSweep`): the compiled ``model``, the ``motion`` it performed, its
    kinematics ``kin`` (None: not solved), the actuated joints' efforts ``u (n, na)`` and the
    joint reactions ``reactions`` (:class:`pkmdyn.multibody.dynamics.newton_euler.JointReactions`; None
    where not computed)."""

    model: Any
    motion: Any
    kin: Any = None
    u: Array | None = None
    reactions: Any = None


def evaluate_model(model: Any, motion: Any, ctx: DescribedSweepContext) -> tuple[DesignOutcome, DesignState]:
    """The evaluation of one compiled design along ``motion``: kinematics (``unreachable``,
    ``singular``), the plausibility limits (``limit``), the singularity measures (``singular``
    below ``ctx.threshold``; with ``ctx.measures``), the efforts with every joint reaction and the
    friction, the metrics (the efforts' with ``ctx.efforts``); with what was computed on the way
    (:class:`DesignState`)."""

    state = DesignState(model, motion)
    try:
        kin = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
    except UnreachablePoseError as exc:
        return DesignOutcome("unreachable", str(exc)), state
    except SingularityError as exc:
        return DesignOutcome("singular", str(exc)), state
    except PkmdynError as exc:
        return DesignOutcome("invalid", str(exc)), state
    state = DesignState(model, motion, kin)

    try:  # the plausibility limits that pkmdyn run holds a motion to (its [limits], the drives' motors)
        lim = effective_limits(model)
        check_task_rates(model, kin.t, motion.xd, motion.xdd, lim)
        check_actuator_rates(model, kin.t, kin.act_qd, kin.act_qdd, lim)
    except LimitError as exc:
        return DesignOutcome("limit", str(exc)), state
    t = motion.t
    direct = model.na == model.nt
    m: dict[str, float] = {}
    # redundant actuation: the tall direct measure at every sample (by its SVD), for the
    # conditioning index and the least measures both
    tall = singularity_measures(model, kin.q, only="direct").direct if (
        model.na > model.nt and (ctx.gci or ctx.measures)) else None
    if ctx.gci and tall is not None:
        m["gci"] = _mean(tall, t)
    if ctx.gci and tall is None:
        # the conditioning index's measure at every sample, the least of each from proven brackets
        # (the decompositions only where a sample can hold the least: the same values to the bit)
        mu = getattr(singularity_measures(model, kin.q, only="direct" if direct else "inverse"),
                     "direct" if direct else "inverse")
        m["gci"] = _mean(mu, t)
    # the least measures: proven brackets, the decompositions only where a sample can hold the least
    least = least_measures(model, kin.q) if ctx.measures else None
    if least is not None and tall is not None:
        least = {**least, "direct": float(np.min(tall))}
        direct = True
    if least is not None:
        m["min_inverse_measure"] = least["inverse"]
        m["min_constraint_measure"] = least["constraint"]
        if direct:
            m["min_direct_measure"] = least["direct"]
    if least is not None and not np.minimum(least["inverse"], least["direct"] if direct else np.inf) >= ctx.threshold:
        # (NaN: singular)
        sm = singularity_measures(model, kin.q)  # the first sample where the worst is least, named
        worst = np.minimum(sm.inverse, sm.direct) if direct else sm.inverse
        k = int(np.argmin(worst))
        return DesignOutcome("singular", f"t = {t[k]:.6g} s (sample {k + 1}): the singularity measure "
                                         f"{worst[k]:.3g} is below the threshold {ctx.threshold:g}", m), state
    try:
        if ctx.reactions:
            reac = joint_reactions(model, kin, named=motion.loads)
            u = reac.u
        else:
            u = inverse_dynamics(model, kin, named=motion.loads).u
    except SingularityError as exc:
        return DesignOutcome("singular", str(exc), m), state
    except PkmdynError as exc:  # friction that locks the mechanism, a load it cannot carry
        return DesignOutcome("limit", str(exc), m), state
    state = DesignState(model, motion, kin, u, reac if ctx.reactions else None)
    sd = kin.act_qd
    power = u * sd
    if ctx.efforts:
        units = [effort_unit(model, i) for i in range(model.na)]
        for unit in set(units):
            cols = [i for i, x in enumerate(units) if x == unit]
            m[f"peak_effort_{unit}"] = float(np.abs(u[:, cols]).max())
        for i, (name, unit) in enumerate(zip(model.actuator_names, units)):
            sp = _speed_unit(unit)
            m[f"peak_effort_{name}_{unit}"] = float(np.abs(u[:, i]).max())
            m[f"rms_effort_{name}_{unit}"] = math.sqrt(_mean(u[:, i] ** 2, t))
            m[f"peak_speed_{name}_{sp}"] = float(np.abs(sd[:, i]).max())
            m[f"rms_speed_{name}_{sp}"] = math.sqrt(_mean(sd[:, i] ** 2, t))
    wanted = ctx.stiffness
    if wanted:
        try:
            st = stiffness(model, kin)
        except SingularityError as exc:
            return DesignOutcome("singular", str(exc), m), state
        except PkmdynError as exc:
            return DesignOutcome("invalid", str(exc), m), state
        values = {"min_stiffness_N_m": st.min_stiffness.min(), "min_rot_stiffness_Nm_rad": st.min_rot_stiffness.min(),
                  "lowest_frequency_Hz": st.frequencies[:, 0].min()}
        m.update({k: float(values[k]) for k in wanted})
    grids = {}
    for key, spec in (("workspace", ctx.workspace), ("required", ctx.required)):
        if spec is not None:
            try:
                grids[key] = _on_grid(model, spec, ctx.threshold, key == "workspace" and ctx.workspace_measure,
                                      ctx.workspace_refine if key == "workspace" else 0)
            except PkmdynError as exc:
                return DesignOutcome("invalid", str(exc), m), state
    if "workspace" in grids:
        ws = grids["workspace"]
        size_name = _workspace_size_name(model, ctx.workspace[0])[0]  # type: ignore[index]
        m[size_name] = ws.size
        m[size_name.replace("workspace_size_", "workspace_size_error_", 1)] = float(ws.size_error)
        m["workspace_inside_share"] = float(ws.inside.mean())
        m["workspace_at_grid_edge"] = 1.0 if edges_reached(model, ws) else 0.0
        if not ws.inside.any():
            return DesignOutcome("unreachable", "no pose of [motion] workspace_grid is inside the workspace", m), state
        if ctx.workspace_measure:
            m["workspace_min_measure"] = float(ws.least_measure)
    if "required" in grids:
        m["required_region_coverage"] = float(grids["required"].inside.mean())
    if ctx.efforts:
        m.update(_limit_metrics(model, kin, u))
        m["peak_power_W"] = float(power.sum(axis=1).max())
        m["motor_energy_per_cycle_J"] = float(time_integral(np.abs(power).sum(axis=1), t))
    if ctx.reactions and ctx.efforts:
        m["friction_energy_per_cycle_J"] = float(time_integral(reac.dissipation, t))
    if ctx.reactions:
        force = np.linalg.norm(reac.joint_force, axis=-1).max(axis=0)
        moment = np.linalg.norm(reac.joint_moment, axis=-1).max(axis=0)
        for j, name in enumerate(model.joint_names):
            m[f"peak_force_{name}_N"] = float(force[j])
            m[f"peak_moment_{name}_Nm"] = float(moment[j])
    return DesignOutcome("ok", "", m), state


# ----------------------------------------------------------------------------- generated descriptions
@dataclass(frozen=True)
class GeneratedMotion:
    """What a machine's description generator says of the motion (its ``motion`` hook): the
    task motion every design performs (``motion``, a :class:`pkmdyn.multibody.TaskMotion` in
    the generated description's task order, its named loads included), the threshold on the
    engine's singularity measures (``threshold``; 0: only a singular sample), the machine's
    own design-independent data (``data``, handed back to its ``design_metrics``; picklable) and
    whether the engine computes its least singularity measures (``measures``: the metrics
    ``min_*_measure`` and the status on ``threshold``; false: a machine whose status comes from
    a measure of its own, the largest stage of a design spared)."""

    motion: Any
    threshold: float = 0.0
    data: Any = None
    measures: bool = True


@dataclass(frozen=True)
class GeneratedSweepContext:
    """The engine's context (:class:`DescribedSweepContext`: the motion, the compiled structure
    of the base design's description) and the machine's own data."""

    engine: DescribedSweepContext
    data: Any = None


@dataclass(frozen=True, eq=False)
class GeneratedSweep:
    """The sweep adapter of a machine that generates its mechanism description from a parameter
    file of its own: the designs vary that file's keys, and each design is evaluated by the
    engine (:func:`evaluate_model`) on the description generated from it.

    ``module``: the import name of the machine's generator module, which provides

    - ``NAME``: the machine's name;
    - ``default_params() -> dict``: the built-in parameter file;
    - ``check_params(params, source)``: the parameter file's schema (its own validation; a
      :class:`~pkmdyn.errors.PkmdynError` naming the key);
    - ``description(params) -> dict``: the mechanism description of a parameter file (raises
      the schema's error for an invalid one);
    - ``motion(params, options, base_dir) -> GeneratedMotion``: the ``[motion]`` options
      checked against the base parameters, the motion every design performs;
    - ``metrics(options, engine) -> tuple[MetricInfo, ...]``: the machine's columns, given the
      engine's (``engine``: those of the base design's description with every joint reaction);
    - ``design_metrics(params, outcome, state, data) -> DesignOutcome``: one design's outcome
      in the machine's terms, from the engine's ``outcome`` and what it computed (``state``,
      :class:`DesignState`).

    The adapter holds only the module's name, so it travels to every worker as it is."""

    module: str
    NAME: str = ""

    @classmethod
    def from_module(cls, module: str) -> GeneratedSweep:
        return cls(module, importlib.import_module(module).NAME)

    @property
    def hooks(self) -> Any:
        return importlib.import_module(self.module)

    def base_description(self, params_path: Path | None) -> dict[str, Any]:
        """The parameter file to vary (``None``: the machine's built-in one) as a dict."""
        return self.hooks.default_params() if params_path is None else read_toml(params_path)

    def check_description(self, description: Mapping[str, Any], source: str) -> None:
        """The machine's own validation of a parameter file."""
        self.hooks.check_params(dict(description), source)

    def _engine_options(self) -> dict[str, Any]:
        return {"reactions": True, "stiffness": False}

    def metrics(self, options: Mapping[str, Any], description: Mapping[str, Any] | None = None
                ) -> tuple[MetricInfo, ...]:
        """The machine's metrics (its ``metrics`` hook, given the engine's metrics of the
        description generated from ``description``, the base parameter file)."""
        params = self.hooks.default_params() if description is None else dict(description)
        try:
            desc = self.hooks.description(params)
        except PkmdynError:  # an invalid base is refused with its reason by prepare
            desc = self.hooks.description(self.hooks.default_params())
        engine = DescribedSweep(Path("."), desc, self.NAME).metrics(self._engine_options(), desc)
        return tuple(self.hooks.metrics(options, tuple(m for m in engine if m.name != "gci")))

    def prepare(self, description: Mapping[str, Any], options: Mapping[str, Any], base_dir: Path
                ) -> GeneratedSweepContext:
        """The machine's motion (``motion`` hook, its ``[motion]`` options checked), and the
        structure of the base design's description compiled once."""

        params = dict(description)
        gm = self.hooks.motion(params, options, base_dir)
        try:
            desc = load_description(self.hooks.description(copy.deepcopy(params)))
            template = model_structure(structure_key(desc))
        except PkmdynError as exc:
            raise ParameterError(f"base parameters: {exc}") from None
        engine = DescribedSweepContext(motion=gm.motion, threshold=gm.threshold, reactions=True, template=template,
                                       gci=False, measures=gm.measures, efforts=False)
        return GeneratedSweepContext(engine, gm.data)

    def evaluate(self, descriptions: Sequence[Mapping[str, Any]], context: GeneratedSweepContext
                 ) -> list[DesignOutcome]:
        """Each design of a batch by itself: rows never depend on the batch."""
        hooks = self.hooks
        with np.errstate(all="ignore"):  # a non-finite metric becomes the status "nonfinite", not a warning
            return [_evaluate_generated(hooks, dict(d), context) for d in descriptions]


def _evaluate_generated(hooks: Any, params: dict[str, Any], ctx: GeneratedSweepContext) -> DesignOutcome:
    """One design of a generated description: parameters -> description -> model (the base's
    structure reused) -> the engine's evaluation -> the machine's outcome."""

    try:
        model = compile_with(ctx.engine.template, load_description(hooks.description(params)))
    except PkmdynError as exc:
        return DesignOutcome("invalid", str(exc))
    outcome, state = evaluate_model(model, ctx.engine.motion, ctx.engine)
    return hooks.design_metrics(params, outcome, state, ctx.data)

"""The run of a described mechanism: a task motion -> kinematics, efforts, every joint reaction,
the drives and the effort split -> files, streamed chunk by chunk.

``run_mechanism`` takes the motion in chunks (:data:`CHUNK` samples; a :class:`~pkmdyn.multibody.kinematics.motion.TaskMotion`
or a :class:`~pkmdyn.multibody.kinematics.motion.PeriodicMotion` made as it goes), so that memory does not grow with
the run: each chunk is solved (warm-started from the chunk before: its last sample is solved
again as the chunk's first row, so that a chunked run follows the same solution as one
solved whole), its rates checked against the plausibility limits
(:mod:`pkmdyn.multibody.dynamics.actuators`), its efforts and reactions computed (:func:`pkmdyn.multibody.dynamics.newton_euler.joint_reactions`,
load-dependent friction iterated per chunk, messages naming the sample of the whole run), its
rows appended to ``results.csv`` (or ``.parquet``), and the summary's extremes kept on the fly.
``bodies.npz`` holds the first ``max_body_samples`` samples (every sample of a run up to that
length), the report's plots and animation a window of them (the first cycle of a repeated
default motion). The files are written into a temporary
folder beside ``--out`` and moved into place only when the whole run succeeded
(:func:`pkmdyn.report.write_output`); formats: ``docs/mechanism_format.md``, "Outputs".
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import MotionError, ParameterError, PkmdynError, at_sample
from ..io import (
    NpzWriter,
    check_table_format,
    note_table_size,
    open_table_writer,
    write_json,
)
from ..multibody.columns import (
    actuator_effort_column,
    bodies_arrays,
    deflection_columns,
    effort_columns,
    joint_effort_column,
    model_summary,
    pose_column_names,
    pose_columns,
    results_column_names,
    results_columns,
)
from ..multibody.description.schema import LIMIT_KEYS
from ..multibody.dynamics.actuators import (
    check_actuator_rates,
    check_task_rates,
    effective_limits,
    motor_effort_column,
)
from ..multibody.dynamics.newton_euler import effort_unit, joint_reactions, load_forces
from ..multibody.dynamics.compliance.reactions import ComplianceDataMissing
from ..multibody.kinematics.direct import task_motion
from ..multibody.kinematics.inverse import (
    MechanismKinematics,
    joint_coordinates,
    limit_hit,
    limit_line,
    limited_joints,
    solve_kinematics,
)
from ..multibody.kinematics.singularity.measures import least_measures
from ..multibody.kinematics.motion import (
    motion_columns,
    periodic_motion,
    read_actuator_motion,
    read_task_motion,
    repeated_motion,
    task_columns,
)
from ..multibody.model.compiler import MechanismModel
from ..multibody.scene import frame_indices_of, mechanism_scene
from ..params_util import check_limit, parse_limit_options
from ..profiles._columns import check_smoothing
from ..report import Curve, Curves, Extremes, FramePicker, Output, Report, TimePlot, write_output
from ..simulate.passive import driven_motion, passive_motion
from ._files import JobResult, prepare

__all__ = ["job", "run_mechanism", "run_report", "report_columns", "CHUNK"]

Array = NDArray[np.float64]

#: samples per chunk of a run (some 40 MiB of working set for a Stewart platform)
CHUNK = 1024
#: beyond the bodies' window, the singularity measures of every this many samples
SINGULARITY_STRIDE = 10


def _motor_arrays(model: MechanismModel, reac: Any) -> dict[str, Array]:
    """``bodies.npz`` arrays of the split's friction: ``friction_share (n, na, nj)`` each joint's
    friction share of every actuator's effort (motor side for a drive, as the columns)."""
    if reac.shares is None:
        return {}
    return {"friction_share": reac.shares.friction / model.drive_ratio[None, :, None]}


def _report_groups(model: MechanismModel) -> list[tuple[str, str, list[str]]]:
    """The report's plots of the actuators: ``(title, y label, columns)``."""
    joints = [motion_columns(a, u) for a, u in zip(model.actuator_names, model.actuator_units)]
    groups = [("Actuator coordinates", "actuator coordinates [SI]", [c[0] for c in joints]),
              ("Actuator rates", "actuator rates [SI]", [c[1] for c in joints]),
              ("Actuator efforts", "actuator efforts [SI]", [joint_effort_column(model, i) for i in range(model.na)])]
    motors = [motor_effort_column(model, i) for i, d in enumerate(model.drive_name) if d is not None]
    if motors:
        groups.append(("Motor efforts", "motor effort [N m or N]", motors))
    return groups


def _pose_groups(model: MechanismModel) -> list[tuple[str, str, list[str]]]:
    """The report's plots of the task body's and the outputs' poses (:func:`pose_columns`)."""
    names = pose_column_names(model)
    return [("Poses: positions (task body and outputs)", "position [m]", [c for c in names if c.endswith("_m")]),
            ("Poses: Euler angles (task body and outputs)", f"angle ({model.euler_sequence}) [rad]",
             [c for c in names if c.endswith("_rad")])]


def report_columns(model: MechanismModel) -> list[str]:
    """The results columns a run's report plots (:func:`run_report`)."""
    pos, _, _ = task_columns(model)
    groups = _report_groups(model) + _pose_groups(model)
    return ["t_s", *pos, *(c for _, _, cols in groups for c in cols)]


def run_report(model: MechanismModel, cols: dict[str, Array], frames: dict[str, Array], description_text: str,
               samples: int | None = None) -> Report:
    """The content of a run's ``report.html`` (:mod:`pkmdyn.report`): the mechanism drawn at the animation's
    samples ``frames`` (``t``, ``joint_point``: each body through its joint centres, actuated
    joints as chains coloured by effort), the task and actuator coordinates, rates and efforts
    against time from the results columns ``cols`` (the plots' window of the run; ``samples``:
    the run's length when the window is shorter)."""
    t = cols["t_s"]
    pos, _, _ = task_columns(model)
    plots = [TimePlot("Task coordinates", "task coordinate [m or rad]", t, tuple(Curve(c, cols[c]) for c in pos))]
    for title, label, group in _report_groups(model) + _pose_groups(model):
        plots.append(TimePlot(title, label, t, tuple(Curve(c, cols[c]) for c in group)))
    idx = frame_indices_of(t, frames["t"])
    efforts = {}
    for i, name in enumerate(model.actuator_names):
        efforts[name] = (cols[joint_effort_column(model, i)][idx], f"{name} effort", effort_unit(model, i))
    scene = mechanism_scene(model, frames["t"], frames["joint_point"], efforts)
    notes = [f"mechanism: {model.name}" + (f" ({model.source})" if model.source else "")]
    if samples is not None and samples > t.shape[0]:
        notes.append(f"plots and animation: the first {t.shape[0]} of {samples} samples (results hold every sample)")
    return Report(f"{model.name}: pkmdyn run", scene=scene, plots=plots, parameters=description_text, notes=notes,
                  scene_note="Joint centres as in bodies.npz (joint_point); actuated joints drawn as chains.",
                  samples=t.shape[0])



class _Summary:
    """The summary's extremes, kept chunk by chunk (:class:`pkmdyn.report.Extremes`)."""

    def __init__(self, model: MechanismModel) -> None:
        self.model = model
        self.ext = Extremes()
        self.sing = {"inverse": np.inf, "direct": np.inf, "constraint": np.inf}
        self.direct_nan = True
        self.reactions: dict[str, Any] = {}

    def add(self, start: int, kin: MechanismKinematics, sm: dict[str, float] | None, reac: Any,
            cols: dict[str, Array]) -> None:
        model, e = self.model, self.ext
        e.max("residual", kin.residual.max())
        if sm is not None:  # (None: a chunk beyond the bodies' window without a sample of the stride)
            for key in ("inverse", "constraint"):
                self.sing[key] = min(self.sing[key], sm[key])
            if not np.isnan(sm["direct"]):
                self.direct_nan = False
                self.sing["direct"] = min(self.sing["direct"], sm["direct"])
        e.max("eq_residual", reac.residual.max())
        e.max("iterations", int(reac.iterations))
        if reac.holding is not None and reac.holding.size:
            e.max("holding", np.abs(reac.holding).max())
        if reac.unactuated is not None:
            e.max("unactuated", reac.unactuated.max(initial=0.0))
        e.max("joint_effort", np.abs(reac.u).max(axis=0))
        for i, name in enumerate(model.drive_name):
            tau = cols[actuator_effort_column(model, i)]
            e.max(f"motor_effort_{i}", np.abs(tau).max())
            e.max(f"motor_speed_{i}", np.abs(kin.act_qd[:, i] * model.drive_ratio[i]).max())
            lim = model.drive_max_effort[i]
            if e.get("beyond_effort") is None and np.isfinite(lim):
                bad = np.flatnonzero(~(np.abs(tau) <= lim))
                if bad.size:
                    s = int(bad[0])
                    u = "N m" if model.motor_units[i] == "rad" else "N"
                    e.first("beyond_effort", f"{at_sample(s, kin.t, start)}: actuator {name!r} needs {tau[s]:.4g} {u}, "
                                             f"beyond its rated {lim:g} {u}")

    def value(self, key: str) -> float:
        """The extreme kept under ``key`` as a number (0 where nothing was kept)."""
        v = self.ext.get(key)
        return 0.0 if v is None else float(v)

    def actuators(self) -> list[dict[str, Any]]:
        model = self.model
        out = []
        for i, joint in enumerate(model.actuator_names):
            spec = model.drive_specs[i] if model.drive_specs else None
            entry: dict[str, Any] = {"joint": joint, "max_abs_joint_effort_SI": float(self.ext["joint_effort"][i])}
            if spec is not None:
                entry.update(name=spec.name, kind=spec.kind, ratio=float(spec.ratio),
                             max_abs_motor_effort_SI=self.value(f"motor_effort_{i}"),
                             max_abs_motor_speed_SI=self.value(f"motor_speed_{i}"),
                             rated_effort_SI=None if not np.isfinite(spec.max_effort) else float(spec.max_effort))
            out.append(entry)
        return out


def _simulated(model: MechanismModel, t: Array, simulate: Callable[..., Any]) -> Any:
    """An under-actuated mechanism's task motion at the times ``t``, its passive freedoms
    simulated by ``simulate(progress=...)`` (:func:`passive_motion` along an actuator motion,
    :func:`driven_motion` along a task motion's actuated joints), with a progress bar in
    simulated seconds on a terminal."""
    from tqdm import tqdm

    span = float(t[-1] - t[0])
    with tqdm(total=span, desc=f"{model.name}: the passive freedoms simulated", unit="s", leave=False,
              disable=None, bar_format="{l_bar}{bar}| {n:.3g}/{total:.3g} s [{elapsed}<{remaining}]") as bar:
        def advance(tau: float) -> None:
            bar.update(max(0.0, min(tau - float(t[0]), span) - bar.n))

        return simulate(progress=advance)


def run_mechanism(model: MechanismModel, motion: Any, out_dir: str | Path, inputs: Any = (),
                  report: Callable[[dict[str, Path]], None] | None = None, description_text: str = "",
                  unique_reactions: bool = False, fmt: str = "csv", limits: dict | None = None,
                  progress: bool = False, chunk: int = CHUNK, plot_window: int | None = None,
                  deflection: bool = False) -> JobResult:
    """Kinematics, efforts and every joint reaction of ``model`` along ``motion`` (a
    :class:`~pkmdyn.multibody.kinematics.motion.TaskMotion` or :class:`~pkmdyn.multibody.kinematics.motion.PeriodicMotion`), written into ``out_dir``
    under the output rule (``inputs`` the files the run read: nothing is written when anything
    fails), streamed chunk by chunk (module docstring).

    ``fmt``: ``"csv"`` or ``"parquet"`` for the results table; ``limits``: overrides of the
    description's ``[limits]`` (``--limit``); ``progress``: a progress bar on a terminal;
    ``plot_window``: the samples the report's plots and animation cover (default: the first
    ``max_body_samples``). An over-constrained mechanism needs the section and material that
    make its reactions unique: without them its run writes the minimum-norm reactions flagged
    ``"unique": false`` (kinematics and efforts are unique all the same), or, with
    ``unique_reactions``, is refused. ``deflection``: the task coordinates' elastic deflection
    under the run's loads in the results table (:func:`deflection_columns`; the description
    needs a compliance source, docs/stiffness.md). ``report`` is called with the files' final paths before
    they move into place. Returns the result: the files (label -> path), the summary ``summary.json``
    holds and the report's content."""
    from tqdm import tqdm

    if isinstance(chunk, bool) or not isinstance(chunk, int) or chunk < 1:
        raise PkmdynError(f"chunk: must be an integer >= 1, got {chunk!r}")
    check_table_format(fmt)
    lim = effective_limits(model, limits)
    n = len(motion)
    if n < 1:
        raise PkmdynError("the motion has no samples")
    check_limit(n, int(lim["max_samples"]), "motion: samples", "max_samples", file="the description")
    note_table_size(n, len(results_column_names(model, deflection)), fmt)
    body_rows = min(n, int(lim["max_body_samples"]))
    window = min(body_rows, n if plot_window is None else int(plot_window))
    limited = limited_joints(model)
    plotted = report_columns(model)

    def make(out: Path) -> Output:
        summ = _Summary(model)
        prev_coords: Array | None = None
        overconstrained = "compliance"
        reason = ""
        frames = FramePicker(window)
        curves = Curves(window, raw_max=None)  # every sample of the plots' window
        files = {"results": out / ("results.csv" if fmt == "csv" else "results.parquet"), "model": out / "model.json",
                 "bodies": out / "bodies.npz"}
        write_json(files["model"], model_summary(model))
        npz = NpzWriter(files["bodies"], body_rows)
        try:
            npz.put("body_names", np.array(model.body_names))
            npz.put("joint_names", np.array(model.joint_names))
            npz.put("coordinate_joints", np.array([model.joint_names[j] for j in model.coord_joint]))
            q_prev: Array | None = None
            bar = tqdm(total=n, desc=f"{model.name}: kinematics, efforts, reactions", unit="sample",
                       disable=not progress or None, leave=False, unit_scale=True)
            with open_table_writer(files["results"], fmt) as writer, bar:
                for start in range(0, n, chunk):
                    stop = min(n, start + chunk)
                    # the chunk with the sample before it: solved again as its first row, from which
                    # the chunk's first sample is predicted as within a run solved whole
                    lead = 1 if start > 0 else 0
                    m = motion.chunk(start - lead, stop)
                    check_task_rates(model, m.t, m.xd, m.xdd, lim, start - lead)
                    kin = solve_kinematics(model, m.x, m.xd, m.xdd, m.t, q_start=q_prev, sample_offset=start - lead)
                    q_prev = kin.q[-1].copy()
                    if lead:
                        kin = kin.rows(1)
                        m = m.chunk(1, len(m))
                    check_actuator_rates(model, kin.t, kin.act_qd, kin.act_qdd, lim, start)
                    if limited:
                        c = joint_coordinates(model, kin, limited, previous=prev_coords)
                        prev_coords = c[-1]
                        hit = limit_hit(model, c, limited) if summ.ext.get("limit_first") is None else None
                        if hit is not None:
                            s, k = hit
                            summ.ext.first("limit_first", limit_line(model, kin, s, limited[k], float(c[s, k]), start))
                    # every sample of the bodies' window, then every SINGULARITY_STRIDE-th: the least of
                    # each measure (with the earlier chunks'), the singular value decompositions only
                    # where bounds leave it open
                    idx = np.arange(start, stop)
                    pick = np.flatnonzero((idx < body_rows) | (idx % SINGULARITY_STRIDE == 0))
                    sm = least_measures(model, kin.q[pick], below=summ.sing) if pick.size else None
                    try:
                        reac = joint_reactions(model, kin, named=m.loads, split=True, sample_offset=start,
                                               overconstrained=overconstrained)
                    except ComplianceDataMissing as exc:
                        if unique_reactions:
                            raise ComplianceDataMissing(str(exc)) from None
                        overconstrained, reason = "minimum-norm", str(exc)
                        reac = joint_reactions(model, kin, named=m.loads, split=True, sample_offset=start,
                                               overconstrained=overconstrained)
                    cols = results_columns(model, kin)
                    cols.update(effort_columns(model, kin, reac, m.loads))
                    if deflection:
                        cols.update(deflection_columns(model, kin, reac, m.loads, start))
                    cols.update(pose_columns(model, kin))
                    writer.write(cols)
                    summ.add(start, kin, sm, reac, cols)
                    summ.reactions = {"method": reac.method, "self_stress_states": reac.self_stress}
                    if start < body_rows:
                        k = min(stop, body_rows) - start
                        arrays = bodies_arrays(model, kin)
                        arrays.update(joint_force=reac.joint_force, joint_moment=reac.joint_moment,
                                      **_motor_arrays(model, reac))
                        if len(model.load_body):
                            LF, LM = load_forces(model, len(kin), m.loads)
                            arrays.update(load_force=LF, load_moment=LM,
                                          load_point=kin.origin[:, model.load_body] + np.einsum(
                                              "nlij,lj->nli", kin.R[:, model.load_body], model.load_point))
                        npz.write({key: v[:k] for key, v in arrays.items()})
                    if start < window:
                        k = min(stop, window) - start
                        curves.add(start, cols["t_s"][:k], {key: cols[key][:k] for key in plotted})
                        frames.add(start, t=kin.t[:k] if kin.t is not None else np.arange(start, start + k, dtype=float),
                                   joint_point=kin.joint_point[:k])
                    bar.update(stop - start)
            npz.close()
        except BaseException:
            npz.discard()
            raise
        summary = {
            "mechanism": model.name, "samples": n, "max_residual": summ.value("residual"),
            "min_inverse_singularity_measure": summ.sing["inverse"],
            "min_direct_singularity_measure": None if summ.direct_nan else summ.sing["direct"],
            "min_constraint_singularity_measure": summ.sing["constraint"],
            # the motion against the joints' limits (stored in the description; the run goes on beyond them)
            "joint_limits": {"kept": summ.ext.get("limit_first") is None, "first_beyond": summ.ext.get("limit_first")},
            "topology": model.topology.as_dict() if model.topology is not None else None,
            "reactions": {**summ.reactions, "max_equilibrium_residual": summ.value("eq_residual"),
                          "unique": overconstrained == "compliance",
                          **({"reason": reason} if reason else {}),
                          "friction_iterations": int(summ.value("iterations")),
                          "idle_freedoms": int(model.solver_idle.shape[0]),
                          "max_idle_holding_effort_SI": summ.value("holding")},
            "actuators": summ.actuators(),
            "actuator_effort_limits": {"kept": summ.ext.get("beyond_effort") is None,
                                       "first_beyond": summ.ext.get("beyond_effort")},
            "effort_split": {"groups": {g: [model.body_names[b] for b in np.flatnonzero(model.body_group == k)]
                                        for k, g in enumerate(model.group_names)},
                             "parts": [*model.group_names, *(["rotor"] if model.has_drives else []), "friction"]},
            "results_format": fmt, "limits": lim, "bodies_samples": body_rows,
        }
        if model.na < model.nt:  # under-actuated: the motion's least dynamic consistency
            summary["max_unactuated_force_ratio"] = summ.value("unactuated")
        plot_cols = {k: v[:, 0] for k, v in curves.data().first.items()}
        return Output(files, summary, run_report(model, plot_cols, frames.arrays(), description_text, samples=n))

    files, output = write_output(out_dir, inputs, make, report)
    return JobResult(files, output.summary or {}, report=output.report)


def job(machine: str, out_dir: Path, *, motion_path: Path | None = None, actuator_path: Path | None = None,
        sg_window: int = 15, sg_order: int = 5, cycles: float | None = None, samples_per_cycle: int | None = None,
        fmt: str = "csv", limit_items: tuple[str, ...] = (), minimum_norm_reactions: bool = False, deflection: bool = False,
        announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """``pkmdyn run``: ``machine`` along its motion (``motion_path``, a task motion file;
    ``actuator_path``, a motion in actuator coordinates through the direct kinematics, rates by a
    Savitzky-Golay differentiator of ``sg_window`` samples and order ``sg_order`` or, with 0, a
    quintic spline; neither: the machine's default motion, ``cycles`` of it at ``samples_per_cycle``)
    into ``out_dir`` (:func:`run_mechanism`). ``minimum_norm_reactions``: an over-constrained
    mechanism without the data that make its reactions unique gets the minimum-norm ones."""
    limits = parse_limit_options(limit_items, LIMIT_KEYS)
    if motion_path is not None and actuator_path is not None:
        raise ParameterError("--motion and --actuator-motion exclude each other: give the motion one way")
    p = prepare(machine, out_dir, {"--motion": motion_path, "--actuator-motion": actuator_path}, limits)
    model, entry = p.model, p.entry
    lim = effective_limits(model, limits)
    window = None
    if motion_path is not None or actuator_path is not None:
        given = "--motion" if motion_path is not None else "--actuator-motion"
        for opt, v in (("--cycles", cycles), ("--samples-per-cycle", samples_per_cycle)):
            if v is not None:
                raise ParameterError(f"{opt} applies to the default motion, not to {given}")
        if motion_path is not None:
            motion = read_task_motion(model, Path(motion_path).absolute())
        else:
            if sg_window != 0:
                check_smoothing(sg_window, sg_order)
            am = read_actuator_motion(model, Path(actuator_path).absolute(), sg_window, sg_order)
            if model.na < model.nt:  # under-actuated: the passive freedoms simulated
                if am.loads:
                    raise MotionError(f"{actuator_path}: named loads ({', '.join(am.loads)}) along the actuator motion "
                                      "of an under-actuated mechanism are not simulated yet; give them by the "
                                      "description's magnitude_N")
                motion = _simulated(model, am.t, partial(passive_motion, model, am.t, am.s, am.sd, am.sdd))
            else:
                motion, _ = task_motion(model, am)
    elif entry is None:
        motion = periodic_motion(model, 1.0 if cycles is None else cycles, samples_per_cycle,
                                 max_samples=int(lim["max_samples"]))
        window = motion.samples_per_cycle + 1  # the plots and the animation show the first cycle
        if model.na < model.nt:  # under-actuated: the default motion drives the actuators, the rest simulated
            whole = motion.chunk(0, len(motion))
            motion = _simulated(model, whole.t, partial(driven_motion, model, whole))
    else:
        if samples_per_cycle is not None:
            raise ParameterError(f"--samples-per-cycle applies to a described mechanism's default motion; "
                                 f"{machine}'s is fixed")
        cycle = entry.default_motion()
        motion = repeated_motion(cycle, 1.0 if cycles is None else cycles, f"{machine}'s default motion",
                                 max_samples=int(lim["max_samples"]))
        window = len(cycle)
    try:
        res = run_mechanism(model, motion, out_dir, inputs=p.inputs, report=announce, description_text=p.text,
                            unique_reactions=not (minimum_norm_reactions or model.reactions == "minimum-norm"),
                            fmt=fmt, limits=limits, progress=True, deflection=deflection, plot_window=window)
    except ComplianceDataMissing as exc:
        raise ComplianceDataMissing(f"{exc}; or --minimum-norm-reactions ([mechanism] reactions = \"minimum-norm\") "
                                    "for reactions that balance every body but are not unique") from None
    summary = res.summary
    warnings = []
    beyond = summary["joint_limits"]["first_beyond"]
    if beyond is not None:
        warnings.append(f"the motion leaves the joint limits: {beyond}")
    over = summary["actuator_effort_limits"]["first_beyond"]
    if over is not None:
        warnings.append(f"the motion needs more than an actuator's rated effort: {over}")
    reactions = summary.get("reactions", {})
    if reactions.get("unique") is False:
        warnings.append(f"joint reactions are the minimum-norm ones, not unique: {reactions.get('reason')}")
    return replace(res, warnings=tuple(warnings))

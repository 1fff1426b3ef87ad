"""Machine-independent commands: ``pkmdyn machines``, ``describe``, ``run``, ``control``,
``identify``, ``export``.

``--machine`` takes a built-in name (``pkmdyn machines``) or a description ``FILE.toml``; an
unknown name is refused, never routed to another machine's code.
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..errors import MotionError, ParameterError
from ..io import atomic_file, check_output_dir, check_output_file, dumps_yaml
from ..machines.registry import builtin_names, resolve
from ..profiles._columns import check_smoothing
from ._groups import MACHINE_HELP, PATH_IN, FiniteFloat, cli, list_files, show
from .control import MAX_CYCLES, machine_controllers

if TYPE_CHECKING:
    from .. import control as _control
    from .. import multibody as _multibody
    from ..jobs import identify as identify_job
    from ..jobs import run as run_job
    from ..multibody.analyses import stiffness as _stiffness
    from ..multibody.dynamics import verbs as _verbs
    from ..multibody.formats import mjcf_out as _mjcf_out
    from ..multibody.formats import urdf_out as _urdf_out
    from ..multibody.kinematics import inverse as _inverse
    from ..multibody.model import legs as _legs
else:  # loaded when a command runs, not on import (nor for --help)
    _control = lazy_module("pkmdyn.control")
    identify_job = lazy_module("pkmdyn.jobs.identify")
    _multibody = lazy_module("pkmdyn.multibody")
    _stiffness = lazy_module("pkmdyn.multibody.analyses.stiffness")
    _verbs = lazy_module("pkmdyn.multibody.dynamics.verbs")
    _mjcf_out = lazy_module("pkmdyn.multibody.formats.mjcf_out")
    _urdf_out = lazy_module("pkmdyn.multibody.formats.urdf_out")
    _inverse = lazy_module("pkmdyn.multibody.kinematics.inverse")
    _legs = lazy_module("pkmdyn.multibody.model.legs")
    run_job = lazy_module("pkmdyn.jobs.run")


@cli.command("machines")
def machines() -> None:
    """List the built-in machines, one name a line."""
    for name in builtin_names():
        click.echo(name)


def _load(machine: str, limits: dict | None = None):
    """The compiled mechanism of ``--machine`` (a generated machine through the description its
    folder makes) and its registry entry (``None`` for a described one); ``limits`` (``--limit``)
    over the description's own for the plausibility of its numbers."""
    entry, path = resolve(machine)
    return _multibody.load_mechanism(path if entry is None else entry.description(), limits), entry


def _check_differentiator(sg_window: int, sg_order: int) -> None:
    """``--sg-window`` and ``--sg-order`` of the Savitzky-Golay differentiator, before any file
    is read (0: the spline, no differentiator)."""
    if sg_window != 0:
        check_smoothing(sg_window, sg_order)


@cli.command("describe")
@click.option("--machine", required=True, help=MACHINE_HELP)
def describe(machine: str) -> None:
    """Print the topology, mobility and over-constraints of a machine."""
    model, _ = _load(machine)
    rep = model.topology
    counts = ", ".join(f"{c} {k}" for k, c in rep.joint_counts.items())
    lines = [
        f"mechanism: {model.name}",
        f"source: {model.source}" if model.source else None,
        f"moving bodies: {rep.bodies}; joints: {counts}",
        f"spanning tree: {', '.join(rep.tree_joints)}",
        f"cut joints (independent loops {rep.loops}): {', '.join(rep.cut_joints) or 'none'}",
        f"Grubler-Kutzbach mobility: {rep.kutzbach}",
        f"mobility (rank at the reference configuration): {rep.mobility}",
        f"idle freedoms: {rep.idle}",
        f"degrees of freedom: {rep.dof}",
        f"over-constraints: {rep.overconstraints}"
        + (f" ({', '.join(f'{j} {d}' for j, d in rep.overconstrained)})" if rep.overconstrained else ""),
        f"actuated joints: {', '.join(model.actuator_names)}",
        f"task coordinates: {', '.join(f'{n} [{u}]' for n, u in zip(model.task_names, model.task_units))} "
        f"of body {model.body_names[model.task_body]}",
        f"explicit legs (closed form, {model.legs.count}): "
        + (", ".join(f"{'-'.join(chain)} to {cut} ({_legs.LEG_PATTERNS[kind].split(' ')[0]}{_held(model, chain)})"
                     for cut, chain, kind in model.legs.names) or "none; Newton solves every loop")
        + (" (every block: Newton only checks)" if model.legs.count == model.solver_blocks.shape[0] - 1 else ""),
    ]
    src = _stiffness.compliance_sources(model)
    lines.append("compliance (pkmdyn stiffness): " + ("; ".join(f"{k} {', '.join(v)}" for k, v in src.items() if v)
                                                      or "none (every body, joint and drive rigid)"))
    if model.parameters:
        lines.append("parameters: " + "; ".join(f"{k} = {_shown(v)}{_range(model.parameter_bounds.get(k))}"
                                                for k, v in model.parameters.items()))
    for line in lines:
        if line is not None:
            click.echo(line)


def _held(model, chain) -> str:
    """``, J spin held`` for the joints of an explicit leg's chain with a coordinate that an idle
    row of its own holds (an S-S rod's spin; docs/mechanism_format.md, "Explicit legs")."""
    held = _legs.held_coordinates(model)
    out = ""
    for j in chain:
        k = model.joint_index(j)
        if held & set(range(model.joint_q0[k], model.joint_q0[k] + model.joint_nq[k])):
            out += f", {j} spin held"
    return out


def _range(bounds) -> str:
    """A bounded parameter's bounds as ``describe`` prints them: `` (min 0.1, max 0.3)``."""
    if not bounds:
        return ""
    parts = [f"{w} {b:.9g}" for w, b in zip(("min", "max"), bounds) if b is not None]
    return f" ({', '.join(parts)})"


def _shown(v) -> str:
    """A parameter's value as ``describe`` prints it: a number, or a vector of numbers."""
    if isinstance(v, list):
        return "[" + ", ".join(_shown(x) for x in v) + "]"
    return f"{v:.9g}"


@cli.command("run")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="Motion CSV: t_s and one column per task coordinate (<name>_<unit>), optional rates "
                   "<name>d_<unit>_s and accelerations <name>dd_<unit>_s2 (default: the machine's default motion, "
                   "for a paper's machine the paper's motion).")
@click.option("--actuator-motion", "actuator_path", type=PATH_IN, default=None,
              help="Motion in actuator coordinates (CSV): t_s and one column per actuated joint, <joint>_pos_<m|rad>, "
                   "optional rates <joint>_vel_<u>_s and accelerations <joint>_acc_<u>_s2 and named loads; the pose "
                   "by the direct kinematics (docs/mechanism_format.md, \"Direct kinematics\").")
@click.option("--sg-window", type=click.IntRange(0, 100_001), default=15, show_default=True,
              help="--actuator-motion without rate columns: samples of the Savitzky-Golay smoothing differentiator "
                   "(odd, >= 3; uniform sampling), or 0 for the interpolating quintic spline (exact positions).")
@click.option("--sg-order", type=click.IntRange(2, 20), default=5, show_default=True,
              help="Degree of the Savitzky-Golay polynomial (less than --sg-window).")
@click.option("--cycles", type=FiniteFloat(0.0, 1e9, lo_open=True), default=None,
              help="Cycles of the default motion (default 1; a periodic default motion repeats).")
@click.option("--samples-per-cycle", type=click.IntRange(1, 100_000_000), default=None,
              help="A described mechanism's default motion: samples per cycle (default: its [default_motion] "
                   "samples - 1).")
@click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="Format of the results table (results.csv or results.parquet).")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a plausibility limit of the description's [limits] (max_samples, max_body_samples, "
                   "max_task_speed_m_s, max_joint_acceleration_rad_s2, ...; docs/mechanism_format.md). Repeatable.")
@click.option("--minimum-norm-reactions", is_flag=True,
              help="For an over-constrained mechanism whose bodies lack the section and material data that make "
                   "its joint reactions unique (refused without this flag): write its kinematics and efforts "
                   "(unique all the same) with the minimum-norm reactions, which balance every body but are one "
                   "choice among its self-stress states; said on stderr and in summary.json.")
@click.option("--deflection", is_flag=True,
              help="Also the task body's elastic deflection under the run's loads with the actuators locked "
                   "(<coordinate>_deflection_<unit> columns; the description needs drive, link or joint "
                   "stiffness, docs/stiffness.md).")
@click.option("--unique-reactions", is_flag=True, hidden=True,
              help="The default: refuse reactions that are not unique.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def run(machine: str, motion_path: Path | None, actuator_path: Path | None, sg_window: int, sg_order: int,
        cycles: float | None, samples_per_cycle: int | None, fmt: str, limit_items: tuple[str, ...],
        minimum_norm_reactions: bool, deflection: bool, unique_reactions: bool, out_dir: Path) -> None:
    """Kinematics, actuator and motor efforts, the effort split and every joint reaction along a
    motion, streamed in chunks: results.csv (or .parquet), model.json, bodies.npz, summary.json,
    report.html.

    The same files for every machine; a paper's machine has its own job too, with the paper's
    columns and figures (pkmdyn <machine> run; see pkmdyn machines)."""
    if minimum_norm_reactions and unique_reactions:
        raise click.UsageError("--minimum-norm-reactions and --unique-reactions contradict each other")
    show(run_job.job(machine, out_dir, motion_path=motion_path, actuator_path=actuator_path, sg_window=sg_window,
                     sg_order=sg_order, cycles=cycles, samples_per_cycle=samples_per_cycle, fmt=fmt,
                     limit_items=limit_items, minimum_norm_reactions=minimum_norm_reactions, deflection=deflection,
                     announce=list_files))


#: controllers a described mechanism takes (from its dynamics verbs; pkmdyn.control)
DESCRIBED_CONTROLLERS = ("computed-torque", "augmented-pd", "pd", "pid", "feedforward")


def described_control_settings(model) -> dict:
    """Control settings of a described mechanism, laid under ``--gains`` (no ``[mismatch]``: the
    plant is the controller's own model): 2 ms cycle, 1 ms plant step, exact pose feedback, effort
    limits the drives' rated efforts (``[[actuators]]`` ``max_torque_Nm`` or ``max_force_N``;
    far away without one), the efforts being the drives' motor efforts, divergence at 0.05 m or 0.2 rad of
    tracking error; every controller tuned for 5 Hz at damping 0.7 on the mechanism's inertia
    at its reference pose: computed torque ``kp = wn^2``, ``kd = 2 zeta wn`` [1/s^2, 1/s]; the
    task-space PD (and augmented PD) ``kp = wn^2 M_ii``, ``kd = 2 zeta wn M_ii`` with ``M`` the
    task mass matrix [N/m or N m/rad, ...]; the actuators' PID ``kp = wn^2 Ma_ii``,
    ``kd = 2 zeta wn Ma_ii``, ``ki = wn kp / 10`` with ``Ma = B^+ M B^+T`` (``B = J_ax^T K``) the inertia
    seen by each actuator. Keys ending ``_si`` are in SI units of their coordinate."""
    import numpy as np

    nt, na = model.nt, model.na
    wn, zeta = 2 * np.pi * 5.0, 0.7
    verbs = _verbs.machine_verbs(model)
    x0 = _multibody.reference_task(model)[None]
    M = verbs.mass_matrix(model, x0)[0]
    B = verbs.actuator_map(model, x0)[0]  # J_ax^T K (nt, na): the motors' map, K the drives' ratios
    Ma = np.linalg.pinv(B) @ M @ np.linalg.pinv(B.T) if na else np.zeros((0, 0))
    dm, da = np.abs(np.diag(M)), np.abs(np.diag(Ma))

    def lst(v) -> list[float]:
        return [float(f"{x:.6g}") for x in v]

    pd = {"kp_si": lst(wn * wn * dm), "kd_si": lst(2 * zeta * wn * dm)}
    limits = [float(v) if np.isfinite(v) else 1e9 for v in model.drive_max_effort]
    return {
        "timing": {"control_cycle_s": 0.002, "integration_step_s": 0.001},
        "actuators": {"effort_limit_si": limits},
        "sensors": {"encoder_counts_per_turn": 1000000, "encoder_travel_per_turn_m": 0.001,
                    "velocity_cutoff_Hz": 200.0, "acceleration_cutoff_Hz": 50.0, "pose_noise_si": [0.0] * nt,
                    "pose_delay_cycles": 0, "pose_feedback_from_sensor": 1, "seed": 1, "exact_encoders": 1},
        "run": {"divergence_limit_si": [0.2 if k == 1 else 0.05 for k in model.task_kind]},
        "computed-torque": {"kp_1_s2": [wn * wn] * nt, "kd_1_s": [2 * zeta * wn] * nt},
        "pd": dict(pd),
        "augmented-pd": dict(pd),
        "pid": {"kp_si": lst(wn * wn * da), "ki_si": lst(wn * wn * wn * da / 10.0), "kd_si": lst(2 * zeta * wn * da)},
    }


@cli.command("control")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--controller", default=None,
              help="; ".join(f"{n}: {', '.join(c)}" for n, c in machine_controllers().items()) + "; a described "
                   "mechanism: " + ", ".join(DESCRIBED_CONTROLLERS) + " (default computed-torque).")
@click.option("--params", "params_path", type=PATH_IN, help="Generated machines: the controller model's parameter file.")
@click.option("--plant-params", "plant_path", type=PATH_IN, help="Generated machines: the plant's parameter file.")
@click.option("--motion", "motion_path", type=PATH_IN,
              help="A motion file (CSV): the machine's own format; a described mechanism's task motion "
                   "(docs/mechanism_format.md), its named load's column driving the load. Default: the built-in "
                   "motion.")
@click.option("--cycles", type=FiniteFloat(0.0, MAX_CYCLES, lo_open=True), default=None,
              help="Generated machines: cycles of the built-in motion (default 1).")
@click.option("--gains", "gains_path", type=PATH_IN,
              help="Control settings (TOML) laid over the machine's defaults (docs/control.md; a described "
                   "mechanism's defaults are tuned from its inertia, docs/multibody_dynamics.md).")
@click.option("--format", "fmt", type=click.Choice(["csv", "parquet"]), default="csv", show_default=True,
              help="Table format of the per-cycle results.")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--duration", "duration_s", type=FiniteFloat(0.0, 1e6, lo_open=True), default=None,
              help="Described mechanisms: seconds of the motion to track (default 1 s or the motion's length).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def control(machine: str, controller: str | None, params_path: Path | None, plant_path: Path | None,
            motion_path: Path | None, cycles: float | None, gains_path: Path | None, fmt: str, no_plots: bool,
            duration_s: float | None, out_dir: Path) -> None:
    """Closed-loop tracking for any machine: control.csv (or .parquet), summary.json.

    A generated machine runs its own control job (the same as its pkmdyn <machine> control,
    with every option of that); a described mechanism tracks its default motion in
    task space on its own dynamics (pkmdyn.multibody.dynamics.verbs), the controller the same model."""
    import numpy as np

    from .control import _check_encoder, _Setup, _stream, check_loop, control_command

    entry, path = resolve(machine)
    if entry is not None:
        if controller is None:
            raise click.UsageError(f"--controller is required for --machine {machine}")
        if duration_s is not None:
            raise click.UsageError("--duration applies to a described mechanism; a generated machine takes --cycles")
        control_command(entry.NAME, controller, params_path, plant_path, motion_path, 1.0 if cycles is None else cycles,
                 gains_path, no_plots, out_dir, fmt)
        return
    given = [o for o, v in (("--params", params_path), ("--plant-params", plant_path), ("--cycles", cycles))
             if v is not None]
    if given:
        raise click.UsageError(f"{given[0]} applies to the generated machines (see pkmdyn machines), not to a described mechanism")
    controller = controller or "computed-torque"
    if controller not in DESCRIBED_CONTROLLERS:
        raise click.UsageError(f"--controller {controller!r}: a described mechanism takes "
                               + ", ".join(DESCRIBED_CONTROLLERS))
    inputs = {"--machine": path, "--motion": motion_path, "--gains": gains_path}
    check_output_dir(out_dir, inputs)
    model, _ = _load(machine)
    if motion_path is not None:
        motion = _multibody.read_task_motion(model, Path(motion_path).absolute())
        what = str(motion_path)
    else:
        motion = _multibody.default_motion(model)
        what = "the default motion"
    span = float(motion.t[-1] - motion.t[0])
    duration_s = min(1.0, span) if duration_s is None else duration_s
    if not duration_s <= span:
        raise MotionError(f"--duration: {duration_s:g} s must be at most the motion's {span:g} s")
    if _inverse.limited_joints(model):  # the plant has no end stops: say where the reference leaves the joint limits
        span_mask = motion.t <= motion.t[0] + duration_s
        beyond = _inverse.limit_message(model, _multibody.solve_kinematics(model, motion.x[span_mask], motion.xd[span_mask],
                                                       motion.xdd[span_mask], motion.t[span_mask]))
        if beyond is not None:
            click.echo(f"pkmdyn: warning: the reference motion leaves the joint limits: {beyond}", err=True)
    settings = _control.overlay_settings(described_control_settings(model), gains_path)
    ls = _control.loop_settings(settings)
    if np.any(model.drive_encoder > 0):  # a drive's own encoder, counts per motor turn, in motor radians
        ls = replace(ls, encoder_resolution=np.where(model.drive_encoder > 0, model.drive_encoder,
                                                     float(ls.encoder_resolution)))
    check_loop(ls, duration_s, gains_path)
    verbs = _verbs.machine_verbs(model)
    load, column = _control_load(model, motion, what, verbs.ACTUATORS)
    fn = _control.hermite_motion(motion.t, motion.x, motion.xd, motion.xdd, load)
    encoders = tuple((d, "encoder_counts_per_turn" if u == "rad" else "encoder_counts_per_m", u) if r > 0 else None
                     for d, r, u in zip(model.drive_name, model.drive_encoder, model.motor_units))
    setup = _Setup(model.name, verbs, model, model, fn, duration_s, load is not None, str(path),
                   "the controller's model", what, span_s=span, load_column=column, drive_encoders=encoders)
    _check_encoder(setup, ls, settings, gains_path)
    n = model.na if controller == "pid" else model.nt
    _stream(setup, controller, _control.gains(settings, controller, n), ls, settings, out_dir,
            not no_plots, gains_path, inputs, fmt)


def _control_load(model, motion, what: str, efforts: tuple[str, ...]):
    """The named load that a control run drives from its motion: ``(magnitudes [N] per sample,
    column)`` where the motion has the column of the mechanism's one named load, else ``(None,
    "")`` (the description's ``magnitude_N`` then holds, on the plant and in the controller
    alike). The loop carries one load: a motion with named-load columns for a mechanism with
    several is refused rather than run without them; so is a load whose name is that of an
    actuator's effort column of ``control.csv`` (``efforts``), which it would replace."""
    given = [nm for nm in model.named_loads if nm in motion.loads]
    if not given:
        return None, ""
    if len(model.named_loads) > 1:
        raise MotionError(f"{what}: column {given[0]!r}: control drives one named load from the motion, and "
                          f"{model.name!r} has {len(model.named_loads)} ({', '.join(model.named_loads)}); "
                          "remove the named-load columns to run on the description's magnitude_N")
    if given[0] in efforts:
        raise MotionError(f"{what}: column {given[0]!r}: the named load has the name of an actuator's effort column "
                          "of control.csv; rename the load (its [[loads]] name and the motion's column)")
    return motion.loads[given[0]], given[0]


@cli.command("identify")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--measured", "measured_path", type=PATH_IN, required=True,
              help="Measured run (CSV): t_s, the task columns (or the actuated joints' <joint>_pos_<m|rad>: the pose "
                   "by the direct kinematics) and one effort column per actuator, a drive's <actuator>_torque_Nm or a "
                   "joint's <joint>_effort_<N|Nm> (a pkmdyn run results.csv works as it is); optional: rates, "
                   "accelerations, named loads.")
@click.option("--rank-tol", type=FiniteFloat(0.0, 1.0, lo_open=True), default=1e-6, show_default=True,
              help="Singular values of the column-scaled regressor below this fraction of the largest count as zero.")
@click.option("--sg-window", type=click.IntRange(0, 100_001), default=15, show_default=True,
              help="A log in actuator coordinates without rate columns: samples of the Savitzky-Golay smoothing "
                   "differentiator (odd, >= 3; uniform sampling), or 0 for the interpolating quintic spline.")
@click.option("--sg-order", type=click.IntRange(2, 20), default=5, show_default=True,
              help="Degree of the Savitzky-Golay polynomial (less than --sg-window).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run of this command there is replaced whole, any other non-empty folder is refused.")
def identify(machine: str, measured_path: Path, rank_tol: float, sg_window: int, sg_order: int,
             out_dir: Path) -> None:
    """Identify a mechanism's inertial parameters and joint friction coefficients from measured
    actuator efforts: identification.json, efforts.csv (docs/identification.md)."""
    _check_differentiator(sg_window, sg_order)
    show(identify_job.job(machine, measured_path, out_dir, rank_tol=rank_tol, sg_window=sg_window, sg_order=sg_order,
                          announce=list_files))


def _numbers(text: str | None, n: int, flag: str) -> tuple[float, ...] | None:
    if text is None:
        return None
    try:
        vals = tuple(float(x) for x in text.split(","))
    except ValueError:
        vals = ()
    if len(vals) != n:
        raise ParameterError(f"{flag}: {n} numbers, comma-separated")
    return vals


@cli.command("export")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--format", "fmt", type=click.Choice(["mjcf", "urdf"]), required=True,
              help="mjcf: a MuJoCo model (the spanning tree; spherical, revolute and fixed cut joints as stiff "
                   "equality constraints; motors with gear and armature; no loads). urdf: URDF plus a loop "
                   "sidecar FILE.yaml beside it (Pinocchio's parser and Gepetto's Extended-URDF loader; "
                   "docs/import.md).")
@click.option("--solref", default=None, help="mjcf: the equality constraints' solref 'timeconst,dampratio' "
                                             "(default 0.0005,1: stiff).")
@click.option("--solimp", default=None, help="mjcf: the equality constraints' solimp 'd0,dwidth,width,midpoint,power' "
                                             "(default 0.9999,0.9999,0.001,0.5,2).")
@click.option("--timestep", "timestep_s", type=FiniteFloat(1e-6, 1.0), default=None,
              help="mjcf: MuJoCo's integration step [s], 1e-6 to 1 (default 0.001).")
@click.option("--massless-mass-kg", "massless_kg", type=FiniteFloat(1e-12, 1e6), default=None,
              help="mjcf: the mass [kg] given to bodies without one (MuJoCo needs a mass; default: refused).")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="File to write (e.g. machine.xml, machine.urdf).")
def export(machine: str, fmt: str, solref: str | None, solimp: str | None, timestep_s: float | None,
           massless_kg: float | None, out_path: Path) -> None:
    """Write a described mechanism in another engine's format; the files are written only when
    the whole model can be written (a cut joint the format cannot express, a body without
    mass for MuJoCo: an error naming it)."""

    entry, path = resolve(machine)
    inputs = {"--machine": path}
    check_output_file(out_path, inputs)
    if fmt != "mjcf" and (solref or solimp or massless_kg is not None or timestep_s is not None):
        raise ParameterError("--solref, --solimp, --timestep, --massless-mass-kg: only for --format mjcf")
    model, _ = _load(machine)
    files = {out_path: ""}
    if fmt == "mjcf":
        files[out_path] = _mjcf_out.mechanism_mjcf(model, 1e-3 if timestep_s is None else timestep_s, solref=_numbers(solref, 2, "--solref") or _mjcf_out.SOLREF,
                                         solimp=_numbers(solimp, 5, "--solimp") or _mjcf_out.SOLIMP, massless_kg=massless_kg)
        light = _mjcf_out.massless_bodies(model)
        if light:
            click.echo(f"note: bodies without mass given {massless_kg:g} kg: {', '.join(light)}", err=True)
    else:
        side_path = out_path.with_suffix(".yaml")
        if side_path == out_path:
            raise ParameterError("--out: a URDF file name not ending in .yaml (its sidecar is FILE.yaml)")
        check_output_file(side_path, inputs)
        text, sidecar, notes = _urdf_out.mechanism_urdf(model)
        files = {out_path: text, side_path: dumps_yaml(sidecar)}
        for line in notes:
            click.echo(f"note: {line}", err=True)
    for fpath, text in files.items():
        with atomic_file(fpath, inputs=inputs) as tmp:
            tmp.write_text(text, encoding="utf-8")
        click.echo(f"{fmt if fpath == out_path else 'sidecar'}: {fpath}")

"""Machine-independent commands: ``pkmdyn machines``, ``describe``, ``run``, ``control``,
``identify``, ``export``.

``--machine`` takes a built-in name (``pkmdyn machines``) or a description ``FILE.toml``; an
unknown name is refused, never routed to another machine's code.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..errors import ParameterError
from ..io import atomic_file, check_output_file, dumps_yaml
from ..machines.registry import builtin_names, resolve
from ..profiles._columns import check_smoothing
from ._groups import MACHINE_HELP, PATH_IN, FiniteFloat, cli, list_files, show

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

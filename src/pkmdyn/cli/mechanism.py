"""Machine-independent commands: ``pkmdyn machines``, ``pkmdyn describe``, ``pkmdyn run``.

``--machine`` takes a built-in name (``pkmdyn machines``) or a description ``FILE.toml``; an
unknown name is refused, never routed to another machine's code.
"""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN, cli, list_files

_MACHINE_HELP = "A built-in machine (see pkmdyn machines) or a mechanism description FILE.toml."


@cli.command("machines")
def machines() -> None:
    """List the built-in machines, one name a line."""
    from ..machines.registry import builtin_names

    for name in builtin_names():
        click.echo(name)


def _load(machine: str):
    """The compiled mechanism of ``--machine`` (a hand-built machine through the description its
    folder makes) and its registry entry (``None`` for a described one)."""
    from ..machines.registry import resolve
    from ..multibody import load_mechanism

    entry, path = resolve(machine)
    return load_mechanism(path if entry is None else entry.description()), entry


@cli.command("describe")
@click.option("--machine", required=True, help=_MACHINE_HELP)
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
    ]
    for line in lines:
        if line is not None:
            click.echo(line)


@cli.command("run")
@click.option("--machine", required=True, help=_MACHINE_HELP)
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="Motion CSV: t_s and one column per task coordinate (<name>_<unit>), optional rates "
                   "<name>d_<unit>_s and accelerations <name>dd_<unit>_s2 (default: the machine's default motion; "
                   "hip: the ISO 14242-1 cycle, pdm: the Eq. 84 motion).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; an earlier run there is replaced whole, any other non-empty folder is refused.")
def run(machine: str, motion_path: Path | None, out_dir: Path) -> None:
    """Kinematics of every body and joint along a motion: results.csv, model.json, bodies.npz, summary.json.

    The same files for every machine; the hip's and the PDM's own jobs (dynamics, plots) are
    pkmdyn hip run and pkmdyn pdm run."""
    from ..io import check_output_dir
    from ..machines.registry import resolve
    from ..multibody import default_motion, read_task_motion
    from ..multibody.output import run_mechanism

    entry, path = resolve(machine)
    inputs = {"--machine": path, "--motion": motion_path}
    check_output_dir(out_dir, inputs)
    model, entry = _load(machine)
    if motion_path is not None:
        motion = read_task_motion(model, Path(motion_path).absolute())
    else:
        motion = default_motion(model) if entry is None else entry.default_motion()
    text = path.read_text(encoding="utf-8", errors="replace") if path is not None else ""
    run_mechanism(model, motion, out_dir, inputs=inputs, report=list_files, description_text=text)

"""``pkmdyn stiffness``: stiffness, worst directions, deflection and natural frequencies of a
mechanism with its actuators locked (``docs/stiffness.md``)."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import MACHINE_HELP, PATH_IN, cli, list_files


@cli.command("stiffness")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--pose", "poses", multiple=True, metavar="NAME=VALUE,...",
              help="A task pose (task coordinates by name, e.g. \"x=0.02,euler3_rad=0.1\"; the reference pose's "
                   "value for the others); repeat for several. Default: the reference pose.")
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="A task motion file (as for pkmdyn run): the stiffness at every sample and the deflection under "
                   "the motion's own loads, in results.csv.")
@click.option("--default-motion", is_flag=True,
              help="The description's default motion (one cycle) as the motion.")
@click.option("--grid", default=None, metavar="NAME=LOW:HIGH:COUNT[,NAME=...]",
              help="One or two task coordinates swept about the reference pose: grid.csv and stiffness_map.png.")
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a plausibility limit of the description's numbers ([limits]).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def stiffness_command(machine: str, poses: tuple[str, ...], motion_path: Path | None, default_motion: bool,
                      grid: str | None,
                      limit_items: tuple[str, ...], out_dir: Path) -> None:
    """Cartesian stiffness of the task body with the actuators locked (from the drives', links' and
    joints' compliance), its eigen-stiffnesses and worst directions, natural frequencies and modes;
    along a motion the task body's elastic deflection under its loads; over a grid, maps."""
    from ..io import check_output_dir, output_dir
    from ..machines.registry import resolve
    from ..multibody import read_task_motion
    from ..multibody.description.schema import LIMIT_KEYS
    from ..jobs.stiffness import MAX_GRID_POINTS, run_stiffness
    from ..multibody.analyses.task_grid import parse_grid, parse_pose
    from ..params_util import parse_limit_options
    from .mechanism import _load

    given = [o for o, v in (("--pose", poses), ("--motion", motion_path), ("--default-motion", default_motion),
                            ("--grid", grid)) if v]
    if len(given) > 1:
        raise click.UsageError(f"{' and '.join(given)} exclude each other: give poses, a motion or a grid")
    entry, path = resolve(machine)
    inputs = {"--machine": path, "--motion": motion_path}
    check_output_dir(out_dir, inputs)
    limits = parse_limit_options(limit_items, LIMIT_KEYS)
    model, _ = _load(machine, limits)
    import numpy as np

    kw: dict = {}
    if poses:
        kw["poses"] = np.stack([parse_pose(model, p) for p in poses])
    elif motion_path is not None:
        kw["motion"] = read_task_motion(model, Path(motion_path).absolute())
    elif default_motion:
        from ..multibody.kinematics.motion import default_motion as one_cycle

        kw["motion"] = one_cycle(model)
    elif grid is not None:
        kw["grid"] = parse_grid(model, grid, max_axes=2, max_points=MAX_GRID_POINTS)
    text = path.read_text(encoding="utf-8", errors="replace") if path is not None else ""
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as out:
        doc = run_stiffness(model, out, description_text=text,
                            report=lambda files: list_files({k: final / v.name for k, v in files.items()}), **kw)
    pose = doc.get("worst") or doc["poses"][0]
    k = pose["min_stiffness_N_m"]
    kr = pose["min_rot_stiffness_Nm_rad"]
    click.echo(f"{'worst pose' if 'worst' in doc else 'pose'}: "
               + ", ".join(f"{n} = {v:.6g}" for n, v in pose.get("task", {}).items()))
    click.echo(f"  translational stiffness, worst direction: {'rigid' if k is None else f'{k:.6g} N/m'}; "
               f"rotational: {'rigid' if kr is None else f'{kr:.6g} N m/rad'}")
    click.echo("  natural frequencies: " + ", ".join(f"{f:.6g}" for f in pose.get("frequencies_Hz", [])) + " Hz")

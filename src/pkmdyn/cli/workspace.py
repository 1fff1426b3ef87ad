"""``pkmdyn workspace``: the workspace of any described mechanism on a grid of task poses
(``docs/workspace.md``)."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import MACHINE_HELP, FiniteFloat, cli, list_files


@cli.command("workspace")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--grid", required=True, metavar="NAME=LOW:HIGH:COUNT[,...]",
              help="One to three task coordinates on a grid, e.g. \"x=-0.3:0.3:17,y=-0.3:0.3:17,z=0.8:1.2:9\".")
@click.option("--pose", default="", metavar="NAME=VALUE,...",
              help="The task coordinates held while the grid varies the others (default: the reference pose's), "
                   "e.g. a constant orientation \"euler3_rad=0.2\".")
@click.option("--orientation-range", "orientation_range", default=None, metavar="NAME=LOW:HIGH:COUNT[,...]",
              help="Held coordinates over ranges, e.g. \"euler1=-0.1:0.1:3,euler2=-0.1:0.1:3\": a pose is inside only "
                   "where it is inside at every combination of their values (the total orientation workspace).")
@click.option("--threshold", type=FiniteFloat(0.0, 1.0), default=1e-3, show_default=True,
              help="A pose is inside only where every singularity measure is at least this.")
@click.option("--centre", default=None, metavar="V1,V2,...",
              help="Centre of the inscribed cube and cylinder, one value per grid coordinate (default: the pose's).")
@click.option("--refine", type=click.IntRange(0, 64), default=0, show_default=True,
              help="Steps along each grid edge the workspace's boundary crosses, for a size that varies smoothly with "
                   "the design (0: inside poses times the cell; docs/workspace.md).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def workspace_command(machine: str, grid: str, pose: str, orientation_range: str | None, threshold: float,
                      centre: str | None, refine: int, out_dir: Path) -> None:
    """The reachable workspace within the joint limits and away from every singularity, on a grid
    of task poses: its size with an error estimate, the largest inscribed cube and cylinder about a
    centre, dexterity statistics, a map."""
    import numpy as np

    from ..errors import ParameterError
    from ..io import check_output_dir, output_dir, write_csv, write_json
    from ..machines.registry import resolve
    from ..multibody.analyses.task_grid import parse_grid, parse_pose, parse_ranges
    from ..multibody.analyses.workspace import check_centre, workspace, workspace_document, workspace_png
    from ..report import write_report
    from .mechanism import _load

    entry, path = resolve(machine)
    inputs = {"--machine": path}
    check_output_dir(out_dir, inputs)
    model, _ = _load(machine)
    axes = parse_grid(model, grid, max_axes=3)
    base = parse_pose(model, pose)
    ranges = None if orientation_range is None else parse_ranges(model, orientation_range)
    c = None
    if centre is not None:
        try:
            c = np.array([float(v) for v in centre.split(",")])
        except ValueError:
            raise ParameterError(f"--centre {centre!r}: expected numbers separated by commas") from None
        c = check_centre(c, len(axes))
    ws = workspace(model, axes, base, threshold, c, ranges, refine=refine)
    doc = workspace_document(model, ws)
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as out:
        files = {"workspace": out / "workspace.json", "poses": out / "workspace.csv", "map": out / "workspace.png"}
        write_json(files["workspace"], doc)
        cols = {f"{n}_{u}": ws.x[:, i] for i, (n, u) in enumerate(zip(model.task_names, model.task_units))}
        cols.update(reached=ws.reached.astype(float), inside=ws.inside.astype(float), singularity_measure=ws.measure)
        write_csv(files["poses"], cols)
        workspace_png(files["map"], model, ws)
        files["report"] = write_report(out, title=f"{model.name}: workspace", scene=None, summary=doc,
                                       parameters=path.read_text(encoding="utf-8", errors="replace") if path else "",
                                       images=[files["map"]], notes=["definitions: docs/workspace.md"])
        list_files({k: final / v.name for k, v in files.items()})
    shapes = ("" if ws.cube_half_width is None else
              f"; inscribed cube half-width {ws.cube_half_width:.4g}, cylinder radius {ws.cylinder_radius:.4g}")
    click.echo(f"{doc['inside']} of {doc['poses']} poses inside (reached: {doc['reached']}); size "
               f"{ws.size:.6g} +- {ws.size_error:.2g} {ws.unit}{shapes}")
    if doc["size_is_lower_bound"]:
        click.echo(f"pkmdyn: warning: the workspace reaches the grid's edge along {', '.join(doc['inside_at_grid_edge'])}: "
                   "its size is a lower bound (widen --grid there)", err=True)

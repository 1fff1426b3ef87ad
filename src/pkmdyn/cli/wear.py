"""``pkmdyn wear``: slide tracks, cross-shear and Archard wear of a mechanism's spherical joints
along a motion (``docs/wear.md``)."""

from __future__ import annotations

import json
from pathlib import Path

import click

from ._groups import MACHINE_HELP, PATH_IN, FiniteFloat, cli, list_files


def _pole(text: str | None) -> tuple[float, float, float] | None:
    from ..errors import ParameterError

    if text is None:
        return None
    try:
        v = tuple(float(x) for x in text.split(","))
    except ValueError:
        raise ParameterError(f"--pole {text!r}: expected three numbers X,Y,Z") from None
    if len(v) != 3:
        raise ParameterError(f"--pole {text!r}: expected three numbers X,Y,Z")
    return v  # type: ignore[return-value]


@cli.command("wear")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--joint", "joints", multiple=True, required=True,
              help="A spherical joint (repeat for several): the head on one of its bodies, the cup on the other.")
@click.option("--motion", "motion_path", type=PATH_IN, default=None,
              help="A task motion file (as for pkmdyn run); default: the description's default motion, one cycle.")
@click.option("--cycles", type=FiniteFloat(0.0, 1e9, lo_open=True), default=1.0, show_default=True,
              help="The cycles the motion spans (wear per million cycles divides by it).")
@click.option("--head", type=click.Choice(["child", "parent"]), default="child", show_default=True,
              help="The joint's body that carries the head (the other carries the cup).")
@click.option("--radius-m", type=FiniteFloat(0.0, 10.0, lo_open=True), default=None,
              help="The head's radius [m]; default: the joint's friction ball_radius_m.")
@click.option("--load", default=None, metavar="NAME",
              help="A named load of the motion as the load through the joint (default: the joint's own reaction force).")
@click.option("--spacing-deg", type=FiniteFloat(0.0, 90.0, lo_open=True), default=10.0, show_default=True,
              help="Marker grid: angle between rings and between markers of a ring.")
@click.option("--cap-deg", type=FiniteFloat(0.0, 180.0, lo_open=True), default=60.0, show_default=True,
              help="Marker grid: polar angle of the last ring from the pole.")
@click.option("--pole", default=None, metavar="X,Y,Z",
              help="Marker grid axis, base frame at the reference configuration (default: the joint frame's z).")
@click.option("--wear-factor", "wear_factor", type=FiniteFloat(0.0, 1.0, lo_open=True), default=None,
              help="Archard wear factor k [mm^3/(N m)] (default 8e-8, UHMWPE on a ceramic head, Saikko 1994).")
@click.option("--cross-shear-law", default=None, metavar="EXPR",
              help="Factor on each track's wear as an expression of cs, e.g. \"0.2 + 1.6 * cs\".")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def wear(machine: str, joints: tuple[str, ...], motion_path: Path | None, cycles: float, head: str,
         radius_m: float | None, load: str | None, spacing_deg: float, cap_deg: float, pole: str | None,
         wear_factor: float | None, cross_shear_law: str | None, out_dir: Path) -> None:
    """Slide tracks of points of the head on the cup (and of the cup on the head), their sliding
    distance, aspect ratio (the share above 5.5), cross-shear, track integral of load and the
    Archard wear per million cycles, for spherical joints of any mechanism."""
    from ..io import check_output_dir, output_dir
    from ..machines.registry import resolve
    from ..multibody import read_task_motion, solve_kinematics
    from ..multibody.kinematics.motion import default_motion
    from ..multibody.analyses.wear import WEAR_FACTOR_MM3_N_M, marker_grid
    from ..jobs.wear import tracks_figure, write_wear_files
    from ..multibody.analyses.wear import WearOptions, head_radius, joint_wear
    from .mechanism import _load

    entry, path = resolve(machine)
    inputs = {"--machine": path, "--motion": motion_path}
    check_output_dir(out_dir, inputs)
    opts = WearOptions(radius_m=radius_m, head=head, load=load, spacing_deg=spacing_deg, cap_deg=cap_deg,
                       pole=_pole(pole), wear_factor_mm3_N_m=WEAR_FACTOR_MM3_N_M if wear_factor is None else wear_factor,
                       cross_shear_law=cross_shear_law, cycles=cycles)
    marker_grid(spacing_deg, cap_deg)
    model, entry = _load(machine)
    for j in joints:
        head_radius(model, j, radius_m)
    if motion_path is not None:
        motion = read_task_motion(model, Path(motion_path).absolute())
    elif entry is not None:
        motion = entry.default_motion()
    else:
        motion = default_motion(model)
    kin = solve_kinematics(model, motion.x, motion.xd, motion.xdd, motion.t)
    results = [(j, *joint_wear(model, kin, j, opts, motion.loads)) for j in dict.fromkeys(joints)]
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as out:
        files = write_wear_files(out, model, results, opts, {"motion": str(motion_path) if motion_path
                                                             else "the machine's default motion"})
        from ..report import write_report

        doc = json.loads(files["wear"].read_text(encoding="utf-8"))
        files["report"] = write_report(out, title=f"{model.name}: slide tracks and wear", scene=None,
                                       summary={j["joint"]: j for j in doc["joints"]},
                                       parameters=path.read_text(encoding="utf-8", errors="replace") if path else "",
                                       images=[p for p in files.values() if p.suffix == ".png"],
                                       notes=["definitions: docs/wear.md"],
                                       figures=[(f"{j}: tracks on the cup", tracks_figure(j, c)) for j, c, _, _ in results])
        list_files({k: final / v.name for k, v in files.items()})
    for j, on_cup, on_head, what in results:
        s = on_cup.summary()
        click.echo(f"{j}: {s['markers']} markers; load: {what}; sliding distance per cycle "
                   f"{1e3 * s['sliding_distance_per_cycle_m']['mean']:.4g} mm (mean); aspect ratio median "
                   f"{s['aspect_ratio']['median']:.4g}, share above 5.5: {100 * s['share_aspect_ratio_above_5_5']:.0f} %; "
                   f"cross-shear mean {s['cross_shear']['mean']:.3g}; wear "
                   f"{on_head.wear_per_million_cycles:.4g} mm^3 per million cycles")

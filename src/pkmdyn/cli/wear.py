"""``pkmdyn wear``: slide tracks, cross-shear and Archard wear of a mechanism's spherical joints
along a motion (``docs/wear.md``)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..errors import ParameterError
from ._groups import MACHINE_HELP, PATH_IN, FiniteFloat, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import wear as job
else:  # the engine and its kernels load when the command runs, not for --help
    job = lazy_module("pkmdyn.jobs.wear")



def _pole(text: str | None) -> tuple[float, float, float] | None:
    """``--pole X,Y,Z`` as three numbers (None: not given)."""
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
@click.option("--limit", "limit_items", multiple=True, metavar="KEY=VALUE",
              help="Raise a plausibility limit of the description's numbers ([limits]; the tracks' size: "
                   "max_wear_track_points, markers x samples).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder (an earlier run of this command there is replaced whole).")
def wear(machine: str, joints: tuple[str, ...], motion_path: Path | None, cycles: float, head: str,
         radius_m: float | None, load: str | None, spacing_deg: float, cap_deg: float, pole: str | None,
         wear_factor: float | None, cross_shear_law: str | None, limit_items: tuple[str, ...], out_dir: Path) -> None:
    """Slide tracks of points of the head on the cup (and of the cup on the head), their sliding
    distance, aspect ratio (the share above 5.5), cross-shear, track integral of load and the
    Archard wear per million cycles, for spherical joints of any mechanism."""
    opts = {"radius_m": radius_m, "head": head, "load": load, "spacing_deg": spacing_deg, "cap_deg": cap_deg,
            "pole": _pole(pole), "cross_shear_law": cross_shear_law, "cycles": cycles}
    if wear_factor is not None:
        opts["wear_factor_mm3_N_m"] = wear_factor
    show(job.job(machine, joints, out_dir, motion_path=motion_path, opts=job.WearOptions(**opts), announce=list_files,
                 limit_items=limit_items))

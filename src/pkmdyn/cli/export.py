"""``pkmdyn export``: a machine as MJCF or URDF (:mod:`pkmdyn.jobs.export`)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import MACHINE_HELP, FiniteFloat, cli, list_files, show

if TYPE_CHECKING:
    from ..jobs import export as export_job
else:  # the engine loads when the command runs, not for --help
    export_job = lazy_module("pkmdyn.jobs.export")


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
    show(export_job.job(machine, fmt, out_path, solref=solref, solimp=solimp, timestep_s=timestep_s,
                        massless_kg=massless_kg, announce=list_files))

"""``pkmdyn view``: a page for a machine without running a motion."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from ._groups import PATH_IN, cli, echo


def _listing(path: Path) -> None:
    echo(f"view: {path}")


def _hip_page(params: Path | None, out: Path) -> Path:
    from ..machines.hip_simulator import load_params
    from ..machines.hip_simulator.report import parameters_text
    from ..machines.hip_simulator.scene import hip_mobility, hip_scene_from_angles, hip_topology
    from ..report import write_view

    model = load_params(params)
    scene = hip_scene_from_angles(model, np.zeros(1), np.zeros((1, 3)), np.zeros((1, 3)))
    return write_view(out, title="2(3PUS+S) hip simulator: machine view", scene=scene, topology=hip_topology(),
                      mobility=hip_mobility(model), parameters=parameters_text(params),
                      notes=[f"parameters: {params or 'built-in (paper Tables 1-2)'}", "home pose: all angles zero"],
                      inputs={"--params": params}, listing=_listing)


def _pdm_page(params: Path | None, out: Path) -> Path:
    from ..machines.pdm4.params import load_params
    from ..machines.pdm4.report import parameters_text
    from ..machines.pdm4.scene import pdm_mobility, pdm_scene_from_pose, pdm_topology
    from ..report import write_view

    model = load_params(params)
    scene = pdm_scene_from_pose(model, np.zeros(1), np.zeros((1, 4)), np.zeros((1, 4)))
    return write_view(out, title="4-DOF PDM: machine view", scene=scene, topology=pdm_topology(),
                      mobility=pdm_mobility(model), parameters=parameters_text(params),
                      notes=[f"parameters: {model.source}", "home pose: x = y = 0, alpha = gamma = 0"],
                      inputs={"--params": params}, listing=_listing)


@cli.command("view")
@click.option("--machine", type=click.Choice(["hip", "pdm"]), required=True, help="The machine to show.")
@click.option("--params", "params_path", type=PATH_IN, help="Parameter file (TOML); default: the built-in one.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="HTML file to write (atomically; only a page pkmdyn wrote is replaced).")
def view(machine: str, params_path: Path | None, out_path: Path) -> None:
    """A self-contained HTML page of a machine: home pose in 3D, topology graph, mobility and
    over-constraint counts."""
    from ..io import check_output_file

    check_output_file(out_path, {"--params": params_path})  # the output rule, before any work
    (_hip_page if machine == "hip" else _pdm_page)(params_path, out_path)

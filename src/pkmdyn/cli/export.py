"""Machine export commands: ``pkmdyn hip export --format mjcf``."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN as _PATH_IN
from ._groups import echo, hip
from ._groups import FiniteFloat
from ._hip_options import paper_option

#: the mass [kg] written for a platform of zero mass (the paper gives none; MuJoCo needs a mass on a
#: moving body): its centre of mass sits on the platform's fixed ball joint, so the value changes no
#: dynamics
PLATFORM_MASS_KG = 1e-3


@hip.command("export")
@click.option("--format", "fmt", type=click.Choice(["mjcf"]), required=True,
              help="mjcf: a MuJoCo model of the machine's description (kinematic tree, the loops closed by "
                   "connect constraints, the motors with the screws' gear and rotor inertia; no load, no "
                   "load-dependent friction).")
@paper_option
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--timestep", "timestep_s", type=FiniteFloat(1e-6, 1.0), default=1e-3,
              show_default=True, help="MuJoCo integration step [s], 1e-6 to 1.")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="File to write (e.g. machine.xml).")
def hip_export(fmt, params_path, timestep_s, out_path) -> None:
    """Write the machine in another engine's format (MuJoCo's MJCF, the same writer as pkmdyn
    export --machine hip); the file is written only when the whole model is valid."""
    from ..io import atomic_file, check_output_file
    from ..machines.hip_simulator.description import hip_description
    from ..machines.hip_simulator.params import load_params
    from ..multibody import load_mechanism
    from ..multibody.mjcf import massless_bodies, mechanism_mjcf

    inputs = {"--params": params_path}
    check_output_file(out_path, inputs)
    model = load_mechanism(hip_description(load_params(params_path)))
    light = massless_bodies(model)
    text = mechanism_mjcf(model, timestep_s, massless_kg=PLATFORM_MASS_KG if light else None)
    with atomic_file(out_path, inputs=inputs) as tmp:
        tmp.write_text(text, encoding="utf-8")
        echo(f"{fmt}: {out_path}")

"""Machine export commands: ``pkmdyn hip export --format mjcf``."""

from __future__ import annotations

from pathlib import Path

import click

from ._groups import PATH_IN as _PATH_IN
from ._groups import hip


@hip.command("export")
@click.option("--format", "fmt", type=click.Choice(["mjcf"]), required=True,
              help="mjcf: a MuJoCo model (kinematic tree, six connect loop constraints, slide motors, no friction).")
@click.option("--params", "params_path", type=_PATH_IN, help="Parameter file (TOML); default: the paper's Tables 1-2.")
@click.option("--timestep", "timestep_s", type=click.FloatRange(min=0, min_open=True, max=1.0), default=1e-3,
              show_default=True, help="MuJoCo integration step [s].")
@click.option("--out", "out_path", type=click.Path(dir_okay=False, path_type=Path), required=True,
              help="File to write (e.g. machine.xml).")
def hip_export(fmt, params_path, timestep_s, out_path) -> None:
    """Write the machine in another engine's format (MuJoCo's MJCF); the file is written only
    when the whole model is valid."""
    from ..machines.hip_simulator import load_params
    from ..machines.hip_simulator.mjcf import mjcf_string

    model = load_params(params_path)
    text = mjcf_string(model, timestep_s)
    out_path = Path(out_path)
    if out_path.is_dir():
        raise click.UsageError(f"--out {out_path}: is a folder; give a file name such as machine.xml")
    tmp = out_path.with_name(f".{out_path.name}.partial")
    try:
        out_path.parent.mkdir(parents=True, exist_ok=True)
        tmp.write_text(text, encoding="utf-8")
        tmp.replace(out_path)
    except OSError as exc:
        tmp.unlink(missing_ok=True)
        raise click.UsageError(f"--out {out_path}: cannot write ({exc.strerror or exc})") from None
    click.echo(f"{fmt}: {out_path}")

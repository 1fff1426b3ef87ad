"""``pkmdyn sweep``: design sweeps of any machine with a sweep adapter, in this process or on Dask.

Every check (machine, space file, base parameters, motion, design count, the designs'
validity, the output folder) comes before any design is evaluated; a user error is one line
and exit status 2. The output folder fills batch by batch; a rerun resumes it.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ._groups import PATH_IN, cli, show

if TYPE_CHECKING:
    from ..jobs import sweep as sweep_job
else:  # the sweep, pydantic and Dask load when the command runs, not for --help
    sweep_job = lazy_module("pkmdyn.jobs.sweep")

#: a Dask scheduler address: an optional scheme of Dask's comms, a host, a port
_ADDRESS = re.compile(r"^(?:(?P<scheme>[A-Za-z][A-Za-z0-9+.-]*)://)?"
                      r"(?P<host>\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]]+):(?P<port>\d{1,5})/?$")
_SCHEMES = ("tcp", "tls", "ws", "wss", "ucx")


def check_scheduler(address: str) -> None:
    """A scheduler address of the form ``[scheme://]host:port`` (``scheme`` one of Dask's comms:
    tcp, tls, ws, wss, ucx; ``port`` 1 to 65535), else one line naming what is wrong."""
    m = _ADDRESS.match(address)
    if m is None:
        raise click.UsageError(f"--scheduler {address!r}: expected [scheme://]host:port, e.g. tcp://head:8786")
    if m["scheme"] is not None and m["scheme"].lower() not in _SCHEMES:
        raise click.UsageError(f"--scheduler {address!r}: unknown scheme {m['scheme']!r} "
                               f"(one of {', '.join(_SCHEMES)})")
    if not 1 <= int(m["port"]) <= 65535:
        raise click.UsageError(f"--scheduler {address!r}: port {m['port']} is not from 1 to 65535")


_MACHINE_HELP = ("Machine to sweep: a built-in machine (see pkmdyn machines) or a mechanism "
                 "description FILE.toml.")


@cli.command("sweep")
@click.option("--machine", required=True, metavar="NAME", help=_MACHINE_HELP)
@click.option("--space", "space_path", type=PATH_IN, required=True,
              help="Space file (TOML): swept keys, sampling, motion, constraints, objectives (docs/sweep.md).")
@click.option("--params", "params_path", type=PATH_IN, default=None,
              help="Base parameter file (overrides the space file's params; default: the machine's built-in one).")
@click.option("--workers", type=click.IntRange(min=0, max=4096), default=None,
              help="Local Dask worker processes (default: one per CPU core; 0: in this process, without Dask).")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="Address of a running Dask scheduler (e.g. tcp://head:8786) instead of a local cluster.")
@click.option("--batch-size", type=click.IntRange(min=1, max=1_000_000), default=None,
              help="Designs per task (default: [sampling] batch_size, else about 8 tasks per worker, 10 to 250).")
@click.option("--limit", "limits", multiple=True, metavar="max_designs=N",
              help="Raise the design limit (default 100,000; also [sampling] max_designs).")
@click.option("--search", type=click.Choice(["grid", "random", "lhs", "sobol", "nsga2"]), default=None,
              help="Sampling method, in place of the space file's [sampling] method (nsga2: the population is "
                   "[sampling] designs, run for [sampling] generations).")
@click.option("--no-plots", is_flag=True, help="Write no PNG plots.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), required=True,
              help="Output folder; a rerun on the same folder and space resumes, skipping finished designs.")
def sweep(machine: str, space_path: Path, params_path: Path | None, workers: int | None, scheduler: str | None,
          batch_size: int | None, limits: tuple[str, ...], search: str | None, no_plots: bool, out_dir: Path) -> None:
    """Evaluate many designs of a machine; write designs.parquet, the Pareto set, the best design, plots."""

    if workers is not None and scheduler is not None:
        raise click.UsageError("--workers and --scheduler: give one of them (a scheduler has its own workers)")
    if scheduler is not None:
        check_scheduler(scheduler)
    try:
        result = sweep_job.job(machine, space_path, out_dir, params_path=params_path, workers=workers,
                               scheduler=scheduler, batch_size=batch_size, limit_items=limits, search=search,
                               no_plots=no_plots)
    except KeyboardInterrupt:
        # not the generic line of a single run: a sweep's folder keeps what it finished
        click.echo(f"pkmdyn: interrupted; the finished batches are kept in {out_dir / 'parts'}; rerun the same "
                   "command to resume", err=True)
        raise click.exceptions.Exit(130) from None
    show(result)

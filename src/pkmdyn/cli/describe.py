"""``pkmdyn machines`` and ``pkmdyn describe``: the built-in machines, and what one machine is
(:mod:`pkmdyn.jobs.describe`).

``--machine`` takes a built-in name (``pkmdyn machines``) or a description ``FILE.toml``; an
unknown name is refused, never routed to another machine's code.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import click

from .._lazy import lazy_module
from ..machines.registry import builtin_names
from ._groups import MACHINE_HELP, cli, show

if TYPE_CHECKING:
    from ..jobs import describe as describe_job
else:  # the engine loads when the command runs, not for --help
    describe_job = lazy_module("pkmdyn.jobs.describe")


@cli.command("machines")
def machines() -> None:
    """List the built-in machines, one name a line."""
    for name in builtin_names():
        click.echo(name)


@cli.command("describe")
@click.option("--machine", required=True, help=MACHINE_HELP)
def describe(machine: str) -> None:
    """Print the topology, mobility and over-constraints of a machine."""
    show(describe_job.job(machine))

"""The hip commands' ``--paper`` option: the built-in parameter file of the paper's own
convention (``machines/hip_simulator/paper.toml``; docs/hip_simulator.md) in place of
``--params``."""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any

import click


def paper_option(f: Callable[..., Any]) -> Callable[..., Any]:
    """Add ``--paper`` to a hip command that has ``--params`` (keyword ``params_path``)."""

    @click.option("--paper", is_flag=True,
                  help="Use the paper's own convention (FE about the base Z axis, the paper-fit-zxy ISO cycle): the "
                       "built-in paper.toml in place of --params; docs/hip_simulator.md.")
    @functools.wraps(f)
    def wrapped(*args: Any, paper: bool, **kwargs: Any) -> Any:
        if paper:
            if kwargs.get("params_path") is not None:
                raise click.UsageError("--paper and --params exclude each other: --paper is a built-in parameter file")
            from ..machines.hip_simulator.params import paper_params_path

            kwargs["params_path"] = paper_params_path()
        return f(*args, **kwargs)

    return wrapped

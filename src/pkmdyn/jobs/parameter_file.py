"""``pkmdyn <machine> params``: a generated machine's built-in parameter file, or its control
settings, written for a user to edit (every key with its unit and a comment)."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from pathlib import Path

from ..control import default_settings_text
from ..machines.registry import generated
from ._files import JobResult, write_texts

__all__ = ["job"]


def job(machine: str, out_path: Path, *, control: bool = False,
        announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """The built-in parameter file of the generated machine ``machine`` (with ``control``: its
    control settings, what ``control --gains`` takes) into ``out_path``."""
    if control:
        label, text = "control settings", default_settings_text(machine)
    else:
        label, text = "parameters", generated(machine).default_params_text()
    return JobResult(write_texts({label: (Path(out_path), text)}, {}, announce))

"""What every job shares: the machine it is given and its result.

A job runs in three steps:

1. :func:`prepare`: the machine resolved (a built-in name or a description file), the output
   folder checked against the output rule before anything is computed (:func:`pkmdyn.io.check_output_dir`:
   no input, link, device or foreign folder is ever replaced) and the mechanism compiled;
2. the job's own computation (the engine's free functions);
3. its files written by the one writer of ``--out``, :func:`pkmdyn.report.write_output`: the job's
   own files, ``summary.json`` and ``report.html`` (a :class:`pkmdyn.report.Report`) into a temporary
   folder beside ``--out``, announced, and moved into place only once all of them are written.

A job returns a :class:`JobResult`; the command prints it and writes nothing itself.
"""

from __future__ import annotations

import contextlib
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._lazy import lazy_module
from ..io import atomic_file, check_output_dir, check_output_file
from ..machines.registry import resolve
from ..report._output import JobResult

if TYPE_CHECKING:
    from ..multibody.model import compiler as _compiler
    from ..multibody.model.compiler import MechanismModel
else:  # the compiler and its kernels load when a job runs: a command module may import its job for --help
    _compiler = lazy_module("pkmdyn.multibody.model.compiler")

__all__ = ["JobResult", "Prepared", "prepare", "load_machine", "write_texts"]


@dataclass(frozen=True)
class Prepared:
    """A job's machine: the compiled ``model``, its registry ``entry`` (a generated machine's
    module; None for a described one), its description file ``path`` (None for a generated
    machine), that file's ``text`` for the report, and the run's ``inputs`` (option -> path), which
    no output may replace."""

    model: MechanismModel
    entry: Any
    path: Path | None
    text: str
    inputs: Mapping[str, Path | None]


def load_machine(machine: str, limits: Mapping[str, float] | None = None) -> tuple[MechanismModel, Any]:
    """The compiled mechanism of ``machine`` (a generated machine through the description its
    folder makes) and its registry entry (None for a described one); ``limits`` (``--limit``) over
    the description's own for the plausibility of its numbers."""
    entry, path = resolve(machine)
    return _compiler.load_mechanism(path if entry is None else entry.description(), limits), entry


def prepare(machine: str, out_dir: Path | None, inputs: Mapping[str, Path | None] | None = None,
            limits: Mapping[str, float] | None = None) -> Prepared:
    """Resolve ``machine``, check ``out_dir`` (when given) against the output rule with the run's
    ``inputs`` (the machine's file added), then compile the mechanism: a bad folder is refused
    before any computation and nothing is written."""
    entry, path = resolve(machine)
    given = {"--machine": path, **(inputs or {})}
    if out_dir is not None:
        check_output_dir(out_dir, given)
    model, entry = load_machine(machine, limits)
    text = path.read_text(encoding="utf-8", errors="replace") if path is not None else ""
    return Prepared(model, entry, path, text, given)


def write_texts(texts: Mapping[str, tuple[Path, str]], inputs: Mapping[str, Path | None],
                announce: Callable[[Mapping[str, Path]], None] | None = None) -> dict[str, Path]:
    """Write the text files of a job whose ``--out`` is a file (an export, an import): label ->
    ``(path, text)``, each path checked (:func:`pkmdyn.io.check_output_file`, before anything is
    written) and written whole or not at all (:func:`pkmdyn.io.atomic_file`): all are written under
    temporary names, ``announce`` is given their paths (so the listing is out, as for a folder,
    before anything moves), and only then do they move into place, one rename each; a failure
    while writing or listing them (a full standard output included) leaves none of them. Returns
    label -> path."""
    for path, _ in texts.values():
        check_output_file(path, inputs)
    placed = {k: p for k, (p, _) in texts.items()}
    with contextlib.ExitStack() as stack:
        for path, text in texts.values():
            stack.enter_context(atomic_file(path, inputs=inputs)).write_text(text, encoding="utf-8")
        if announce is not None:
            announce(placed)
    return placed

"""Jobs: files in, files out, one module per command's work (``docs/architecture.md``).

Each module's ``job(...)`` resolves the machine, checks ``--out`` against the output rule before
anything is computed, calls the engine's free functions, writes its files through the one writer
(:func:`pkmdyn.report.write_output`) and returns a :class:`JobResult`: ``run`` (``pkmdyn run``), ``stiffness``,
``wear``, ``workspace``, ``assemble``, ``identify``. The commands print the result; the engine writes nothing."""

from __future__ import annotations

from typing import TYPE_CHECKING

from .._lazy import attach

if TYPE_CHECKING:
    from ._files import JobResult, Prepared, load_machine, prepare

__all__ = ["JobResult", "Prepared", "load_machine", "prepare"]

__getattr__, __dir__ = attach(__name__, dict.fromkeys(__all__, "._files"))

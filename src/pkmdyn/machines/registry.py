"""The one list of built-in machines, read off the folders under ``machines/``.

Two kinds of folder make a built-in machine, and nothing else has to change to add one:

- a *described* machine: ``machines/<name>/<name>.toml``, a mechanism description
  (:mod:`pkmdyn.multibody`);
- a *generated* machine (the two papers' machines): a package ``machines/<folder>/`` whose
  module ``machine.py`` turns the machine's own parameter file into a mechanism description.
  It says ``NAME``, ``TITLE``, ``CONTROL_SETTINGS`` (a path) and provides
  ``default_params_text()``, ``description(params=None)`` (the parameter file ``params``, the
  built-in one by default, as a mechanism description), ``default_motion()`` (a
  :class:`pkmdyn.multibody.TaskMotion`) and either ``parameters_text(params)`` (``pkmdyn view``
  then draws the engine's page of the description) or ``view_page(params, out, listing)`` (a
  page of its own). Optional modules beside it: ``commands.py`` (a click group ``group``: the
  machine's own commands, ``pkmdyn <NAME> ...``, mounted by :func:`command_groups`),
  ``described_sweep.py`` (the hooks of :class:`pkmdyn.multibody.analyses.designs.GeneratedSweep`: its
  parameter file's schema, the description generated from a parameter file, its motion and
  metrics; the machine is then swept on the engine) or ``sweep.py`` (a sweep of its own,
  :mod:`pkmdyn.sweep_protocol`), and ``control_job.py`` (a control job,
  :mod:`pkmdyn.control_protocol`).

Every command that takes ``--machine`` resolves it here; an unknown name is refused, never
routed to another machine's code.
"""

from __future__ import annotations

import difflib
import functools
import importlib
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING, Any

from .._lazy import lazy_module
from ..errors import ParameterError

if TYPE_CHECKING:
    from ..multibody.analyses import designs as _designs
else:  # the sweep adapters (and the engine) load when a sweep asks for one, not for the machine list
    _designs = lazy_module("pkmdyn.multibody.analyses.designs")

__all__ = ["described_machines", "generated_machines", "generated", "command_groups", "builtin_names", "description_path",
           "resolve", "title", "sweep_adapter", "control_adapter"]

_HERE = Path(__file__).resolve().parent
#: the module of a generated machine's folder that generates its mechanism description from its
#: parameter file, for sweeps on the engine (:class:`pkmdyn.multibody.analyses.designs.GeneratedSweep`)
GENERATOR = "described_sweep"


def described_machines() -> dict[str, Path]:
    """Every folder ``machines/<name>/`` that holds ``<name>.toml``: name -> description file."""
    out = {}
    for folder in sorted(_HERE.iterdir()):
        f = folder / f"{folder.name}.toml"
        if folder.is_dir() and f.is_file():
            out[folder.name] = f
    return out


@functools.cache
def generated_machines() -> dict[str, ModuleType]:
    """Every package ``machines/<folder>/`` with a ``machine.py``: its ``NAME`` -> that module."""
    out: dict[str, ModuleType] = {}
    for folder in sorted(_HERE.iterdir()):
        if folder.is_dir() and (folder / "machine.py").is_file() and (folder / "__init__.py").is_file():
            module = importlib.import_module(f"{__package__}.{folder.name}.machine")
            out[module.NAME] = module
    return out


def generated(name: str) -> ModuleType:
    """The registry entry (``machine.py`` module) of the generated machine ``name``."""
    machines = generated_machines()
    if name not in machines:
        raise ParameterError(f"machine {name!r}: not a generated machine (those are: {', '.join(sorted(machines))})")
    return machines[name]


def builtin_names() -> list[str]:
    """All built-in machine names, sorted."""
    return sorted({*described_machines(), *generated_machines()})


def title(name: str) -> str:
    """One line saying what built-in machine ``name`` is."""
    if name in generated_machines():
        return generated_machines()[name].TITLE
    return f"described mechanism {description_path(name)}"


def description_path(name: str) -> Path:
    """The description file of the described built-in machine ``name``."""
    described = described_machines()
    if name in described:
        return described[name]
    if name in generated_machines():
        raise ParameterError(f"--machine {name}: a machine generated from its parameter file, without a description file ({title(name)})")
    close = difflib.get_close_matches(name, builtin_names(), n=1)
    raise ParameterError(f"--machine {name}: unknown machine ({f'did you mean {close[0]}? ' if close else ''}"
                         f"built-in: {', '.join(builtin_names())}; or give a description FILE.toml)")


def resolve(machine: str) -> tuple[ModuleType | None, Path | None]:
    """``(entry, None)`` for a generated machine (its ``machine.py`` module), ``(None, path)`` for
    a described built-in or a description ``FILE.toml``; anything else is refused."""
    if machine in generated_machines():
        return generated_machines()[machine], None
    if machine in described_machines():
        return None, described_machines()[machine]
    p = Path(machine)
    if p.suffix.lower() == ".toml" or p.exists():
        return None, p
    if p.suffix or len(p.parts) > 1:  # a path, not a name: say that the file is missing
        raise ParameterError(f"--machine {machine}: no such file (and no built-in machine of that name)")
    return None, description_path(machine)


def sweep_adapter(name: str) -> Any:
    """The sweep adapter (:class:`pkmdyn.sweep_protocol.SweepAdapter`) of ``name``: a generated
    machine's own ``sweep.py`` module; for a generated machine whose folder holds a description
    generator (``described_sweep.py``: its parameter file turned into a mechanism description)
    the generic adapter of generated descriptions (:class:`pkmdyn.multibody.analyses.designs.GeneratedSweep`);
    for a described machine (a built-in name or a description ``FILE.toml``) the generic adapter
    of its description (:class:`pkmdyn.multibody.analyses.designs.DescribedSweep`)."""
    machines = generated_machines()
    shown = name if len(name) <= 60 else name[:60] + "..."
    if name not in machines:
        entry, path = resolve(name)
        assert entry is None and path is not None
        return _designs.DescribedSweep.from_file(path)
    folder = Path(machines[name].__file__).parent
    if (folder / "sweep.py").is_file():
        return importlib.import_module(f"{machines[name].__package__}.sweep")
    if (folder / f"{GENERATOR}.py").is_file():
        return _designs.GeneratedSweep.from_module(f"{machines[name].__package__}.{GENERATOR}")
    raise ParameterError(f"--machine {shown!r}: this machine has no sweep adapter")


def control_adapter(name: str) -> ModuleType:
    """The control adapter (``control_job.py`` of its folder,
    :class:`pkmdyn.control_protocol.ControlJob`) of the generated machine ``name``."""
    entry = generated(name)
    if not (Path(entry.__file__).parent / "control_job.py").is_file():
        raise ParameterError(f"machine {name!r}: this machine has no control job")
    return importlib.import_module(f"{entry.__package__}.control_job")


def command_groups() -> list[Any]:
    """The click groups of the machines' own commands (``commands.py`` of a generated machine's
    folder: its ``group``), for the command line to mount."""
    out = []
    for entry in generated_machines().values():
        if (Path(entry.__file__).parent / "commands.py").is_file():
            out.append(importlib.import_module(f"{entry.__package__}.commands").group)
    return out

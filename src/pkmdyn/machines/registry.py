"""The one list of built-in machines.

A *described* machine is a folder under ``machines/`` holding ``<name>.toml`` (a mechanism
description, :mod:`pkmdyn.multibody`): adding one is adding the folder and the file. The two
papers' machines are hand-built (their own packages and commands, ``pkmdyn hip ...``,
``pkmdyn pdm ...``). Both folders also turn their parameters into a description
(``hip_simulator/description.py``, ``pdm4/description.py``), which ``pkmdyn describe`` and
``pkmdyn run --machine hip|pdm`` use: every machine's run writes the same files.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ParameterError

__all__ = ["HAND_BUILT", "described_machines", "builtin_names", "description_path", "resolve",
           "hand_built_description", "hand_built_motion"]

_HERE = Path(__file__).resolve().parent

#: hand-built machines: name -> what it is
HAND_BUILT = {
    "hip": "2(3PUS+S) dual-platform hip-joint wear simulator (Chen, Cheng & Pang 2022); see pkmdyn hip --help",
    "pdm": "4-DOF over-constrained parallel driving mechanism (Huang et al. 2023); see pkmdyn pdm --help",
}


def described_machines() -> dict[str, Path]:
    """Every folder ``machines/<name>/`` that holds ``<name>.toml``: name -> description file."""
    out = {}
    for folder in sorted(_HERE.iterdir()):
        f = folder / f"{folder.name}.toml"
        if folder.is_dir() and f.is_file():
            out[folder.name] = f
    return out


def builtin_names() -> list[str]:
    """All built-in machine names, sorted."""
    return sorted({*described_machines(), *HAND_BUILT})


def description_path(name: str) -> Path:
    """The description file of built-in machine ``name``."""
    described = described_machines()
    if name in described:
        return described[name]
    if name in HAND_BUILT:
        raise ParameterError(f"--machine {name}: a hand-built machine without a description file ({HAND_BUILT[name]})")
    raise ParameterError(f"--machine {name}: unknown machine (built-in: {', '.join(builtin_names())}; "
                         "or give a description FILE.toml)")


def hand_built_description(name: str) -> dict | None:
    """The description a hand-built machine's folder makes from its built-in parameters, or None."""
    if name == "hip":
        from .hip_simulator import load_params
        from .hip_simulator.description import hip_description

        return hip_description(load_params())
    if name == "pdm":
        from .pdm4 import load_params as load_pdm
        from .pdm4.description import pdm_description

        return pdm_description(load_pdm())
    return None


def hand_built_motion(name: str):
    """The default task motion of a hand-built machine for ``pkmdyn run --machine``: the hip's
    ISO 14242-1 cycle (one cycle, 1000 samples), the PDM's Eq. 84 motion of its parameters;
    as a :class:`pkmdyn.multibody.TaskMotion` in the order of the description's task."""
    from ..multibody import TaskMotion

    if name == "hip":
        from ..profiles.iso14242 import iso14242_motion

        m = iso14242_motion(cycles=1, samples_per_cycle=1000)
        return TaskMotion(m.t, m.angles, m.rates, m.accels)
    from ..profiles.pdm_motion import cycloidal_motion
    from .pdm4 import load_params as load_pdm

    tr = load_pdm().trajectory
    m = cycloidal_motion(tr.strokes, tr.period_s, tr.samples)
    return TaskMotion(m.t, m.q, m.qd, m.qdd)


def resolve(machine: str) -> tuple[str, Path | None]:
    """``("described", path)`` for a built-in description or a ``.toml`` file, ``("hip", None)`` or
    ``("pdm", None)`` for a hand-built machine; anything else is refused, never guessed."""
    if machine in HAND_BUILT:
        return machine, None
    if machine in described_machines():
        return "described", described_machines()[machine]
    p = Path(machine)
    if p.suffix.lower() == ".toml" or p.exists():
        return "described", p
    return "described", description_path(machine)

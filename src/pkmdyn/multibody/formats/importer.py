"""``pkmdyn import``: a model file to a checked description's TOML text (docs/import.md)."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ...errors import ParameterError, PkmdynError
from ...io import dumps_toml
from ..kinematics.inverse import solve_kinematics
from ..kinematics.motion import default_motion
from ..model.compiler import load_mechanism
from .graph import Graph, TaskChoice, description_from_graph
from .mjcf_in import mjcf_graph
from .sdf_in import sdf_graph
from .urdf_in import read_sidecar, sidecar_task, urdf_graph


def read_graph(path: Path, fmt: str, sidecar: Path | None = None, actuated: tuple[str, ...] = (),
               assemble: bool = False, keyframe: str | None = None, weld_free: bool = False
               ) -> tuple[Graph, TaskChoice]:
    """The file's :class:`~pkmdyn.multibody.formats.graph.Graph` and the task its sidecar asks for."""
    choice = TaskChoice()
    if fmt == "mjcf":
        for flag, given in (("--sidecar", sidecar), ("--actuated", actuated)):
            if given:
                raise ParameterError(f"{flag}: not for MJCF (its equalities close the loops, its actuators drive)")
        g = mjcf_graph(path, keyframe, weld_free, assemble)
        return g, g.task or choice
    if keyframe is not None:
        raise ParameterError("--keyframe: only for MJCF")
    if weld_free:
        raise ParameterError("--weld-free: only for MJCF (its free joints)")
    if fmt == "urdf":
        side = read_sidecar(sidecar) if sidecar is not None else None
        if side is not None:
            choice = sidecar_task(side)
        return urdf_graph(path, side, actuated, assemble), choice
    if fmt == "sdf":
        if sidecar is not None:
            raise ParameterError("--sidecar: not for SDFormat (a link with several parent joints closes a loop)")
        return sdf_graph(path, actuated, assemble), choice
    raise ParameterError(f"--format {fmt}: one of mjcf, urdf, sdf")


def _merge(asked: TaskChoice, side: TaskChoice) -> TaskChoice:
    return TaskChoice(body=asked.body or side.body, point=asked.point if asked.point is not None else side.point,
                      position=asked.position if asked.position is not None else side.position,
                      orientation=asked.orientation if asked.orientation is not None else side.orientation,
                      sequence=asked.sequence or side.sequence,
                      joints=asked.joints if asked.joints is not None else side.joints)


#: the default motion's amplitude is divided by this until the mechanism follows it
SHRINK = 4.0
TRIES = 5


def _fit_default_motion(model, desc: dict, notes: list[str]) -> None:
    """Shrink ``[default_motion]`` until the kinematics of ``model`` (``desc`` compiled) follows
    it (an imported reference configuration may lie near a singularity); none at all after
    ``TRIES``, said in the notes."""
    amp = desc["default_motion"]["amplitude"]
    for k in range(TRIES):
        mo = default_motion(replace(model, motion=replace(model.motion, amplitude=dict(amp))))
        try:
            solve_kinematics(model, mo.x, mo.xd, mo.xdd, mo.t)
            if k:
                notes.append(f"default motion: amplitudes divided by {SHRINK ** k:g} to stay reachable")
            return
        except PkmdynError:
            for c in amp:
                amp[c] /= SHRINK
    desc["default_motion"]["amplitude"] = {}
    notes.append("default motion: the mechanism stays at its reference configuration (no small motion about it "
                 "was reachable; the reference may be near a singularity)")


def import_description(path: Path, fmt: str, *, sidecar: Path | None = None, actuated: tuple[str, ...] = (),
                       assemble: bool = False, keyframe: str | None = None,
                       choice: TaskChoice = TaskChoice(), weld_free: bool = False) -> tuple[str, list[str]]:
    """TOML text of the description of ``path`` (loaded and checked as ``run`` loads it) and
    the import's notes."""
    graph, side = read_graph(path, fmt, sidecar, actuated, assemble, keyframe, weld_free)
    desc, notes = description_from_graph(graph, _merge(choice, side))
    model = load_mechanism(desc)  # what describe and run will do with the file
    if model.topology.overconstraints:
        desc["mechanism"]["reactions"] = "minimum-norm"
        notes.append(f"over-constrained ({model.topology.overconstraints} self-stress states): the efforts are unique; "
                     "the file holds no link compliance, so [mechanism] reactions = \"minimum-norm\" (runs write "
                     "the minimum-norm joint reactions, flagged); [[bodies]] section and material make them unique")
    if model.na < model.topology.dof:
        notes.append(f"under-actuated: {model.na} actuators for {model.topology.dof} degrees of freedom; a task motion's "
                     "efforts exist only where it is dynamically consistent (pkmdyn run refuses it elsewhere; its default motion "
                     "drives the actuators and simulates the other freedoms)")
    if model.na > model.topology.dof:
        notes.append(f"redundantly actuated: {model.na} actuators for {model.topology.dof} degrees of freedom; the "
                     "efforts are the minimum-norm ones unless an [actuation] section says otherwise "
                     "(docs/mechanism_format.md, \"Redundant actuation\")")
    _fit_default_motion(model, desc, notes)
    header = "\n".join([f"Imported by pkmdyn import from {graph.source} ({fmt.upper()}).",
                        "Base frame, reference configuration: the file's (docs/import.md).", *notes])
    return dumps_toml(desc, header=header), notes

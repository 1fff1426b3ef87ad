"""A machine generated as a description (a paper's machine) on the engine: its model (its own
parameters and the compiled mechanism of their description) and its verbs under its own names
(:class:`pkmdyn.machine_protocol.MachineDynamics`, the engine's
:class:`pkmdyn.multibody.dynamics.verbs.MechanismVerbs` renamed), for its control adapter."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..errors import ParameterError
from ..multibody.dynamics.verbs import MechanismVerbs
from ..multibody.model.compiler import MechanismModel

__all__ = ["GeneratedModel", "RenamedVerbs"]


@dataclass(frozen=True)
class GeneratedModel:
    """A machine generated as a description (a paper's machine): its own parameters ``params``
    (for its motions and drawings) and the compiled mechanism of their description, the model
    :class:`RenamedVerbs` run on."""

    params: Any
    mechanism: MechanismModel


class RenamedVerbs:
    """The verbs of a machine generated as a description (a paper's machine), under its own
    names: ``COORDINATES`` and ``ACTUATORS`` renamed (same order and units as the
    description's), every verb the :class:`MechanismVerbs` one of the compiled mechanism that
    its models carry as ``.mechanism`` (a model object that also carries the paper's
    parameters, for its motions and drawings)."""

    def __init__(self, mechanism: MechanismModel, coordinates: tuple[str, ...], actuators: tuple[str, ...]) -> None:
        if len(coordinates) != mechanism.nt or len(actuators) != mechanism.na:
            raise ParameterError(f"mechanism {mechanism.name!r}: {mechanism.nt} task coordinates and {mechanism.na} "
                                 f"actuators, renamed as {len(coordinates)} and {len(actuators)}")
        self._verbs = MechanismVerbs(mechanism)
        self.COORDINATES = tuple(coordinates)
        self.ACTUATORS = tuple(actuators)

    def __getattr__(self, name: str) -> Any:
        verb = None if name.startswith("_") else getattr(self._verbs, name, None)
        if not callable(verb):
            raise AttributeError(name)

        def on_mechanism(model: Any, *args: Any, **kwargs: Any) -> Any:
            return verb(model.mechanism, *args, **kwargs)

        on_mechanism.__doc__ = verb.__doc__
        setattr(self, name, on_mechanism)  # made once: a loop's calls then find it as an attribute
        return on_mechanism

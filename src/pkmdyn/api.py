"""The library's public verbs: a machine loaded once, then free functions over it.

``import pkmdyn`` gives them (imported on first use)::

    m = pkmdyn.load("stewart")                 # a built-in name, a description FILE.toml or dict,
                                               # or a generated machine with params=FILE.toml
    kin = pkmdyn.kinematics(m)                 # along its default motion, or a TaskMotion
    dyn = pkmdyn.dynamics(m, kin)              # efforts, every joint's reaction, friction, motors
    dyn.columns()                              # the dynamics columns of ``pkmdyn run``'s results

Each verb returns the engine's frozen result (shapes and units in its docstring): the
kinematics of every body and joint (:class:`pkmdyn.multibody.MechanismKinematics`), the
dynamics (:class:`Dynamics`), the direct kinematics and assembly modes
(:mod:`pkmdyn.multibody.kinematics.direct`), the stiffness (:mod:`pkmdyn.multibody.analyses.stiffness`), a
spherical joint's slide tracks (:mod:`pkmdyn.multibody.analyses.wear`), the workspace on a grid
(:mod:`pkmdyn.multibody.analyses.workspace`), the fastest or least-energy timing of a path
(:mod:`pkmdyn.multibody.analyses.retime`) and the identification of the inertial and friction
parameters from efforts (:mod:`pkmdyn.identify.described`). The engine writes no files;
the commands (``pkmdyn run``, ...) are these verbs plus their files.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from ._lazy import lazy_module
from .errors import ParameterError
from .identify._base import DEFAULT_RANK_TOL
from .identify.described import effort_columns as measured_columns
from .identify.described import fit_described
from .machines.registry import resolve, sweep_adapter
from .multibody import default_motion as motion
from .multibody import load_mechanism, solve_kinematics
from .multibody.analyses.retime import RetimeLimits, task_path
from .multibody.analyses.retime import retime as fastest_timing
from .multibody.analyses.retime_energy import retime_energy
from .multibody.analyses.stiffness import stiffness as k
from .multibody.analyses.task_grid import parse_grid, parse_pose, parse_ranges
from .multibody.analyses.wear import WearOptions, joint_wear
from .multibody.analyses.workspace import workspace as reach
from .multibody.columns import effort_columns
from .multibody.dynamics.actuators import motor_efforts
from .multibody.dynamics.newton_euler import joint_reactions
from .multibody.dynamics.verbs import machine_verbs
from .multibody.kinematics.direct import assembly_modes as modes
from .multibody.kinematics.direct import direct_kinematics as direct

if TYPE_CHECKING:
    from .jobs import sweep as _sweep_job
else:  # the sweep (pydantic, PyArrow, Dask) loads when a sweep is asked for, not with the other verbs
    _sweep_job = lazy_module("pkmdyn.jobs.sweep")

__all__ = ["load", "default_motion", "kinematics", "Dynamics", "dynamics", "forward_dynamics", "direct_kinematics",
           "assembly_modes", "stiffness", "wear", "workspace", "retime", "identification", "Designs", "designs"]

Array = NDArray[np.float64]

#: what the verbs remember of the objects they made, by the object (held weakly): a generated
#: machine's own default motion for each model :func:`load` made of one, and the named loads of
#: the motion each :func:`kinematics` was solved along; so that ``kinematics(load("hip"))`` and
#: ``dynamics`` on it are what ``pkmdyn run --machine hip`` computes (the ISO 14242-1 cycle and
#: its hydraulic load, which a description's ``[default_motion]`` cannot hold)
_own_motions: dict[int, tuple[weakref.ref, Callable[[], Any]]] = {}
_motion_loads: dict[int, tuple[weakref.ref, Mapping[str, Array]]] = {}


def _remember(table: dict, obj: Any, value: Any) -> None:
    table[id(obj)] = (weakref.ref(obj), value)
    weakref.finalize(obj, table.pop, id(obj), None)


def _recall(table: dict, obj: Any) -> Any:
    held = table.get(id(obj))
    return held[1] if held is not None and held[0]() is obj else None


def load(machine: str | Path | Mapping[str, Any], params: str | Path | None = None) -> Any:
    """The compiled mechanism (:class:`pkmdyn.multibody.MechanismModel`) of ``machine``: a
    built-in machine's name (``pkmdyn machines``), a description file (``docs/mechanism_format.md``)
    or a description as a dict; ``params``: the parameter file of a machine that generates its
    description from one (the papers' machines; default its built-in parameters)."""

    if isinstance(machine, Mapping):
        if params is not None:
            raise ParameterError("params: a description given as a dict takes no parameter file")
        return load_mechanism(dict(machine))
    entry, path = resolve(str(machine))
    if entry is not None:
        model = load_mechanism(entry.description(None if params is None else Path(params)))
        if hasattr(entry, "default_motion"):  # a paper's machine: its commands' own default motion
            _remember(_own_motions, model, entry.default_motion)
        return model
    if params is not None:
        raise ParameterError(f"params: {machine} is a description; only a generated machine takes a parameter file")
    return load_mechanism(path)


def default_motion(model: Any) -> Any:
    """The default task motion (:class:`pkmdyn.multibody.TaskMotion`) that the commands take for
    ``model``: a paper's machine's own where :func:`load` made ``model`` of one (the hip's ISO
    14242-1 cycle with its hydraulic load, the PDM's Eq. 84 motion), else the description's."""
    own = _recall(_own_motions, model)
    return own() if own is not None else motion(model)


def kinematics(model: Any, motion: Any = None) -> Any:
    """Every body's and joint's kinematics (:class:`pkmdyn.multibody.MechanismKinematics`) along
    ``motion`` (a :class:`pkmdyn.multibody.TaskMotion`; default :func:`default_motion`); its
    named loads are what :func:`dynamics` takes along these kinematics unless given others."""
    m = default_motion(model) if motion is None else motion
    kin = solve_kinematics(model, m.x, m.xd, m.xdd, m.t)
    if m.loads:
        _remember(_motion_loads, kin, dict(m.loads))
    return kin


@dataclass(frozen=True)
class Dynamics:
    """The inverse dynamics along a motion: ``reactions`` (:class:`pkmdyn.multibody.dynamics.newton_euler.JointReactions`:
    actuator efforts ``u (n, na)``, every joint's force ``(n, nj, 3)`` [N] and moment [N m],
    the friction, the effort split), ``motors`` (:class:`pkmdyn.multibody.dynamics.actuators.MotorEfforts`:
    each drive's motor effort and its parts ``(n, na)``), and the kinematics and named loads
    they were computed on."""

    model: Any
    kin: Any
    reactions: Any
    motors: Any
    named: Mapping[str, Array]

    def columns(self) -> dict[str, Array]:
        """The dynamics' columns of ``pkmdyn run``'s results table, by name (unit-suffixed)."""
        return effort_columns(self.model, self.kin, self.reactions, self.named)


def dynamics(model: Any, kin: Any, loads: Mapping[str, Array] | None = None) -> Dynamics:
    """Actuator and motor efforts with every joint's reaction and the joints' friction (the
    load-dependent friction iterated on the reactions) along ``kin``; ``loads``: the named
    loads' magnitudes per sample (``{name: (n,)}`` [N or N m]; by default those of the motion
    :func:`kinematics` solved ``kin`` along, else the description's ``magnitude_N``)."""

    named = dict(loads if loads is not None else (_recall(_motion_loads, kin) or {}))
    reac = joint_reactions(model, kin, named=named, split=True)
    return Dynamics(model, kin, reac, motor_efforts(model, kin.act_q, kin.act_qd, kin.act_qdd, reac.u), named)


def forward_dynamics(model: Any, x: Array, xd: Array, u: Array, load: Array | None = None) -> Array:
    """Task accelerations ``xdd (n, nt)`` under efforts ``u (n, na)`` (a drive's motor effort,
    as :attr:`Dynamics.motors`) at task poses ``x`` and rates ``xd (n, nt)``; ``load (n,)``: a
    mechanism's one named load's magnitudes."""
    return machine_verbs(model).forward_dynamics(model, x, xd, u, load)


def direct_kinematics(model: Any, s: Array, sd: Array | None = None, sdd: Array | None = None,
                      t: Array | None = None) -> Any:
    """The task pose and every body along an actuator motion ``s, sd, sdd (n, na)``
    (:func:`pkmdyn.multibody.kinematics.direct.direct_kinematics`)."""
    return direct(model, s, sd, sdd, t)


def assembly_modes(model: Any, s: Array, starts: int | None = None, seed: int = 0, patience: int = 5000) -> Any:
    """Every assembly mode found at the actuator coordinates ``s (na,)``
    (:func:`pkmdyn.multibody.kinematics.direct.assembly_modes`): ``starts`` starts, or by default
    until ``patience`` consecutive starts found no new mode."""
    return modes(model, s, starts, seed, patience)


def stiffness(model: Any, kin: Any, rotors: str = "held") -> Any:
    """The Cartesian stiffness of the task body with the actuators locked, per sample of ``kin``
    (:func:`pkmdyn.multibody.analyses.stiffness.stiffness`; the description needs a compliance source);
    the modes with the drives' rotors ``"held"`` or ``"moving"`` (both frequency sets are kept);
    ``.columns(model)`` gives the columns ``pkmdyn stiffness`` writes for these poses."""
    return k(model, kin, rotors=rotors)


def wear(model: Any, kin: Any, joint: str, radius_m: float | None = None, load: str | None = None,
         loads: Mapping[str, Array] | None = None) -> Any:
    """The slide tracks of the spherical joint ``joint``'s head on its cup and of the cup on the
    head along ``kin`` (:func:`pkmdyn.multibody.analyses.wear.joint_wear`: ``(on_cup, on_head,
    what loads it)``); ``radius_m``: the head's radius (default the joint's friction
    ``ball_radius_m``); ``load``: a named load's name pressing the head (default the joint's
    own reaction), its magnitudes in ``loads``. Each track set's ``.columns()`` is the markers'
    table ``pkmdyn wear`` writes."""
    return joint_wear(model, kin, joint, WearOptions(radius_m=radius_m, load=load), dict(loads or {}))


def workspace(model: Any, grid: str, pose: str = "", threshold: float = 1e-3, orientation_range: str | None = None,
              refine: int = 0) -> Any:
    """The reachable workspace (:class:`pkmdyn.multibody.analyses.workspace.Workspace`: every grid
    pose ``x (N, nt)``, ``reached``, ``inside (N,)``, the least singularity measure, the size
    with its error in ``unit``, the inscribed cube and cylinder) on ``grid``, written as
    ``pkmdyn workspace --grid`` takes it (``"x_m=-0.1:0.1:21,y_m=-0.1:0.1:21"``, up to three task
    coordinates), the others held at ``pose`` (``"z_m=0.5,..."``; default the reference pose)
    or over ``orientation_range`` (the same syntax); inside where every singularity measure is
    at least ``threshold``; ``refine``: steps along each boundary edge for the size
    (``docs/workspace.md``)."""
    axes = parse_grid(model, grid, max_axes=3, max_points=int(model.limits["max_workspace_poses"]),
                      limit_key="max_workspace_poses")
    ranges = None if orientation_range is None else parse_ranges(model, orientation_range)
    return reach(model, axes, parse_pose(model, pose), threshold, None, ranges, refine=refine)


def retime(model: Any, path: Array | None = None, points: int = 1000,
           max_effort: float | Mapping[str, float] | None = None, cycle_time: float | None = None,
           friction: bool = True) -> Any:
    """The fastest timing of a path of the task coordinates (rows ``(m, nt)`` in the order of
    ``model.task_names``, a spline through them; default the default motion's path) from rest to
    rest on ``points`` grid points, within the description's drive and ``[limits]`` bounds and
    ``max_effort`` on every actuated joint's effort (one value for all, or ``{joint: value}``) [N
    or N m]; with ``cycle_time`` [s] the least-energy timing within it instead (copper losses
    and friction dissipation, Eq. E1; its ``cycle_time`` is shorter where the least energy is
    reached sooner). Returns the :class:`pkmdyn.multibody.analyses.retime.Retiming` (``t``,
    ``sd``, ``x, xd, xdd``; ``.motion()`` a motion for :func:`kinematics`; ``docs/retime.md``)."""
    rows = default_motion(model).x if path is None else np.asarray(path, dtype=float)
    nj = len(model.joint_names)
    eff = np.full(model.na, np.inf)
    if isinstance(max_effort, Mapping):
        for joint, v in max_effort.items():
            if joint not in model.actuator_names:
                raise ParameterError(f"max_effort: {joint!r} is not an actuated joint (one of "
                                     f"{', '.join(model.actuator_names)})")
            eff[model.actuator_names.index(joint)] = float(v)
    elif max_effort is not None:
        eff[:] = float(max_effort)
    if not np.all(eff > 0):
        raise ParameterError("max_effort: every bound must be a number > 0")
    limits = RetimeLimits(eff, np.full(nj, np.inf), np.full(nj, np.inf), {})
    p = task_path(model, rows)
    fastest = fastest_timing(model, p, points, limits, friction)
    if cycle_time is None:
        return fastest
    return retime_energy(model, p, float(cycle_time), points, limits, friction, fastest=fastest).timing


def identification(model: Any, kin: Any, u: Array, loads: Mapping[str, Array] | None = None,
                   rank_tol: float = DEFAULT_RANK_TOL) -> Any:
    """Every body's inertial parameters and every joint's friction coefficients fitted to the
    efforts ``u (n, na)`` measured along ``kin``, one column per actuator in the order and unit
    :func:`pkmdyn.identify.described.effort_columns` names (a drive's motor effort, else the
    actuated joint's effort: what ``Dynamics.motors.effort`` holds); ``loads``: the
    named loads' magnitudes ``{name: (n,)}``. Returns the
    :class:`pkmdyn.identify._identify.Identification` (``names``, ``prior`` the description's
    values, ``base`` what the motion determines, ``estimate.theta``, ``u_identified``,
    ``residual_rms``; ``.columns(t)`` the efforts table ``pkmdyn identify`` writes;
    ``docs/identification.md``)."""
    u = np.asarray(u, dtype=float)
    if u.ndim != 2 or u.shape != (len(kin), model.na):
        cols = ", ".join(measured_columns(model))
        raise ParameterError(f"u: expected efforts of shape ({len(kin)}, {model.na}) ({cols}), got {u.shape}")
    return fit_described(model, kin, u, dict(loads or {}) or None, rank_tol, source="u")


@dataclass(frozen=True)
class Designs:
    """A sweep's designs (``docs/sweep.md``): ``columns`` every design's row of
    ``designs.parquet`` by column name (``design_id``, the swept keys, ``status``, ``reason``,
    ``feasible``, every metric with its unit in its name; ``(n,)`` each, NaN where the file has
    no value), ``pareto_ids`` the design ids of the Pareto set, ``best_design_id`` (None
    where no design is feasible) and the ``files`` of the sweep's folder."""

    columns: Mapping[str, Array]
    pareto_ids: Array
    best_design_id: int | None
    files: Mapping[str, Path]


def designs(machine: str | Path, space: str | Path, out_dir: str | Path, params: str | Path | None = None,
            workers: int = 0, max_designs: int | None = None, plots: bool = False) -> Designs:
    """The designs of ``machine`` (a built-in name or a description file) that the space file
    ``space`` spans, evaluated in this process (``workers`` 0; more: a local Dask cluster) into the
    folder ``out_dir`` as ``pkmdyn sweep`` writes it (a rerun there resumes; ``plots`` the PNGs);
    ``params``: a generated machine's base parameter file."""
    import pyarrow.parquet as pq  # deferred: no other verb needs PyArrow

    report = _sweep_job.run_sweep(sweep_adapter(str(machine)), space, out_dir, workers=workers, params=params,
                       max_designs=max_designs, plots=plots, progress=False)
    table = pq.read_table(report.files["designs"])
    cols = {name: np.asarray(table.column(name).to_numpy(zero_copy_only=False)) for name in table.column_names}
    front = pq.read_table(report.files["pareto"]).column("design_id").to_numpy() if "pareto" in report.files \
        else np.zeros(0, dtype=np.int64)
    return Designs(cols, np.asarray(front), report.best_design_id, dict(report.files))

"""Control settings files (``--gains G.toml``): timing, actuators, sensors, gains, mismatch.

Each generated machine's folder holds its built-in settings file (``control.toml``, named by
the machine's registry entry, :mod:`pkmdyn.machines.registry`) with every key it accepts and
its default; a user file overrides any subset of them. Rules (each violation is
a :class:`~pkmdyn.errors.ParameterError` naming the table and key): no table or key the
built-in file lacks; a number where the default is a number, a list of the same length where
it is a list; every value finite and >= 0; the keys in :data:`POSITIVE` > 0; the keys in
:data:`INTEGER` whole numbers; the keys in :data:`MAXIMUM` at most their bound. Units come from the key's suffix; ``_deg`` and ``_mm`` values
are converted to radians and metres by :func:`si`.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from ..machines.registry import generated
from ..params_util import read_toml
from ._laws import Gains

__all__ = ["default_settings_text", "load_settings", "loop_settings", "LoopSettings", "gains", "si",
           "scale_description", "POSITIVE", "INTEGER", "MAXIMUM"]

Array = NDArray[np.float64]

#: keys (prefixes) whose values must be > 0
POSITIVE = ("control_cycle_s", "integration_step_s", "effort_limit", "encoder_counts_per_turn",
            "encoder_travel_per_turn", "divergence_limit", "mass_factor", "friction_factor")
#: keys whose values must be whole numbers
INTEGER = ("encoder_counts_per_turn", "pose_delay_cycles", "seed", "pose_feedback_from_sensor", "exact_encoders")
#: upper bounds of keys (the loop allocates ``pose_delay_cycles`` samples; seeds are 64-bit; a flag is 0 or 1)
MAXIMUM = {"pose_delay_cycles": 10_000, "seed": 2**63 - 1, "pose_feedback_from_sensor": 1, "exact_encoders": 1}


def default_settings_text(machine: str) -> str:
    """The built-in settings file of the generated machine ``machine`` (a registry name) as text."""
    return generated(machine).CONTROL_SETTINGS.read_text(encoding="utf-8")


def _check_value(where: str, key: str, value: Any, default: Any) -> Any:
    if isinstance(default, list):
        if not isinstance(value, list) or len(value) != len(default):
            raise ParameterError(f"{where} {key}: expected a list of {len(default)} numbers, got {value!r}")
        return [_check_value(where, f"{key}[{i}]", v, d) for i, (v, d) in enumerate(zip(value, default))]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ParameterError(f"{where} {key}: expected a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v):
        raise ParameterError(f"{where} {key}: {value} is not finite")
    if v < 0:
        raise ParameterError(f"{where} {key}: {value} must be >= 0")
    base = key.split("[")[0]
    if base.startswith(POSITIVE) and v <= 0:
        raise ParameterError(f"{where} {key}: {value} must be > 0")
    if base in INTEGER and v != int(v):
        raise ParameterError(f"{where} {key}: {value} must be a whole number")
    if base in MAXIMUM and v > MAXIMUM[base]:
        raise ParameterError(f"{where} {key}: {value} is above the limit {MAXIMUM[base]}")
    return value


def load_settings(machine: str, path: str | Path | None = None) -> dict[str, dict[str, Any]]:
    """The built-in settings of ``machine`` with the tables of ``path`` (if given) laid over."""
    return overlay_settings(tomllib.loads(default_settings_text(machine)), path)


def overlay_settings(default: dict[str, dict[str, Any]], path: str | Path | None) -> dict[str, dict[str, Any]]:
    """``default`` settings with the tables of the file ``path`` (if given) laid over; every key
    of the file must be one of ``default``'s, with a value of its kind (errors name the key)."""
    if path is None:
        return default
    user = read_toml(path)
    out = {k: dict(v) for k, v in default.items()}
    for table, keys in user.items():
        where = f"{path}: [{table}]"
        if table not in default:
            raise ParameterError(f"{path}: [{table}]: unknown table (known: {', '.join(default)})")
        if not isinstance(keys, dict):
            raise ParameterError(f"{where}: expected a table")
        for key, value in keys.items():
            if key not in default[table]:
                raise ParameterError(f"{where} {key}: unknown key (known: {', '.join(default[table])})")
            out[table][key] = _check_value(where, key, value, default[table][key])
    return out


def si(table: dict[str, Any], key: str) -> np.ndarray:
    """A settings value in SI units as a float array (``_deg`` -> rad, ``_mm`` -> m)."""
    v = np.atleast_1d(np.asarray(table[key], dtype=float))
    if key.endswith("_deg"):
        return np.deg2rad(v)
    if key.endswith("_mm"):
        return v * 1e-3
    return v


def scale_description(desc: dict[str, Any], mass_factor: float, friction_factor: float) -> dict[str, Any]:
    """A machine description (its parameter file as a dict) with every mass, inertia and density
    (keys ending ``_kg``, ``_kgm2``, ``_kg_m3``) times ``mass_factor`` and every friction
    coefficient, Coulomb and viscous term (keys containing ``coefficient``, ``coulomb``,
    ``viscous``) times ``friction_factor``: the default plant of a mismatch study."""

    def scale(v: Any, f: float) -> Any:
        if isinstance(v, list):
            return [scale(x, f) for x in v]
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            return float(v) * f
        return v

    def walk(d: dict[str, Any]) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for k, v in d.items():
            if isinstance(v, dict):
                out[k] = walk(v)
            elif k.endswith(("_kg", "_kgm2", "_kg_m3")):
                out[k] = scale(v, mass_factor)
            elif any(w in k for w in ("coefficient", "coulomb", "viscous")):
                out[k] = scale(v, friction_factor)
            else:
                out[k] = v
        return out

    return walk(desc)


@dataclass(frozen=True)
class LoopSettings:
    """Timing, sensors and limits of a closed loop (SI; displacement unit of the actuators).

    ``cycle_s`` control cycle; ``step_s`` integration step (divides the cycle);
    ``effort_limit (nu,)`` [N m or N]; ``divergence_limit (nq,)`` [rad or m];
    ``encoder_resolution`` actuator displacement per count [rad or m], one for every actuator
    or one each (nu,);
    ``velocity_cutoff_Hz``, ``acceleration_cutoff_Hz`` encoder filters (0: none);
    ``pose_noise (nq,)`` standard deviation [rad or m]; ``pose_delay_cycles``; ``seed``;
    ``pose_from_sensor``: the controller's pose from the pose sensor (else from the encoders);
    ``exact_encoders``: the encoders read the plant's true actuator coordinates and the
    controller's pose comes from its direct kinematics (:mod:`pkmdyn.simulate`'s loop; else both
    to first order about the reference); ``method``: the plant's step (:data:`pkmdyn.simulate.METHODS`;
    by default a third-order explicit step away from the friction band and ROS2 in it);
    ``compiled_cycles``: where the loop's kernel is compiled and every kernel of the cycle is
    the described mechanism's own, the cycles in one compiled call (``pkmdyn.simulate._cycles``:
    the same records, to rounding, except within the solvers' tolerances after a cycle it hands
    back); False: every cycle in Python.
    """

    cycle_s: float
    step_s: float
    effort_limit: Array
    divergence_limit: Array
    encoder_resolution: float | Array
    velocity_cutoff_Hz: float
    acceleration_cutoff_Hz: float
    pose_noise: Array
    pose_delay_cycles: int
    seed: int
    pose_from_sensor: bool = False
    method: str = "rk3-ros2"
    exact_encoders: bool = False
    compiled_cycles: bool = True


def _prefixed(table: dict[str, Any], prefix: str) -> np.ndarray:
    """The values of every key starting with ``prefix``, in SI, concatenated in file order."""
    parts = [si(table, k) for k in table if k.startswith(prefix)]
    if not parts:
        raise ParameterError(f"settings: no key starting with {prefix!r}")
    return np.concatenate(parts)


def loop_settings(settings: dict[str, dict[str, Any]]) -> LoopSettings:
    """The :class:`LoopSettings` of a settings dict (:func:`load_settings`)."""
    tm, act, sen, run = settings["timing"], settings["actuators"], settings["sensors"], settings["run"]
    travel = float(_prefixed(sen, "encoder_travel_per_turn")[0])
    return LoopSettings(
        cycle_s=float(tm["control_cycle_s"]),
        step_s=float(tm["integration_step_s"]),
        effort_limit=_prefixed(act, "effort_limit"),
        divergence_limit=_prefixed(run, "divergence_limit"),
        encoder_resolution=travel / float(sen["encoder_counts_per_turn"]),
        velocity_cutoff_Hz=float(sen["velocity_cutoff_Hz"]),
        acceleration_cutoff_Hz=float(sen["acceleration_cutoff_Hz"]),
        pose_noise=_prefixed(sen, "pose_noise"),
        pose_delay_cycles=int(sen["pose_delay_cycles"]),
        seed=int(sen["seed"]),
        pose_from_sensor=bool(sen["pose_feedback_from_sensor"]),
        exact_encoders=bool(sen.get("exact_encoders", 0)),
    )


def gains(settings: dict[str, dict[str, Any]], kind: str, n: int) -> "Gains":
    """The gains of controller ``kind`` (``n`` values each; absent gains are zero)."""
    table = settings.get(kind, {})
    vals = {}
    for g in ("kp", "kd", "ki"):
        keys = [k for k in table if k.startswith(g + "_")]
        vals[g] = si(table, keys[0]) if keys else np.zeros(n)
    return Gains(vals["kp"], vals["kd"], vals["ki"])

"""The retime job: a described mechanism, a geometric path of its task coordinates and the limits
in; the fastest timing of the path as a motion file every command takes, ``retime.json``,
``retime.csv``, plots and ``report.html`` out (``docs/retime.md``). The numbers come from
:mod:`pkmdyn.multibody.analyses.retime`; every bound's use is checked again on the timed motion
through the same kinematics and inverse dynamics as ``pkmdyn run``."""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from ..io import read_csv_columns, write_csv, write_json
from ..multibody.analyses.retime import (
    SETTLED,
    LimitUse,
    RetimeLimits,
    Retiming,
    copper_coefficients,
    limit_use,
    retime,
    task_path,
    timing_energy,
)
from ..multibody.analyses.retime_energy import SETTLED as ENERGY_SETTLED
from ..multibody.analyses.retime_energy import EnergyTiming, pareto_front, retime_energy
from ..multibody.description.schema import LIMIT_KEYS
from ..multibody.dynamics.newton_euler import joint_reactions
from ..multibody.kinematics.inverse import solve_kinematics
from ..multibody.kinematics.motion import MAX_MOTION_ROWS, default_motion, task_columns
from ..multibody.scene import mechanism_scene
from ..params_util import parse_limit_options
from ..report import Curve, Output, Report, TimePlot, write_output
from ._files import JobResult, prepare

__all__ = ["job", "parse_bounds"]

Array = NDArray[np.float64]

#: a bound counts as active at a grid point where its use is at least this
ACTIVE = 0.99


def parse_bounds(option: str, items: tuple[str, ...], names: tuple[str, ...], unit: str) -> dict[int, float]:
    """``("NAME=VALUE", ...)`` of ``option`` over ``names`` (``all`` for every one) -> {index:
    bound}; a value must be a finite number > 0 [``unit``]."""
    out: dict[int, float] = {}
    for item in items:
        key, sep, text = item.partition("=")
        key = key.strip()
        if not sep or (key != "all" and key not in names):
            raise ParameterError(f"{option} {item!r}: expected NAME=VALUE [{unit}] with NAME 'all' or one of "
                                 f"{', '.join(names)}")
        try:
            value = float(text)
        except ValueError:
            raise ParameterError(f"{option} {item!r}: {text!r} is not a number") from None
        if not (np.isfinite(value) and value > 0):
            raise ParameterError(f"{option} {item!r}: the bound must be a finite number > 0 [{unit}], got {text}")
        for i, nm in enumerate(names):
            if key in ("all", nm):
                out[i] = value
    return out


def _path_rows(model: Any, entry: Any, path_file: Path | None) -> tuple[Array, str]:
    """The path's rows: a motion file's task columns (``t_s`` and rates, when present, are not
    used), or the default motion's."""
    if path_file is None:
        m = entry.default_motion() if entry is not None else default_motion(model)
        return m.x, "the default motion's path"
    pos, vel, acc = task_columns(model)
    cols = read_csv_columns(path_file, pos, ("t_s", *vel, *acc), max_rows=MAX_MOTION_ROWS,
                            beyond="the path's row limit (200,000 rows)")
    return np.column_stack([cols[c] for c in pos]), str(path_file)


def _key(name: str) -> str:
    """A bound's column stem: its name up to the unit, in letters, digits and ``_``."""
    return re.sub(r"[^A-Za-z0-9]+", "_", name.split(" [")[0]).strip("_")


def _document(model: Any, ret: Retiming, use: LimitUse, limits: RetimeLimits, source: str, energy: dict,
              friction: bool, least: EnergyTiming | None) -> dict[str, Any]:
    most = use.use.max(axis=1) if use.use.size else np.zeros(len(ret.t))
    bounds = []
    for k, name in enumerate(use.names):
        col = use.use[:, k]
        bounds.append({"bound": name, "largest_use_ratio": float(col.max()),
                       "at_t_s": float(ret.t[int(np.argmax(col))]),
                       "share_of_points_active": float(np.mean(col >= ACTIVE))})
    w, given = copper_coefficients(model)
    coeff = [{"actuator": nm, "copper_loss_coefficient_W_per_effort2": float(w[i]), "from_description": bool(given[i])}
             for i, nm in enumerate(model.actuator_names)]
    if least is None:
        objective: dict[str, Any] = {
            "objective": "least time",
            "algorithm": "reachability analysis (TOPP-RA), a linear program per grid point (HiGHS)",
            "stopping_rule": f"largest change of sd at most {SETTLED:g} of its largest value"}
    else:
        objective = {
            "objective": "least energy within the cycle time",
            "algorithm": "a second-order cone program per pass (Clarabel), on the limits of the least-time timing",
            "stopping_rule": f"largest change of sd at most {ENERGY_SETTLED:g} of its largest value",
            "cycle_time_bound_s": least.cycle_time_bound, "fastest_cycle_time_s": least.fastest_s,
            "least_energy_reached_sooner": least.beyond_least_energy}
    return {
        "mechanism": model.name, "path": source, "definitions": "docs/retime.md", **objective,
        "grid_points": len(ret.s), "cycle_time_s": ret.cycle_time, "passes": ret.iterations,
        "friction": friction, "copper_loss_coefficients": coeff,
        "largest_use_ratio": float(most.max()) if most.size else 0.0,
        "share_of_points_with_a_bound_at_99_percent": float(np.mean(most >= ACTIVE)) if most.size else 0.0,
        "bounds": bounds, **energy,
    }


def _pngs(out: Path, ret: Retiming, use: LimitUse, fastest: Retiming | None, pareto: dict | None) -> dict[str, Path]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    files = {}
    fig, ax = plt.subplots(figsize=(10, 5))
    ax.plot(ret.s, ret.sd, label="timing sd" if fastest is None else "least-energy timing sd", lw=2)
    if fastest is not None:
        ax.plot(fastest.s, fastest.sd, label=f"least-time timing sd ({fastest.cycle_time:.6g} s)", lw=1)
    top = max(float(np.max(ret.sd)), float(np.max(fastest.sd)) if fastest is not None else 0.0, 1e-12) * 3
    ax.plot(ret.s, np.minimum(ret.sd_reach, top), "--", label="controllable sets' upper bound")
    ax.plot(ret.s, np.minimum(ret.sd_limit, top), ":", label="speed limits alone")
    ax.set_ylim(0, top)
    ax.set_xlabel("path parameter s")
    ax.set_ylabel("path speed sd [1/s]")
    ax.set_title(f"path speed against its limits: cycle {ret.cycle_time:.6g} s")
    ax.legend()
    fig.tight_layout()
    files["png_speed"] = out / "retime_speed.png"
    fig.savefig(files["png_speed"], dpi=100)
    plt.close(fig)
    fig, ax = plt.subplots(figsize=(10, 5))
    order = np.argsort(-use.largest)[:8]
    for k in order:
        ax.plot(ret.t, use.use[:, k], label=use.names[k])
    ax.axhline(1.0, color="0.3", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("use of the bound (|value| / bound)")
    ax.set_title("the most used bounds along the timed motion (pkmdyn run's inverse dynamics)")
    ax.legend(fontsize=7, loc="lower right")
    fig.tight_layout()
    files["png_use"] = out / "limit_use.png"
    fig.savefig(files["png_use"], dpi=100)
    plt.close(fig)
    if pareto is not None:
        fig, ax = plt.subplots(figsize=(10, 5))
        T = pareto["cycle_time_s"]
        ax.plot(T, pareto["energy_J"], "o-", lw=2, label="energy (Eq. E1)")
        ax.plot(T, pareto["copper_loss_J"], "s--", label="copper losses")
        ax.plot(T, pareto["friction_dissipation_J"], "^:", label="friction dissipation")
        ax.set_xlabel("cycle time [s]")
        ax.set_ylabel("energy per cycle [J]")
        ax.set_title("Pareto curve: the least energy of the path for each cycle time")
        ax.legend()
        fig.tight_layout()
        files["png_pareto"] = out / "pareto.png"
        fig.savefig(files["png_pareto"], dpi=100)
        plt.close(fig)
    return files


def _pareto(model: Any, path: Any, fastest: Retiming, count: int, span: float, points: int, limits: RetimeLimits,
            friction: bool) -> dict[str, Array]:
    """The Pareto curve's table: ``count`` cycle-time bounds from the fastest to ``span`` times it,
    each point's energy checked through ``pkmdyn run``'s inverse dynamics."""
    from tqdm import tqdm

    bounds = fastest.cycle_time * np.linspace(1.0, span, count)
    with tqdm(total=count, desc=f"{model.name}: Pareto curve", unit="cycle time", disable=None, leave=False) as bar:
        front = pareto_front(model, path, bounds, points, limits, friction, fastest, progress=lambda k: bar.update())
    cols: dict[str, list] = {k: [] for k in ("cycle_time_bound_s", "cycle_time_s", "energy_J", "copper_loss_J",
                                              "friction_dissipation_J", "largest_use_ratio")}
    for e in front:
        r = e.timing
        kin = solve_kinematics(model, r.x, r.xd, r.xdd, r.t)
        reac = joint_reactions(model, kin, friction=friction)
        en = timing_energy(model, kin, reac)
        cols["cycle_time_bound_s"].append(e.cycle_time_bound)
        cols["cycle_time_s"].append(r.cycle_time)
        for k in ("energy_J", "copper_loss_J", "friction_dissipation_J"):
            cols[k].append(en[k])
        cols["largest_use_ratio"].append(float(limit_use(model, kin, reac, limits).largest.max(initial=0.0)))
    return {k: np.array(v, dtype=float) for k, v in cols.items()}


def job(machine: str, out_dir: Path, *, path_file: Path | None = None, points: int = 1000,
        efforts: tuple[str, ...] = (), reaction_forces: tuple[str, ...] = (), reaction_moments: tuple[str, ...] = (),
        friction: bool = True, plots: bool = True, limit_items: tuple[str, ...] = (),
        cycle_time: float | None = None, pareto: int = 0, pareto_span: float = 3.0,
        announce: Callable[[Mapping[str, Path]], None] | None = None) -> JobResult:
    """``pkmdyn retime``: the fastest timing of ``machine``'s path (``path_file``'s task columns,
    default its default motion's path) on ``points`` grid points, within the drives' limits of
    the description, the bounds ``efforts`` (``JOINT=VALUE`` or ``all=VALUE`` [N or N m]),
    ``reaction_forces`` [N] and ``reaction_moments`` [N m] (``JOINT=VALUE``) and ``limit_items``
    (``--limit KEY=VALUE`` over the description's ``[limits]``: the task's and joints' speeds and
    accelerations), into ``out_dir``; with ``cycle_time`` [s] the least-energy timing within
    it instead, and with ``pareto`` >= 2 the Pareto curve of cycle time against energy on that
    many cycle times from the fastest to ``pareto_span`` times it."""
    overrides = parse_limit_options(limit_items, LIMIT_KEYS)
    if cycle_time is not None and not (np.isfinite(cycle_time) and cycle_time > 0):
        raise ParameterError(f"--cycle-time: must be a finite number > 0 [s], got {cycle_time!r}")
    if pareto and not 2 <= pareto <= 200:
        raise ParameterError(f"--pareto: the number of cycle times must be between 2 and 200, got {pareto}")
    if not (np.isfinite(pareto_span) and pareto_span > 1.0):
        raise ParameterError(f"--pareto-span: must be a number > 1 (the longest cycle time over the fastest), "
                             f"got {pareto_span!r}")
    p = prepare(machine, out_dir, {"--path": path_file}, overrides)
    model = p.model
    nj = len(model.joint_names)
    eff = np.full(model.na, np.inf)
    for i, v in parse_bounds("--max-effort", efforts, model.actuator_names, "N or N m").items():
        eff[i] = v
    rf, rm = np.full(nj, np.inf), np.full(nj, np.inf)
    for i, v in parse_bounds("--max-reaction-force", reaction_forces, model.joint_names, "N").items():
        rf[i] = v
    for i, v in parse_bounds("--max-reaction-moment", reaction_moments, model.joint_names, "N m").items():
        rm[i] = v
    limits = RetimeLimits(eff, rf, rm, overrides)
    rows, source = _path_rows(model, p.entry, None if path_file is None else Path(path_file).absolute())
    path = task_path(model, rows, source)
    fastest = retime(model, path, points, limits, friction=friction)
    least = None
    ret = fastest
    if cycle_time is not None:
        least = retime_energy(model, path, cycle_time, points, limits, friction, fastest=fastest)
        ret = least.timing
    front = _pareto(model, path, fastest, pareto, pareto_span, points, limits, friction) if pareto else None
    kin = solve_kinematics(model, ret.x, ret.xd, ret.xdd, ret.t)
    reac = joint_reactions(model, kin, friction=friction)
    use = limit_use(model, kin, reac, limits)
    doc = _document(model, ret, use, limits, source, timing_energy(model, kin, reac), friction, least)
    if front is not None:
        doc["pareto"] = {"file": "pareto.csv", "points": len(front["cycle_time_s"]),
                         "ends_at_least_energy": bool(front["cycle_time_s"][-1] < front["cycle_time_bound_s"][-1]
                                                      * (1 - 1e-6))}
    pos, vel, acc = task_columns(model)
    motion_cols = {"t_s": ret.t, **{c: ret.x[:, k] for k, c in enumerate(pos)},
                   **{c: ret.xd[:, k] for k, c in enumerate(vel)}, **{c: ret.xdd[:, k] for k, c in enumerate(acc)}}
    table = {"s": ret.s, "t_s": ret.t, "sd_1_s": ret.sd, "sdd_1_s2": ret.sdd,
             "sd_limit_1_s": np.where(np.isfinite(ret.sd_limit), ret.sd_limit, -1.0),
             "sd_reach_1_s": np.where(np.isfinite(ret.sd_reach), ret.sd_reach, -1.0),
             **{f"{_key(n)}_use_ratio": use.use[:, k] for k, n in enumerate(use.names)}}
    what = "fastest timing" if least is None else f"least-energy timing within {cycle_time:.6g} s"

    scene = mechanism_scene(model, ret.t, kin.joint_point, {
        nm: (reac.u[:, i], f"{nm} effort", "N" if model.actuator_units[i] == "m" else "N m")
        for i, nm in enumerate(model.actuator_names)})
    order = np.argsort(-use.largest)[:8]
    figs = [TimePlot("Use of the most used bounds", "|value| / bound", ret.t,
                     tuple(Curve(use.names[k], use.use[:, k]) for k in order)),
            TimePlot("Path speed", "sd [1/s]", ret.t, (Curve("sd", ret.sd),))]
    report = Report(f"{model.name}: the {what} of its path", scene=scene, plots=figs,
                    summary={k: v for k, v in doc.items() if k not in ("bounds", "copper_loss_coefficients")},
                    parameters=p.text, notes=[f"path: {source}", "definitions: docs/retime.md"])

    def make(out: Path) -> Output:
        files = {"motion": out / "timed_motion.csv", "table": out / "retime.csv", "summary": out / "retime.json"}
        write_csv(files["motion"], motion_cols)
        write_csv(files["table"], table)
        write_json(files["summary"], doc)
        if front is not None:
            files["pareto"] = out / "pareto.csv"
            write_csv(files["pareto"], front)
        images = _pngs(out, ret, use, None if least is None else fastest, front) if plots else {}
        files.update(images)
        return Output(files, report=replace(report, images=list(images)))

    files, output = write_output(out_dir, p.inputs, make, announce)
    over = [b for b in doc["bounds"] if b["largest_use_ratio"] > 1.0 + 1e-6]
    line = (f"{what}: cycle time {ret.cycle_time:.6g} s over {len(ret.s)} grid points ({ret.iterations} passes), "
            f"energy {doc['energy_J']:.6g} J; largest use of a bound {doc['largest_use_ratio']:.9g}; a bound at 99 % "
            f"or more at {100 * doc['share_of_points_with_a_bound_at_99_percent']:.1f} % of the points")
    lines = [line]
    if front is not None:
        lines.append(f"Pareto curve: {len(front['cycle_time_s'])} cycle times from {front['cycle_time_s'][0]:.6g} s "
                     f"({front['energy_J'][0]:.6g} J) to {front['cycle_time_s'][-1]:.6g} s "
                     f"({front['energy_J'][-1]:.6g} J) in pareto.csv")
    warnings = tuple(f"{b['bound']}: used {b['largest_use_ratio']:.9g} of its bound on the timed motion"
                     for b in over)
    notes = []
    if least is not None and least.beyond_least_energy:
        notes.append(f"--cycle-time {cycle_time:.6g} s: the least energy is reached sooner, at {ret.cycle_time:.6g} s "
                     "(a longer motion costs more: holding the load costs copper losses all along)")
    if doc.get("pareto", {}).get("ends_at_least_energy"):
        notes.append(f"the Pareto curve ends at the path's least-energy cycle time {front['cycle_time_s'][-1]:.6g} s "
                     "(longer cycle times cost more)")
    _, given = copper_coefficients(model)
    if (least is not None or front is not None) and not given.all():
        missing = [nm for nm, g in zip(model.actuator_names, given) if not g]
        notes.append(f"copper losses of {', '.join(missing)}: no winding_resistance_ohm and motor constant in "
                     "[[actuators]]; their squared motor effort counts with 1 W per (N m)^2 or N^2")
    return JobResult(files, doc, tuple(lines), warnings, tuple(notes), report=output.report)

"""``pkmdyn assemble``: every assembly mode of a mechanism at one actuator configuration."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import click

from ._groups import MACHINE_HELP, cli, list_files


def _document(model: Any, modes: Any) -> dict[str, Any]:
    """``assemblies.json`` (docs/mechanism_format.md, "Direct kinematics")."""
    units = list(model.task_units)
    return {
        "mechanism": model.name,
        "actuators": {a: {"value": float(v), "unit": "m" if model.coord_motion[c] >= 3 else "rad"}
                      for a, c, v in zip(model.actuator_names, model.act_coord, modes.s)},
        "method": modes.method,
        "starts": modes.starts,
        "converged_starts": modes.converged,
        "modes": [{
            "mode": k + 1,
            "task": {f"{n}_{u}": float(v) for n, u, v in zip(model.task_names, units, a.x)},
            "residual": a.residual,
            "round_trip": a.round_trip,
            "det_sign": a.det_sign,
            "singularity_measures": {"inverse": a.inverse, "direct": a.direct, "constraint": a.constraint},
            "starts_reaching_it": a.hits,
            "tree_coordinates": {name: float(v) for name, v in zip(_coordinate_names(model), a.q)},
        } for k, a in enumerate(modes.modes)],
    }


def _coordinate_names(model: Any) -> list[str]:
    out = []
    for c in range(model.nq):
        j = int(model.coord_joint[c])
        k = c - int(model.joint_q0[j])
        out.append(f"{model.joint_names[j]}[{k}]" if model.joint_nq[j] > 1 else model.joint_names[j])
    return out


def _report(out: Path, model: Any, modes: Any, doc: dict[str, Any], text: str) -> Path:
    """``report.html``: one frame per assembly mode."""
    import numpy as np

    from ..multibody import solve_kinematics
    from ..multibody.columns import model_summary
    from ..report import scene_from_joints, write_report

    points = []
    for a in modes.modes:
        kin = solve_kinematics(model, a.x[None], q_start=a.q)
        points.append(kin.joint_point[0])
    jp = np.stack(points)
    summ = model_summary(model)
    joints = [(j["name"], j["type"], j["body_a"], j["body_b"]) for j in summ["joints"]]
    zero = np.zeros(len(modes.modes))
    actuated = {j["name"]: (zero, f"{j['name']} (actuated)", "-") for j in summ["joints"] if j.get("actuated")}
    scene = scene_from_joints(np.arange(len(modes.modes), dtype=float), jp, joints, actuated)
    return write_report(out, title=f"{model.name}: assembly modes", scene=scene, summary=doc, parameters=text,
                        notes=[f"{len(modes.modes)} assembly mode(s) at " + ", ".join(
                            f"{a} = {v + 0.0:.6g}" for a, v in zip(model.actuator_names, modes.s))],
                        scene_note="One frame per assembly mode, in the order of the table (the slider's "
                                   "'time' is the mode number minus one).")


@cli.command("assemble")
@click.option("--machine", required=True, help=MACHINE_HELP)
@click.option("--actuators", required=True, metavar="NAME=VALUE,...",
              help="Every actuated joint's coordinate, SI (m for a prismatic joint, rad for a revolute one), e.g. "
                   "\"P_1=1.02,P_2=1.05,...\".")
@click.option("--starts", type=click.IntRange(0, 1_000_000), default=2000, show_default=True,
              help="Random configurations the search starts from (more starts, fewer modes missed).")
@click.option("--seed", type=click.IntRange(0, 2**32 - 1), default=0, show_default=True,
              help="Seed of the random starts.")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Output folder for assemblies.json and report.html (an earlier run of this command there is replaced whole).")
def assemble(machine: str, actuators: str, starts: int, seed: int, out_dir: Path | None) -> None:
    """Every assembly mode found at one actuator configuration (the direct kinematics' distinct
    solutions), each verified by the inverse kinematics, with its singularity measures; the
    search (damped Newton from random starts) guarantees that each mode is real, not that none
    is missing."""
    from ..io import check_output_dir, output_dir, write_json
    from ..machines.registry import resolve
    from ..multibody.kinematics.direct import assembly_modes, parse_actuators
    from .mechanism import _load

    entry, path = resolve(machine)
    inputs = {"--machine": path}
    if out_dir is not None:
        check_output_dir(out_dir, inputs)
    model, _ = _load(machine)
    s = parse_actuators(model, actuators)
    modes = assembly_modes(model, s, starts=starts, seed=seed)
    doc = _document(model, modes)
    click.echo(f"mechanism: {model.name}")
    click.echo("actuators: " + ", ".join(f"{a} = {v['value'] + 0.0:.9g} {v['unit']}" for a, v in doc["actuators"].items()))
    click.echo(f"method: {modes.method}")
    click.echo(f"starts: {modes.starts}; converged: {modes.converged}; assembly modes found: {len(modes.modes)}")
    for m in doc["modes"]:
        task = ", ".join(f"{k} = {v + 0.0:.9g}" for k, v in m["task"].items())
        sm = m["singularity_measures"]
        click.echo(f"mode {m['mode']}: {task}; residual {m['residual']:.2g}; round trip {m['round_trip']:.2g}; "
                   f"det sign {m['det_sign']:+d}; singularity measures inverse {sm['inverse']:.4g}, direct "
                   f"{sm['direct']:.4g}, constraint {sm['constraint']:.4g}; starts reaching it {m['starts_reaching_it']}")
    if out_dir is None:
        return
    text = path.read_text(encoding="utf-8", errors="replace") if path is not None else ""
    final = Path(out_dir)
    with output_dir(out_dir, inputs=inputs) as out:
        files = {"assemblies": out / "assemblies.json"}
        write_json(files["assemblies"], doc)
        files["report"] = _report(out, model, modes, doc, text)
        list_files({k: final / v.name for k, v in files.items()})

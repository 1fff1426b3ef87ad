"""``pkmdyn describe``: a machine's topology, mobility, over-constraints, explicit legs, compliance
sources and design parameters, as lines to print (no files)."""

from __future__ import annotations

import numpy as np

from ..multibody.analyses.stiffness import compliance_sources
from ..multibody.dynamics.distribution import internal_directions
from ..multibody.kinematics.inverse import reference_task, solve_kinematics
from ..multibody.model.legs import LEG_PATTERNS, held_coordinates
from ._files import JobResult, load_machine

__all__ = ["job"]


def job(machine: str) -> JobResult:
    """The description of ``machine`` (a built-in name or a description file) as ``pkmdyn describe``
    prints it: one line per fact."""
    model, _ = load_machine(machine)
    rep = model.topology
    counts = ", ".join(f"{c} {k}" for k, c in rep.joint_counts.items())
    lines = [
        f"mechanism: {model.name}",
        f"source: {model.source}" if model.source else None,
        f"moving bodies: {rep.bodies}; joints: {counts}",
        f"spanning tree: {', '.join(rep.tree_joints)}",
        f"cut joints (independent loops {rep.loops}): {', '.join(rep.cut_joints) or 'none'}",
        f"Grubler-Kutzbach mobility: {rep.kutzbach}",
        f"mobility (rank at the reference configuration): {rep.mobility}",
        f"idle freedoms: {rep.idle}",
        f"degrees of freedom: {rep.dof}",
        f"over-constraints: {rep.overconstraints}"
        + (f" ({', '.join(f'{j} {d}' for j, d in rep.overconstrained)})" if rep.overconstrained else ""),
        f"actuated joints: {', '.join(model.actuator_names)}",
        (f"under-actuated: {model.na} actuators for {rep.dof} degrees of freedom (a task motion's efforts exist only "
         "where the motion is dynamically consistent; pkmdyn run refuses it elsewhere, naming the sample; its default "
         "motion drives the actuators and simulates the other freedoms)")
        if model.na < rep.dof else None,
        _redundancy(model) if model.na > rep.dof else None,
        f"task coordinates: {', '.join(f'{n} [{u}]' for n, u in zip(model.task_names, model.task_units))} "
        + (f"of body {model.body_names[model.task_body]}" if any(k != 2 for k in model.task_kind) else
           f"(joints' coordinates; runs write the pose of body {model.body_names[model.task_body]})"),
        f"explicit legs (closed form, {model.legs.count}): "
        + (", ".join(f"{'-'.join(chain)} to {cut} ({LEG_PATTERNS[kind].split(' ')[0]}{_held(model, chain)})"
                     for cut, chain, kind in model.legs.names) or "none; Newton solves every loop")
        + (" (every block: Newton only checks)" if model.legs.count == model.solver_blocks.shape[0] - 1 else ""),
    ]
    src = compliance_sources(model)
    lines.append("compliance (pkmdyn stiffness): " + ("; ".join(f"{k} {', '.join(v)}" for k, v in src.items() if v)
                                                      or "none (every body, joint and drive rigid)"))
    if model.parameters:
        lines.append("parameters: " + "; ".join(f"{k} = {_shown(v)}{_range(model.parameter_bounds.get(k))}"
                                                for k, v in model.parameters.items()))
    return JobResult(lines=tuple(line for line in lines if line is not None))


def _redundancy(model) -> str:
    """The line of a redundantly actuated mechanism: the degree of redundancy, the distribution
    and the internal-force directions at the reference configuration (unit vectors over the
    actuated joints, :func:`~pkmdyn.multibody.dynamics.distribution.internal_directions`)."""
    x = reference_task(model)[None, :]
    z = np.zeros_like(x)
    kin = solve_kinematics(model, x, z, z)
    N = internal_directions(np.swapaxes(kin.J_ax, 1, 2))[0]
    dirs = "; ".join("(" + ", ".join(f"{a} {v:+.4f}" for a, v in zip(model.actuator_names, N[:, k])) + ")"
                     for k in range(N.shape[1]))
    pre = f", preload {model.act_preload:g} (N or N m)" if model.act_preload else ""
    return (f"redundantly actuated: {model.na} actuators for {model.nt} degrees of freedom, degree of redundancy "
            f"{model.na - model.nt}; efforts by the {model.act_distribution.replace('_', ' ')} distribution{pre} "
            f"([actuation]); internal-force directions at the reference configuration: {dirs}")


def _held(model, chain) -> str:
    """``, J spin held`` for the joints of an explicit leg's chain with a coordinate that an idle
    row of its own holds (an S-S rod's spin; docs/mechanism_format.md, "Explicit legs")."""
    held = held_coordinates(model)
    out = ""
    for j in chain:
        k = model.joint_index(j)
        if held & set(range(model.joint_q0[k], model.joint_q0[k] + model.joint_nq[k])):
            out += f", {j} spin held"
    return out


def _range(bounds) -> str:
    """A bounded parameter's bounds as ``describe`` prints them: `` (min 0.1, max 0.3)``."""
    if not bounds:
        return ""
    parts = [f"{w} {b:.9g}" for w, b in zip(("min", "max"), bounds) if b is not None]
    return f" ({', '.join(parts)})"


def _shown(v) -> str:
    """A parameter's value as ``describe`` prints it: a number, or a vector of numbers."""
    if isinstance(v, list):
        return "[" + ", ".join(_shown(x) for x in v) + "]"
    return f"{v:.9g}"

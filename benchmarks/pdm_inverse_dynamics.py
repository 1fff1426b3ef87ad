"""Speed of the PDM's inverse dynamics: the generic engine on the PDM's description (the route of
every PDM command) beside the hand-derived routes.

Runs, in one process and on the same samples (the Eq. 84 cycloidal motion of the built-in
parameters, resampled to ``--samples`` samples), the engine's kinematics and joint reactions,
the hand-derived Newton-Euler oracle of ``tests/oracles/pdm_newton_euler.py`` (actuator forces
only, and every reaction with the compliance solution of Eq. 63-83), the virtual-power oracle
in minimal coordinates (``tests/oracles/pdm_minimal.py``) and the dense general compliance
solver of ``pkmdyn.analysis.compliance`` (on ``--dense-samples`` samples). Prints one JSON
object; with ``--json`` nothing else is printed.

    python benchmarks/pdm_inverse_dynamics.py --json [--samples 10000]

Fields (us = microseconds, best of ``--repeat``): ``samples``; ``actuator_us_per_sample`` and
``reactions_us_per_sample`` (from the kinematics of the samples, which every route shares);
``kinematics_us_per_sample`` (``inverse_kinematics``); ``actuator_with_kinematics_us_per_sample``
and ``reactions_with_kinematics_us_per_sample`` (from q, qd, qdd); ``reference_us_per_sample``
(the independent route, from q, qd, qdd); ``dense_general_us_per_sample``; ``single_sample_us``
(one sample, kinematics + every reaction, as a controller would call it); agreement figures;
the generic engine on the PDM's description (the route of ``pkmdyn pdm run``):
``engine_kinematics_us_per_sample``, ``engine_reactions_us_per_sample`` (every joint reaction,
unique by compliance), ``engine_reactions_over_newton_euler`` and
``engine_max_rel_difference_forces``;
the targets (actuator <= 10 us, reactions <= 50 us per sample on 10,000 samples, of the
engine: ``engine_actuator_us_per_sample`` the kinematics and efforts,
``engine_reactions_with_kinematics_us_per_sample`` the kinematics and every reaction) and
whether they are met.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

# every route here is single-threaded per call (batched small matrices); BLAS threads would only
# contend with each other on a shared machine, so they are pinned to one before numpy loads
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from pkmdyn.machines.pdm4 import inverse_kinematics, load_params  # noqa: E402
from pkmdyn.profiles.pdm_motion import cycloidal_motion  # noqa: E402

from _timing import best_time  # noqa: E402

# the hand-derived routes live beside the tests, as their oracles
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from oracles import pdm_minimal as minimal  # noqa: E402
from oracles.pdm_newton_euler import actuator_forces, compliance_system, equilibrium_system, inverse_dynamics  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=10_000)
    ap.add_argument("--dense-samples", type=int, default=100)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    n = args.samples
    model = load_params()
    tr = model.trajectory
    motion = cycloidal_motion(tr.strokes, tr.period_s, n)
    kin = inverse_kinematics(model, motion)
    us = 1e6 / n
    out: dict = {"samples": n}
    out["actuator_us_per_sample"] = best_time(lambda: actuator_forces(model, kin), args.repeat) * us
    out["reactions_us_per_sample"] = best_time(lambda: inverse_dynamics(model, kin), args.repeat) * us
    out["kinematics_us_per_sample"] = best_time(lambda: inverse_kinematics(model, motion), args.repeat) * us
    out["actuator_with_kinematics_us_per_sample"] = best_time(
        lambda: actuator_forces(model, inverse_kinematics(model, motion)), args.repeat) * us
    out["reactions_with_kinematics_us_per_sample"] = best_time(
        lambda: inverse_dynamics(model, inverse_kinematics(model, motion)), args.repeat) * us
    reac = inverse_dynamics(model, kin)
    ref = minimal.inverse_dynamics(model, motion.q, motion.qd, motion.qdd, None)
    out["reference_us_per_sample"] = best_time(
        lambda: minimal.inverse_dynamics(model, motion.q, motion.qd, motion.qdd, None), args.repeat) * us
    out["max_rel_difference_vs_reference"] = float(np.abs(ref - reac.force).max() / np.abs(ref).max())
    out["speedup_actuator_vs_reference"] = out["reference_us_per_sample"] / out["actuator_with_kinematics_us_per_sample"]
    # the generic engine on the PDM's description (the route of `pkmdyn pdm run`): its kinematics and
    # every joint reaction by the compiled complementary energy in the cut unknowns
    from pkmdyn.machines.pdm4.description import pdm_description
    from pkmdyn.multibody import load_mechanism, solve_kinematics
    from pkmdyn.multibody.dynamics.newton_euler import inverse_dynamics as engine_inverse_dynamics
    from pkmdyn.multibody.dynamics.newton_euler import joint_reactions

    mech = load_mechanism(pdm_description(model))
    gkin = solve_kinematics(mech, motion.q, motion.qd, motion.qdd, motion.t)
    limbs = [mech.actuator_names.index(k) for k in ("P11", "P12", "P23", "P24")]
    greac = joint_reactions(mech, gkin)
    out["engine_kinematics_us_per_sample"] = best_time(
        lambda: solve_kinematics(mech, motion.q, motion.qd, motion.qdd, motion.t), args.repeat) * us
    out["engine_reactions_us_per_sample"] = best_time(lambda: joint_reactions(mech, gkin), args.repeat) * us

    def engine_efforts():
        return engine_inverse_dynamics(mech, solve_kinematics(mech, motion.q, motion.qd, motion.qdd, motion.t))

    out["engine_actuator_us_per_sample"] = best_time(engine_efforts, args.repeat) * us
    out["engine_reactions_with_kinematics_us_per_sample"] = best_time(
        lambda: joint_reactions(mech, solve_kinematics(mech, motion.q, motion.qd, motion.qdd, motion.t)),
        args.repeat) * us
    out["engine_max_rel_difference_forces"] = float(np.abs(greac.u[:, limbs] - reac.force).max()
                                                    / np.abs(reac.force).max())
    out["engine_reactions_over_newton_euler"] = (out["engine_reactions_us_per_sample"]
                                                 / out["reactions_us_per_sample"])
    m = min(args.dense_samples, n)
    small = inverse_kinematics(model, motion.slice(0, m))

    def dense():
        from pkmdyn.analysis.compliance import unique_reactions

        A, b, _ = equilibrium_system(model, small)
        G, w0, C = compliance_system(model, small)
        return unique_reactions(A, b, G, w0, C)

    out["dense_general_us_per_sample"] = best_time(dense, 1) * 1e6 / m
    one = motion.slice(n // 3, n // 3 + 1)
    out["single_sample_us"] = best_time(lambda: inverse_dynamics(model, inverse_kinematics(model, one)), 50) * 1e6
    out["targets"] = {"engine_actuator_us_per_sample": 10.0, "engine_reactions_with_kinematics_us_per_sample": 50.0}
    out["targets_met"] = {k: bool(out[k] <= v) for k, v in out["targets"].items()}
    if not args.json:
        print("PDM inverse dynamics benchmark")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

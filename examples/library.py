"""The library from a notebook: one machine loaded, then its kinematics, dynamics, direct
kinematics, workspace and identification, with nothing but ``import pkmdyn``.

    python examples/library.py
"""

from __future__ import annotations

import numpy as np

import pkmdyn


def main() -> dict:
    m = pkmdyn.load("stewart")                       # a built-in name, a FILE.toml or a dict
    kin = pkmdyn.kinematics(m)                       # along the description's default motion
    dyn = pkmdyn.dynamics(m, kin)                    # efforts, every joint's reaction, motors
    cols = dyn.columns()                             # as results.csv of `pkmdyn run` names them
    back = pkmdyn.direct_kinematics(m, kin.act_q)    # the poses again, from the leg lengths
    xdd = pkmdyn.forward_dynamics(m, kin.x[:5], kin.xd[:5], dyn.motors.effort[:5])
    ws = pkmdyn.workspace(m, "x_m=-0.2:0.2:9,y_m=-0.2:0.2:9")    # reachable and away from singularities
    fit = pkmdyn.identification(m, kin, dyn.motors.effort)       # inertia and friction from efforts
    hip = pkmdyn.load("hip")                         # a paper's machine, generated from its parameters
    print(f"{m.name}: {len(kin)} samples, {m.na} actuators; largest leg force "
          f"{np.abs(dyn.reactions.u).max():.1f} N; direct kinematics back to the poses within "
          f"{np.abs(back.x - kin.x).max():.2e}; forward dynamics back to the accelerations within "
          f"{np.abs(xdd - kin.xdd[:5]).max():.2e}; workspace {ws.inside.sum()} of {len(ws.x)} grid poses inside "
          f"({ws.size:.4g} {ws.unit}); the motion shows {fit.base.rank} of {len(fit.names)} parameters; "
          f"{hip.name}: {len(hip.body_names)} bodies")
    return {"model": m, "kin": kin, "dyn": dyn, "columns": cols, "direct": back, "xdd": xdd, "workspace": ws,
            "fit": fit, "hip": hip}


if __name__ == "__main__":
    main()

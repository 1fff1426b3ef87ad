"""A small machine answering the verbs of ``pkmdyn.machine_protocol``, for the simulation and control tests.

A planar two-link arm in a vertical plane (minimal coordinates: the joint angles [rad]),
driven through a constant, non-diagonal actuator map, with Coulomb friction that grows with a
load (vector regularised sign, like the hip's Eq. 16) plus per-joint viscous friction. Its
mass matrix and bias forces are the textbook ones; the equations are small enough to be
checked by hand, and the friction is as stiff as the hip's (a few N m against 0.1 kg m^2).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from types import SimpleNamespace

import numpy as np


@dataclass(frozen=True)
class ToyModel:
    m1: float = 2.0
    m2: float = 1.5
    l1: float = 0.4
    lc1: float = 0.2
    lc2: float = 0.2
    I1: float = 0.03
    I2: float = 0.02
    g: float = 9.81
    mu0: float = 0.5          # Coulomb friction without load [N m]
    mu_load: float = 1e-3     # extra Coulomb friction per newton of load [N m / N]
    viscous: float = 0.05     # [N m s/rad]
    eps: float = 1e-3         # regularisation [rad/s]
    B: tuple = ((2.0, 0.3), (-0.2, 1.5))


def mass_matrix(model, q):
    q = np.asarray(q, float)
    c2 = np.cos(q[:, 1])
    a = model.I1 + model.I2 + model.m1 * model.lc1**2 + model.m2 * (model.l1**2 + model.lc2**2)
    b = model.m2 * model.l1 * model.lc2
    d = model.I2 + model.m2 * model.lc2**2
    M = np.empty((q.shape[0], 2, 2))
    M[:, 0, 0] = a + 2 * b * c2
    M[:, 0, 1] = M[:, 1, 0] = d + b * c2
    M[:, 1, 1] = d
    return M


def bias_forces(model, q, qd, load):
    q = np.asarray(q, float)
    qd = np.asarray(qd, float)
    n = q.shape[0]
    b = model.m2 * model.l1 * model.lc2
    s2 = np.sin(q[:, 1])
    h = np.empty((n, 2))
    h[:, 0] = -b * s2 * (2 * qd[:, 0] * qd[:, 1] + qd[:, 1] ** 2)
    h[:, 1] = b * s2 * qd[:, 0] ** 2
    g = model.g
    h[:, 0] += (model.m1 * model.lc1 + model.m2 * model.l1) * g * np.cos(q[:, 0]) + model.m2 * model.lc2 * g * np.cos(q[:, 0] + q[:, 1])
    h[:, 1] += model.m2 * model.lc2 * g * np.cos(q[:, 0] + q[:, 1])
    ld = np.zeros(n) if load is None else np.asarray(load, float)
    F = model.mu0 + model.mu_load * ld
    speed = np.sqrt(np.sum(qd**2, axis=1) + model.eps**2)
    h += F[:, None] * qd / speed[:, None] + model.viscous * qd
    return h


def actuator_map(model, q):
    return np.broadcast_to(np.asarray(model.B, float), (np.asarray(q).shape[0], 2, 2)).copy()


def inverse_dynamics(model, q, qd, qdd, load):
    rhs = np.einsum("nij,nj->ni", mass_matrix(model, q), qdd) + bias_forces(model, q, qd, load)
    return np.linalg.solve(actuator_map(model, q), rhs[..., None])[..., 0]


def forward_dynamics(model, q, qd, u, load):
    rhs = np.einsum("nij,nj->ni", actuator_map(model, q), u) - bias_forces(model, q, qd, load)
    return np.linalg.solve(mass_matrix(model, q), rhs[..., None])[..., 0]


def _one(batched):
    def one(model, *args):
        *arrays, load = args
        ld = None if load is None else np.array([load], float)
        return batched(model, *[np.asarray(a, float)[None] for a in arrays], ld)[0]
    return one


def verbs(single_sample: bool = False) -> SimpleNamespace:
    """The toy machine's verbs; with ``single_sample`` also the ``*_one`` fast-path verbs."""
    ns = SimpleNamespace(COORDINATES=("q1_rad", "q2_rad"), ACTUATORS=("u1_Nm", "u2_Nm"),
                         mass_matrix=mass_matrix, bias_forces=bias_forces, actuator_map=actuator_map,
                         inverse_dynamics=inverse_dynamics, forward_dynamics=forward_dynamics)
    if single_sample:
        ns.inverse_dynamics_one = _one(inverse_dynamics)
        ns.forward_dynamics_one = _one(forward_dynamics)
    return ns


def mismatched(model: ToyModel, mass: float, friction: float) -> ToyModel:
    """The model with masses and inertias scaled by ``1 + mass`` and friction by ``1 + friction``."""
    return replace(model, m1=model.m1 * (1 + mass), m2=model.m2 * (1 + mass), I1=model.I1 * (1 + mass),
                   I2=model.I2 * (1 + mass), mu0=model.mu0 * (1 + friction), mu_load=model.mu_load * (1 + friction),
                   viscous=model.viscous * (1 + friction))


def motion(t):
    """A smooth reference with velocity reversals and a varying load: ``t -> q, qd, qdd, load``."""
    t = np.asarray(t, float)
    w = 2 * np.pi
    q = np.stack([0.3 * np.sin(w * t), 0.5 + 0.2 * np.sin(2 * w * t + 0.4)], axis=-1)
    qd = np.stack([0.3 * w * np.cos(w * t), 0.4 * w * np.cos(2 * w * t + 0.4)], axis=-1)
    qdd = np.stack([-0.3 * w * w * np.sin(w * t), -0.8 * w * w * np.sin(2 * w * t + 0.4)], axis=-1)
    load = 1000 + 800 * np.sin(w * t) ** 2
    return q, qd, qdd, load

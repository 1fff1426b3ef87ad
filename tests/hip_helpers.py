"""Shared fixtures for the hip-simulator tests: random models and smooth analytic motions."""

from __future__ import annotations

import copy

import numpy as np

from pkmdyn.machines.hip_simulator.params import HipModel, default_params_dict, model_from_dict
from pkmdyn.profiles.orientation import OrientationMotion, make_motion


def random_model(
    rng: np.random.Generator, spread: float = 0.15, friction: bool = False, inertia: dict | None = None, **geometry
) -> HipModel:
    """The paper's machine with every length, mass and inertia scaled by up to +-spread.

    Angles move by up to +-8 deg, which keeps each S joint well ahead of its module. With
    ``friction`` every friction coefficient is non-zero; ``inertia`` and ``geometry`` override
    keys of those tables.
    """
    d = copy.deepcopy(default_params_dict())

    def jitter(x: float) -> float:
        return float(x * (1.0 + spread * rng.uniform(-1, 1)))

    g = d["geometry"]
    for key in ("base_radius_m", "platform_radius_m", "lever_length_m", "screw_lead_m"):
        g[key] = jitter(g[key])
    h2 = jitter(g["platform_heights_m"][1])
    g["platform_heights_m"] = [h2 + jitter(0.409), h2]
    g["module_angles_deg"] = [a + rng.uniform(-8, 8) for a in g["module_angles_deg"]]
    g["platform_joint_angles_deg"] = [a + rng.uniform(-8, 8) for a in g["platform_joint_angles_deg"]]
    g.update(geometry)
    i = d["inertia"]
    for key in ("slider_mass_kg", "lever_mass_kg", "screw_inertia_kgm2", "gravity_m_s2"):
        i[key] = jitter(i[key])
    i["platform_mass_kg"] = float(rng.uniform(0.5, 5.0))
    i["lever_inertia_kgm2"] = [jitter(x) for x in i["lever_inertia_kgm2"]]
    i["platform_inertia_kgm2"] = [jitter(x) for x in i["platform_inertia_kgm2"]]
    i.update(inertia or {})
    if friction:
        f = d["friction"]
        for key in ("hip_radius_m", "hip_coefficient", "thrust_radius_m", "thrust_coefficient"):
            f[key] = jitter(f[key])
        f.update(
            slider_coulomb_N=rng.uniform(1, 20),
            slider_viscous_Ns_m=rng.uniform(1, 50),
            screw_coulomb_Nm=rng.uniform(0.001, 0.05),
            screw_viscous_Nms_rad=rng.uniform(1e-5, 1e-3),
            spherical_coulomb_Nm=rng.uniform(0.01, 0.5),
            spherical_viscous_Nms_rad=rng.uniform(0.001, 0.05),
            universal_coulomb_Nm=rng.uniform(0.01, 0.5),
            universal_viscous_Nms_rad=rng.uniform(0.001, 0.05),
            friction_velocity_eps_rad_s=0.05,
            friction_velocity_eps_m_s=0.01,
        )
    return model_from_dict(d, "random model")


class SmoothMotion:
    """Euler angles as sums of sinusoids, with exact rates and accelerations; a positive load."""

    def __init__(self, rng: np.random.Generator, amplitude_deg: float = 15.0, harmonics: int = 3):
        self.amp = np.deg2rad(amplitude_deg) * rng.uniform(0.2, 1.0, (harmonics, 3)) / np.arange(1, harmonics + 1)[:, None]
        self.freq = 2 * np.pi * rng.uniform(0.5, 1.5) * np.arange(1, harmonics + 1)
        self.phase = rng.uniform(0, 2 * np.pi, (harmonics, 3))
        self.offset = np.deg2rad(rng.uniform(-5, 5, 3))
        self.load_mean = rng.uniform(300, 2000)
        self.load_amp = rng.uniform(0, 0.9) * self.load_mean

    def angles(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        arg = self.freq[None, :, None] * t[:, None, None] + self.phase[None]
        q = self.offset + np.sum(self.amp * np.sin(arg), axis=1)
        qd = np.sum(self.amp * self.freq[None, :, None] * np.cos(arg), axis=1)
        qdd = -np.sum(self.amp * self.freq[None, :, None] ** 2 * np.sin(arg), axis=1)
        return q, qd, qdd

    def load(self, t: np.ndarray) -> np.ndarray:
        return self.load_mean + self.load_amp * np.sin(self.freq[0] * t + 0.3)

    def motion(self, t: np.ndarray) -> OrientationMotion:
        q, qd, qdd = self.angles(t)
        return make_motion(t, q, qd, qdd, self.load(t))

"""Dynamics on a solved motion: inverse dynamics and efforts (:mod:`.newton_euler`), every joint
reaction, unique by link compliance where over-constrained (:mod:`.compliance.reactions`), joint friction
(:mod:`.friction`), external loads (:mod:`.loads`), drives and motor efforts (:mod:`.actuators`),
and the single-sample verbs of the closed loop (:mod:`.verbs`); their compiled kernels beside them.

Every public name of these modules is importable from here; each is imported on first use."""

from __future__ import annotations

from ..._lazy import attach

__getattr__, __dir__ = attach(__name__, {
    **dict.fromkeys(("MotorEfforts", "check_actuator_rates", "check_task_rates", "effective_limits",
                     "motor_coordinates", "motor_effort_column", "motor_effort_unit", "motor_efforts", "motor_eps",
                     "motor_friction", "rotor_energy"), ".actuators"),
    **dict.fromkeys(("EPS_ROTATION", "EPS_TRANSLATION", "JointFriction", "coulomb_viscous", "friction_diverges", "known_friction",
                     "regularised_sign"),
                     ".friction"),
    **dict.fromkeys(("EffortShares", "InverseDynamics", "JointReactions", "SINGULAR_ACTUATION", "actuator_efforts",
                     "body_wrenches", "coordinate_twists", "effort_shares", "effort_unit", "energies",
                     "equilibrium_system", "free_twists", "generalised_forces", "idle_holding", "inertia_factors",
                     "inverse_dynamics", "joint_reactions", "load_forces", "named_magnitudes", "task_mass_matrix"),
                     ".newton_euler"),
    **dict.fromkeys(("ComplianceDataMissing", "beam_terms", "compliance_terms", "compliant_reactions",
                     "elastic_bodies", "joint_spring_terms"), ".compliance.reactions"),
    **dict.fromkeys(("MechanismData", "MechanismVerbs", "machine_verbs"), ".verbs"),
})

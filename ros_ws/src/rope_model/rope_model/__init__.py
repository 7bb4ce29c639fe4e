"""rope_model: ROS-free towing-rope physics (the multi-body element chain of Yoon, Lee, Park, Kim 2012; the finite-difference cable of Park & Jung).

Units SI, angles rad, world frame ENU (x east, y north, z up), water surface z = 0.

API (what the rope node uses)::

    params = load_rope_params(path)            # RopeParams; RopeParamsError (a ValueError)
                                               # naming file, key and expected range
                                               # (schema.RopeFile); FileNotFoundError
    params = load_rope_params(default_rope_path())   # Table 1 rope
    rope = RopeChain.straight(params, p_a, p_b, n_elements=None, end_a="pinned",
                              end_b="pinned", max_substep=0.01, theta=0.55,
                              relaxation=0.0, current=(0, 0, 0))
    rope = RopeChain.slack(params, p_a, p_b, n_elements=None, sag_direction=(0, 0, -1),
                           length=None, **same_keywords)
    rope = RopeChain.wound_on_winch(params, p_a, p_b, deployed_length=None,
                                    n_elements=None, sag_direction=(0, 0, -1),
                                    heading=(1, 0, 0), **same_keywords)
    rope.set_end_kinematics("a" | "b", position(3,), velocity(3,))   # pinned ends
    notes = rope.set_payout_rate(rate_m_per_s)  # winch at end a: + pays out, - heaves in;
                                               # clamped to params.winch_max_payout_speed /
                                               # winch_max_heave_speed, notes: list of str
    rope.set_environment(current=None, wind=None, seabed_depth=None)
                                               # each step, sampled at rope.element_centres()
                                               # (N,3): current / wind (3,) or (N,3) m/s,
                                               # seabed depth m positive down (number or (N,),
                                               # inf = none); replaces all three, None = calm;
                                               # ValueError naming argument and element
    rope.step(dt)                              # exchange period; internal sub-steps;
                                               # RopeDivergedError(step, time, element,
                                               # connection): also a "parting" without strain
    rope.end_force("a" | "b")                  # (3,) force ON the attachment, N, world
    rope.mean_end_force("a" | "b")             # same, averaged over the last step
    rope.positions, .axes, .velocities, .angular_velocities, .lengths, .pitch_yaw,
    rope.body_velocities(), .tensions (N+1 connections: 0 = end a, N = end b),
    rope.joint_points(), .unstretched_length, .total_mass, .pieces, .events
    (PartingEvent(time, connection, tension)), .momentum(), .kinetic_energy(),
    .potential_energy(), .total_energy(), .time, .n_elements (changes with the winch),
    .breaking_load (N+1,) per-connection strength, .params

Model, integrator and its stability limit, validation and benchmark: ../README.md.

End modes: "pinned" (moves with set_end_kinematics), "fixed" (stays where created),
"free" (no attachment).
"""
from .chain import END_MODES, PartingEvent, RopeChain, RopeDivergedError
from .params import (G0, KNOT, TONNE_FORCE, RopeParams, RopeParamsError, default_rope_path,
                     load_rope_params)

__all__ = [
    "END_MODES", "G0", "KNOT", "TONNE_FORCE", "PartingEvent", "RopeChain",
    "RopeDivergedError", "RopeParams", "RopeParamsError", "default_rope_path",
    "load_rope_params",
]

"""Saturation-aware allocation: yaw is given up first, then roll and pitch are scaled, and a
thrust beyond what the rotors have gives way to roll and pitch.

Fixed-pitch rotors only push and have a maximum thrust. A law that asks for more than the
rotors can give gets each rotor clipped, which changes every input at once: a clipped rotor
takes away roll or pitch moment and adds a yaw moment, the yaw error grows, correcting it asks
for more differential thrust, and the vehicle can tumble. Flight stacks therefore allocate by
priority. ``prioritized_input`` does that for a Vehicle's mixer: with f = mixer^-1 U split
into the parts of U1 (``a U1``), of (U2, U3) (``f_rp``) and of U4 (``f_y``),

    f = a U1' + s_rp f_rp + s_y f_y,   s_rp, s_y in [0, 1] as large as the limits allow.

- While U1 alone is within the rotors' range (``a U1`` within the limits), the thrust is kept
  (U1' = U1), the roll-pitch moment is scaled as far as the limits allow on top of it, then
  yaw: total thrust, roll and pitch, yaw.
- When U1 alone is not (more than the rotors' total, as a payload heavier than they can lift
  makes a mass-learning law ask, or below zero), keeping it would leave no roll-pitch moment
  at all (s_rp = 0 once a U1 is beyond the limits), and the attitude, which points the
  thrust, would be lost. Then roll and pitch come first: s_rp is the largest scale that some
  total thrust can carry within the limits, U1' the thrust nearest to U1 that carries it,
  then yaw.

So the delivered input is U itself when it is feasible, else [U1', s_rp U2, s_rp U3, s_y U4]:
the roll-pitch moment keeps its direction, and yaw is the first to yield. The law then knows
exactly what the rotors deliver (every rotor thrust is within its limits, nothing is clipped
downstream). In AdaptiveQuadBench's payload of twice the vehicle's mass, the SE(3) law with
the thrust kept beyond the rotors' total tipped over (docs/aqb.md). Thrust yielding to roll
and pitch also within the range (as PX4's "airmode" does) tipped the balance the other way:
the SE(3) law's delay margin in AdaptiveQuadBench fell from 0.02 s to 0.01 s.
"""
import casadi as ca

from quadcog.vehicles.vehicle import Vehicle

__all__ = ["prioritized_input"]

_TINY = 1e-12


def _largest_step(base, direction, lower, upper):
    """Largest s in [0, 1] with lower <= base + s direction <= upper for every rotor (SX);
    0 when base itself is outside the limits."""
    s = ca.SX(1.0)
    for i in range(base.numel()):
        b, d = base[i], direction[i]
        up = ca.if_else(d > _TINY, (upper - b) / ca.fmax(d, _TINY), 1.0)
        down = ca.if_else(d < -_TINY, (lower - b) / ca.fmin(d, -_TINY), 1.0)
        s = ca.fmin(s, ca.fmin(up, down))
    return ca.fmax(s, 0.0)


def _roll_pitch_scale(a, r, lower, upper):
    """Largest s in [0, 1] for which some U1 holds ``lower <= a_i U1 + s r_i <= upper`` for
    every rotor i (a_i > 0): for every pair i, j, ``(lower - s r_i) / a_i <= (upper - s r_j)
    / a_j``."""
    s = ca.SX(1.0)
    n = a.numel()
    for i in range(n):
        for j in range(n):
            if i != j:
                d = r[i] / a[i] - r[j] / a[j]
                room = upper / a[j] - lower / a[i]
                s = ca.if_else(d > _TINY, ca.fmin(s, room / ca.fmax(d, _TINY)), s)
    return ca.fmax(s, 0.0)


def prioritized_input(U: ca.SX, vehicle: Vehicle) -> ca.SX:
    """U reduced to what ``vehicle``'s rotors can deliver, yaw first; a thrust beyond the
    rotors' range gives way to roll and pitch (see the module docstring).

    Parameters
    ----------
    U : casadi.SX
        The commanded input (4x1) [U1 (N), U2, U3, U4 (N m, about O)].
    vehicle : Vehicle
        Whose mixer and rotor thrust limits (N) apply.

    Returns
    -------
    casadi.SX
        U itself when feasible, else [U1', s_rp U2, s_rp U3, s_y U4] (4x1), every rotor
        thrust within the limits; U1' = U1 while U1 alone is within the rotors' range.
    """
    inv = ca.DM(vehicle.mixer_inverse())
    lower, upper = vehicle.min_rotor_thrust, vehicle.max_rotor_thrust
    a = inv[:, 0]
    f_T = a * U[0]
    f_rp = inv[:, 1:3] @ U[1:3]
    f_y = inv[:, 3] * U[3]
    n = a.numel()
    # the thrust kept: roll-pitch, then yaw, on top of it
    s_rp = _largest_step(f_T, f_rp, lower, upper)
    s_y = _largest_step(f_T + s_rp * f_rp, f_y, lower, upper)
    kept = ca.vertcat(U[0], s_rp * U[1], s_rp * U[2], s_y * U[3])
    # the thrust beyond the rotors' range: roll-pitch first, then the thrust, then yaw
    t_rp = _roll_pitch_scale(a, f_rp, lower, upper)
    lo_T = ca.mmax(ca.vertcat(*[(lower - t_rp * f_rp[i]) / a[i] for i in range(n)]))
    hi_T = ca.mmin(ca.vertcat(*[(upper - t_rp * f_rp[i]) / a[i] for i in range(n)]))
    U1 = ca.fmin(ca.fmax(U[0], lo_T), hi_T)
    t_y = _largest_step(a * U1 + t_rp * f_rp, f_y, lower, upper)
    yielded = ca.vertcat(U1, t_rp * U[1], t_rp * U[2], t_y * U[3])
    f = f_T + f_rp + f_y
    feasible = ca.logic_and(ca.mmin(f) >= lower, ca.mmax(f) <= upper)
    thrust_inside = ca.logic_and(ca.mmin(f_T) >= lower, ca.mmax(f_T) <= upper)
    return ca.if_else(feasible, U, ca.if_else(thrust_inside, kept, yielded))

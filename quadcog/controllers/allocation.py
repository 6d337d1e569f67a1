"""Saturation-aware allocation: yaw is given up first, then roll and pitch are scaled.

Fixed-pitch rotors only push and have a maximum thrust. A law that asks for more than the
rotors can give gets each rotor clipped, which changes every input at once: a clipped rotor
takes away roll or pitch moment and adds a yaw moment, the yaw error grows, correcting it asks
for more differential thrust, and the vehicle can tumble. Flight stacks therefore allocate by
priority (total thrust, then roll and pitch, then yaw). ``prioritized_input`` does that for a
Vehicle's mixer: with f = mixer^-1 U split into the parts of U1, of (U2, U3) and of U4,

    f = f_T + s_rp f_rp + s_y f_y,   s_rp, s_y in [0, 1] as large as the limits allow,

so the delivered input is U itself when it is feasible, else [U1, s_rp U2, s_rp U3, s_y U4]: the
roll-pitch moment keeps its direction, and yaw is the first to yield. The law then knows
exactly what the rotors deliver (no clipping happens downstream while the thrust itself is
feasible).
"""
import casadi as ca

from quadcog.vehicles.vehicle import Vehicle

__all__ = ["prioritized_input"]


def _largest_step(base, direction, lower, upper):
    """Largest s in [0, 1] with lower <= base + s direction <= upper for every rotor (SX);
    0 when base itself is outside the limits."""
    s = ca.SX(1.0)
    for i in range(base.numel()):
        b, d = base[i], direction[i]
        up = ca.if_else(d > 1e-12, (upper - b) / ca.fmax(d, 1e-12), 1.0)
        down = ca.if_else(d < -1e-12, (lower - b) / ca.fmin(d, -1e-12), 1.0)
        s = ca.fmin(s, ca.fmin(up, down))
    return ca.fmax(s, 0.0)


def prioritized_input(U: ca.SX, vehicle: Vehicle) -> ca.SX:
    """U reduced to what ``vehicle``'s rotors can deliver, yaw first (see the module docstring).

    Parameters
    ----------
    U : casadi.SX
        The commanded input (4x1) [U1 (N), U2, U3, U4 (N m, about O)].
    vehicle : Vehicle
        Whose mixer and rotor thrust limits (N) apply.

    Returns
    -------
    casadi.SX
        U itself when feasible, else [U1, s_rp U2, s_rp U3, s_y U4] (4x1).
    """
    inv = ca.DM(vehicle.mixer_inverse())
    lower, upper = vehicle.min_rotor_thrust, vehicle.max_rotor_thrust
    f_T = inv[:, 0] * U[0]
    f_rp = inv[:, 1:3] @ U[1:3]
    f_y = inv[:, 3] * U[3]
    s_rp = _largest_step(f_T, f_rp, lower, upper)
    s_y = _largest_step(f_T + s_rp * f_rp, f_y, lower, upper)
    f = f_T + f_rp + f_y
    feasible = ca.logic_and(ca.mmin(f) >= lower, ca.mmax(f) <= upper)
    return ca.if_else(feasible, U, ca.vertcat(U[0], s_rp * U[1], s_rp * U[2], s_y * U[3]))

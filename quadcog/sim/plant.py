"""The truth model: the generated ``truth_dynamics`` driven through the vehicle's rotors, with
optional parallel-axis inertia, rotor saturation and first-order motor lag, integrated by one
fixed RK4 step (a CasADi expression, compiled on use).

The rotors always hold ``f >= 0`` (fixed-pitch rotors only push): the commanded input U is
mapped to rotor thrusts by the inverse mixer, clipped, and mapped back. Saturation clips to
``[min_rotor_thrust, max_rotor_thrust]`` instead; motor lag makes the rotor thrusts states that
follow the clipped command with the vehicle's motor time constant.
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np

from quadcog.errors import InputError
from quadcog.model.conventions import IDX, R_G, hover_trim
from quadcog.vehicles.vehicle import N_ROTORS


@dataclass(frozen=True)
class TruthOptions:
    """Effects of the truth model that the controllers' model leaves out (docs/model.md sec. 5;
    all off by default).

    Parameters
    ----------
    parallel_axis : the inertia about O follows the moving mass,
        ``I_O = I_G + m (|r_G|^2 I - r_G r_G^T)``, ``I_G`` being the vehicle's diagonal inertia
        (its inertia about the CoG when r_G = 0).
    rotor_saturation : each rotor's thrust is clipped to the vehicle's
        ``[min_rotor_thrust, max_rotor_thrust]`` (without it: to ``[0, inf)``).
    motor_lag : rotor thrusts follow the clipped command through a first-order lag with the
        vehicle's ``motor_time_constant`` (adds 4 rotor-thrust states; a time constant of 0 is
        instant, i.e. no lag).
    """
    parallel_axis: bool = False
    rotor_saturation: bool = False
    motor_lag: bool = False

    def __post_init__(self):
        for name in ("parallel_axis", "rotor_saturation", "motor_lag"):
            if not isinstance(getattr(self, name), (bool, np.bool_)):
                raise InputError(f"TruthOptions.{name} must be True or False, got "
                                 f"{getattr(self, name)!r}")


@dataclass(frozen=True)
class Actuation:
    """The rotors of one vehicle under given truth options: what the plant step bakes in
    (hashable, so it keys the compile cache). Build it with ``Actuation.of(vehicle, options)``.
    """
    options: TruthOptions
    mixer: tuple                 # (4, 4) row-major, U = mixer @ f
    lower: float                 # N, per rotor
    upper: float                 # N, per rotor (inf without saturation)
    time_constant: float         # s; 0: instant

    @classmethod
    def of(cls, vehicle, options=None):
        """The actuation of ``vehicle`` (a Vehicle) under ``options`` (TruthOptions)."""
        options = options or TruthOptions()
        sat = options.rotor_saturation
        return cls(options, tuple(vehicle.mixer().ravel().tolist()),
                   vehicle.min_rotor_thrust if sat else 0.0,
                   vehicle.max_rotor_thrust if sat else float("inf"),
                   vehicle.motor_time_constant if options.motor_lag else 0.0)

    @property
    def n_rotor_states(self):
        """4 when the rotor thrusts are states (motor lag with a time constant > 0), else 0."""
        return N_ROTORS if self.time_constant > 0 else 0

    def mixer_matrix(self):
        """The (4, 4) mixer as a numpy array."""
        return np.array(self.mixer).reshape(4, 4)

    def rotor_command(self, U):
        """Rotor thrusts (SX or DM 4x1) for input U: inverse mixer, then the limits."""
        f = ca.DM(np.linalg.inv(self.mixer_matrix())) @ U
        clipped = ca.fmax(f, self.lower)
        if not np.isinf(self.upper):
            clipped = ca.fmin(clipped, self.upper)
        # a non-finite command stays non-finite (fmax(NaN, 0) = 0 would hide a failed law)
        return ca.if_else(ca.fabs(f) < np.inf, clipped, f)

    def rotor_command_numpy(self, U):
        """``rotor_command`` for a numpy U (4,), or (B, 4) for many flights."""
        U = np.asarray(U, dtype=float)
        f = np.linalg.solve(self.mixer_matrix(), U.T).T
        return np.clip(f, self.lower, self.upper)


def truth_arguments(p, options):
    """(p with adjusted diagonal inertia, I_products) for the truth model (SX)."""
    if not options.parallel_axis:
        return p, ca.SX.zeros(3)
    m, r = p[IDX["m"]], p[R_G.start:R_G.stop]
    x, y, z = r[0], r[1], r[2]
    diag = ca.vertcat(y * y + z * z, x * x + z * z, x * x + y * y) * m
    p_eff = ca.vertcat(p[:IDX["Ixx"]], p[IDX["Ixx"]:IDX["Izz"] + 1] + diag, p[IDX["Izz"] + 1:])
    return p_eff, -m * ca.vertcat(x * y, x * z, y * z)


def rk4_step_expression(model, x, f, U, p, wrench, dt, actuation):
    """One RK4 step of length dt of the truth plant with U, p and wrench held.

    x: 12 states; f: the rotor thrusts (4x1) when ``actuation.n_rotor_states`` is 4, else an
    empty SX. Returns (x_next, f_next, U_applied): U_applied is the input the rotors deliver at
    the start of the step (mixer @ rotor thrusts)."""
    truth = model.casadi_function("truth_dynamics")
    mix = ca.DM(actuation.mixer_matrix())
    p_eff, products = truth_arguments(p, actuation.options)
    f_cmd = actuation.rotor_command(U)
    if not actuation.n_rotor_states:
        U_app = mix @ f_cmd
        rhs = lambda s: truth(s, U_app, p_eff, products, wrench)
        k1 = rhs(x)
        k2 = rhs(x + dt / 2 * k1)
        k3 = rhs(x + dt / 2 * k2)
        k4 = rhs(x + dt * k3)
        return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4), f, U_app
    tau = actuation.time_constant
    n = x.numel()

    def rhs(s):
        xs, fs = s[:n], s[n:]
        return ca.vertcat(truth(xs, mix @ fs, p_eff, products, wrench), (f_cmd - fs) / tau)

    s = ca.vertcat(x, f)
    k1 = rhs(s)
    k2 = rhs(s + dt / 2 * k1)
    k3 = rhs(s + dt / 2 * k2)
    k4 = rhs(s + dt * k3)
    s_next = s + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s_next[:n], s_next[n:], mix @ f


def plant_step_function(model, actuation):
    """CasADi Function plant_step(x, f, U, p, wrench, dt) -> (x_next, f_next, U_applied);
    f has ``actuation.n_rotor_states`` entries (0 or 4)."""
    nf = actuation.n_rotor_states
    x, f, U, p = ca.SX.sym("x", 12), ca.SX.sym("f", nf), ca.SX.sym("U", 4), ca.SX.sym("p", 14)
    w, dt = ca.SX.sym("wrench", 6), ca.SX.sym("dt")
    x_next, f_next, U_app = rk4_step_expression(model, x, f, U, p, w, dt, actuation)
    return ca.Function("plant_step", [x, f, U, p, w, dt], [x_next, f_next, U_app],
                       ["x", "f", "U", "p", "wrench", "dt"], ["x_next", "f_next", "U_applied"])


def initial_rotor_thrusts(P0, actuation):
    """Rotor thrusts (n_rotor_states,) at t = 0: those of a level hover of the truth
    parameters ``P0`` (14,) (r_G at t = 0), within the limits (the motors spin up before the
    run starts); (B, n_rotor_states) for parameters (B, 14) of many flights."""
    if not actuation.n_rotor_states:
        return np.zeros(np.shape(P0)[:-1] + (0,))
    return actuation.rotor_command_numpy(hover_trim(P0))

"""The truth model: the generated ``truth_dynamics`` with optional parallel-axis inertia and
rotor saturation, integrated by one fixed RK4 step (a CasADi expression, compiled on use)."""
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .conventions import IDX
from .params import ARM_LENGTH, MAX_ROTOR_SPEED, MOMENT_CONSTANT, THRUST_CONSTANT


def mixer_matrix(arm=ARM_LENGTH, moment_constant=MOMENT_CONSTANT):
    """U = mixer @ f for rotor thrusts f (N) of a '+' layout: rotor 1 on +x, 2 on +y,
    3 on -x, 4 on -y; rotors 1 and 3 spin so that their drag moment is +k f about z."""
    l, k = arm, moment_constant
    return np.array([[1.0, 1.0, 1.0, 1.0],
                     [0.0, l, 0.0, -l],      # roll: thrust at +y lifts the +y side
                     [-l, 0.0, l, 0.0],      # pitch: thrust at +x noses up (negative about y)
                     [k, -k, k, -k]])


MAX_ROTOR_THRUST = THRUST_CONSTANT * MAX_ROTOR_SPEED ** 2     # N, about 6.0 N per rotor


@dataclass(frozen=True)
class TruthOptions:
    """Effects the controller's model leaves out (docs/model.md sec. 5).

    parallel_axis: I_O = I_G + m (|r_G|^2 I - r_G r_G^T) follows the moving mass, I_G being
        the diagonal of p (the inertia about the CoG when r_G = 0).
    rotor_saturation: per-rotor thrust limited to [0, max_rotor_thrust] through the mixer.
    """
    parallel_axis: bool = False
    rotor_saturation: bool = False
    max_rotor_thrust: float = MAX_ROTOR_THRUST


def applied_input(U, options):
    """The input the rotors can deliver (SX or DM): mixer, clip, mixer back."""
    if not options.rotor_saturation:
        return U
    mix = ca.DM(mixer_matrix())
    f = ca.solve(mix, ca.DM.eye(4)) @ U
    return mix @ ca.fmin(ca.fmax(f, 0), options.max_rotor_thrust)


def truth_arguments(p, options):
    """(p with adjusted diagonal inertia, I_products) for the truth model (SX)."""
    if not options.parallel_axis:
        return p, ca.SX.zeros(3)
    m, r = p[IDX["m"]], p[IDX["x_G"]:IDX["z_G"] + 1]
    x, y, z = r[0], r[1], r[2]
    diag = ca.vertcat(y * y + z * z, x * x + z * z, x * x + y * y) * m
    p_eff = ca.vertcat(p[:IDX["Ixx"]], p[IDX["Ixx"]:IDX["Izz"] + 1] + diag, p[IDX["Izz"] + 1:])
    return p_eff, -m * ca.vertcat(x * y, x * z, y * z)


def rk4_step_expression(model, x, U, p, wrench, dt, options):
    """x after one RK4 step of length dt with U, p and wrench held. Returns (x_next, U_applied)."""
    f = model.casadi_function("truth_dynamics")
    U_app = applied_input(U, options)
    p_eff, products = truth_arguments(p, options)
    rhs = lambda s: f(s, U_app, p_eff, products, wrench)
    k1 = rhs(x)
    k2 = rhs(x + dt / 2 * k1)
    k3 = rhs(x + dt / 2 * k2)
    k4 = rhs(x + dt * k3)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4), U_app


def plant_step_function(model, options):
    """CasADi Function plant_step(x, U, p, wrench, dt) -> (x_next, U_applied)."""
    x, U, p = ca.SX.sym("x", 12), ca.SX.sym("U", 4), ca.SX.sym("p", 14)
    w, dt = ca.SX.sym("wrench", 6), ca.SX.sym("dt")
    x_next, U_app = rk4_step_expression(model, x, U, p, w, dt, options)
    return ca.Function("plant_step", [x, U, p, w, dt], [x_next, U_app],
                       ["x", "U", "p", "wrench", "dt"], ["x_next", "U_applied"])

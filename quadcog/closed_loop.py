"""One closed-loop step as a CasADi expression, and the per-step table that drives it.

Each step k: the controller runs once at t_k (a 1/dt digital controller), its input is held
for the step, the truth plant takes one RK4 step, the controller state takes an Euler step.
Everything that changes with time comes in through the step table, one row per step:
[t, dt, tail, ref (14), r_table (3), s, wrench (6)], and the CoG at step k is
r_G = s * r_G(p) + r_table (s = 1 and r_G(p) = 0 for a single flight with a CoG profile;
a batch shares the table and gives each flight its own r_G(p)).
"""
import casadi as ca
import numpy as np

from .conventions import IDX
from .plant import rk4_step_expression
from .trajectory import REF_SIZE

TABLE = {"t": 0, "dt": 1, "tail": 2, "ref": slice(3, 17), "r_table": slice(17, 20), "s": 20,
         "wrench": slice(21, 27)}
TABLE_SIZE = 27
assert TABLE["ref"].stop - TABLE["ref"].start == REF_SIZE


def step_table(times, dt, refs, r_table, wrenches, s=1.0, tail_from=np.inf):
    """(N, TABLE_SIZE) table for the steps starting at ``times``."""
    n = len(times)
    table = np.zeros((n, TABLE_SIZE))
    table[:, TABLE["t"]] = times
    table[:, TABLE["dt"]] = dt
    table[:, TABLE["tail"]] = times >= tail_from - 1e-12
    table[:, TABLE["ref"]] = refs
    table[:, TABLE["r_table"]] = r_table
    table[:, TABLE["s"]] = s
    table[:, TABLE["wrench"]] = wrenches
    return table


def truth_parameters(P, row):
    """Truth parameters at a step: P with r_G = s * r_G(P) + r_table (SX or numpy)."""
    r = row[TABLE["s"]] * P[IDX["x_G"]:IDX["z_G"] + 1] + row[TABLE["r_table"]]
    if isinstance(P, np.ndarray):
        out = P.copy()
        out[IDX["x_G"]:IDX["z_G"] + 1] = r
        return out
    return ca.vertcat(P[:IDX["x_G"]], r)


def closed_loop_step(controller, actuation):
    """CasADi Function step(X, P, row) -> (X_next, U_applied), X = [x (12); f (rotor thrusts,
    actuation.n_rotor_states); c (controller state, n_state)]."""
    nc, nf = controller.n_state, actuation.n_rotor_states
    X, P, row = ca.SX.sym("X", 12 + nf + nc), ca.SX.sym("P", 14), ca.SX.sym("row", TABLE_SIZE)
    x, f, c = X[:12], X[12:12 + nf], X[12 + nf:]
    t, dt = row[TABLE["t"]], row[TABLE["dt"]]
    U, c_dot = controller.function()(t, x, row[TABLE["ref"]], c)
    x_next, f_next, U_app = rk4_step_expression(controller.model, x, f, U,
                                                truth_parameters(P, row), row[TABLE["wrench"]],
                                                dt, actuation)
    X_next = ca.vertcat(x_next, f_next, controller.project(c + dt * c_dot) if nc else ca.SX(0, 1))
    X_next, U_app = ca.cse([X_next, U_app])    # the RK4 stages share parameter-only terms
    return ca.Function("closed_loop_step", [X, P, row], [X_next, U_app],
                       ["X", "P", "row"], ["X_next", "U_applied"])


def monitored_step(controller, actuation, limits):
    """Step with metric accumulators, for batches that keep no trajectory.

    State [X; sum e^2; max e; sum e^2 over the tail; diverged_at (-1: not)], where e is the
    position error at the start of each step. Once diverged, the state is frozen."""
    step = closed_loop_step(controller, actuation)
    nX = step.size1_in(0)
    Z, P, row = ca.SX.sym("Z", nX + 4), ca.SX.sym("P", 14), ca.SX.sym("row", TABLE_SIZE)
    X, acc = Z[:nX], Z[nX:]
    X_next, _ = step(X, P, row)
    err = ca.norm_2(X[:3] - row[TABLE["ref"]][:3])
    bad = divergence_flag(X, err, limits)
    new_acc = ca.vertcat(acc[0] + err ** 2, ca.fmax(acc[1], err),
                         acc[2] + row[TABLE["tail"]] * err ** 2, acc[3])
    diverged_now = ca.vertcat(X, acc[:3], row[TABLE["t"]])
    running = ca.if_else(bad, diverged_now, ca.vertcat(X_next, new_acc))
    Z_next = ca.if_else(acc[3] >= 0, Z, running)
    return ca.Function("monitored_step", [Z, P, row], [Z_next], ["Z", "P", "row"], ["Z_next"])


def divergence_flag(X, err, limits):
    """SX: 1 when the state is non-finite, too far from the reference or too tilted."""
    big = 1e12
    finite = ca.logic_and(ca.mmax(ca.fabs(X[:12])) < big, err < big)
    return ca.logic_or(ca.logic_not(finite),
                       ca.logic_or(err > limits.max_position_error,
                                   ca.fmax(ca.fabs(X[3]), ca.fabs(X[4])) > limits.max_tilt))

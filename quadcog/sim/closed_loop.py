"""One closed-loop step as a CasADi expression, and its compiled chunks.

Each step k: the controller runs once at t_k (a 1/dt digital controller), its input is held
for the step, the truth plant takes one RK4 step, the controller state takes an Euler step.
The state is X = [x (12); f (rotor thrusts, 0 or 4); c (controller state)]. Everything that
changes with time comes from the Schedule's named per-step inputs (``STEP_INPUTS``).
"""
from collections.abc import Hashable
import itertools

import casadi as ca

from quadcog.codegen.compiled import cached_compile
from quadcog.codegen.flight_kernel import FlightKernel
from quadcog.codegen.vector_kernel import kernel_isa
from quadcog.controllers.base import Controller
from quadcog.errors import CompileError, KernelError
from quadcog.model.conventions import N_PARAM, N_STATE, R_G
from quadcog.sim.divergence import Limits, divergence_code
from quadcog.sim.plant import Actuation, rk4_step_expression
from quadcog.sim.schedule import STEP_INPUTS, truth_parameters

__all__ = ["CHUNK", "ACCUMULATORS", "SLOW_INPUTS", "closed_loop_step", "chunk_function",
           "flight_kernel", "monitored_step", "chunk_of", "monitored_chunk_function", "packed"]

CHUNK = 1000          # steps per compiled call
# the per-step inputs that stay the same for long runs of steps (they change only while the
# CoG moves): the single-flight kernel reruns what depends only on them and P when they change
SLOW_INPUTS = ("cog", "cog_scale", "payload")


def _step_symbols() -> dict[str, ca.SX]:
    return {name: ca.SX.sym(name, rows) for name, rows in STEP_INPUTS}


def closed_loop_step(controller: Controller, actuation: Actuation, limits: Limits
                     ) -> ca.Function:
    """One closed-loop step as a CasADi Function.

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.

    Returns
    -------
    casadi.Function
        ``step(X, P, t, dt, ref, cog, cog_scale, payload, wrench, tail) -> (X_next, U_applied,
        position_error, code)``:
        P is the vehicle's parameter vector (14,), the per-step inputs are those of
        ``STEP_INPUTS``; position_error |p - p_ref| (m) and code, the divergence code, are
        those of the sample at the start of the step (X and the controller's input U there,
        with ref).
    """
    nc, nf = controller.n_state, actuation.n_rotor_states
    X, P = ca.SX.sym("X", N_STATE + nf + nc), ca.SX.sym("P", N_PARAM)
    s = _step_symbols()
    x, f, c = X[:N_STATE], X[N_STATE:N_STATE + nf], X[N_STATE + nf:]
    U, c_dot = controller.function()(s["t"], x, s["ref"], c)
    x_next, f_next, U_app = rk4_step_expression(
        controller.model, x, f, U, truth_parameters(P, s["cog_scale"], s["cog"]), s["wrench"],
        s["dt"], actuation, s["payload"], P[R_G.start:R_G.stop])
    X_next = ca.vertcat(x_next, f_next,
                        controller.project(c + s["dt"] * c_dot) if nc else ca.SX(0, 1))
    e = ca.norm_2(x[:3] - s["ref"][:3])
    code = divergence_code(x, e, limits, ca.sum1(ca.fabs(ca.vertcat(f, c, U))))
    # one CSE over all outputs: the RK4 stages share parameter-only terms, and the code's U
    # is the law's output (apart, the law ran twice per step)
    X_next, U_app, e, code = ca.cse([X_next, U_app, e, code])
    names = [name for name, _ in STEP_INPUTS]
    return ca.Function("closed_loop_step", [X, P] + [s[n] for n in names],
                       [X_next, U_app, e, code], ["X", "P"] + names,
                       ["X_next", "U_applied", "position_error", "code"])


def chunk_function(controller: Controller, actuation: Actuation, limits: Limits,
                   n: int = CHUNK) -> ca.Function:
    """n closed-loop steps as one compiled Function (cached).

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.
    n : int
        Steps per call.

    Returns
    -------
    casadi.Function
        ``(X0, P, per-step inputs with n columns each) -> (X (nX x n), U (4 x n),
        position_error (1 x n), code (1 x n))``: X after each step, the position error and
        the code (``divergence_code``) of the sample before each. P is shared by all steps.
    """
    def build():
        step = closed_loop_step(controller, actuation, limits)
        acc = step.mapaccum("closed_loop_steps", n)
        X0, P = ca.MX.sym("X0", step.size1_in(0)), ca.MX.sym("P", N_PARAM)
        per_step = [ca.MX.sym(name, rows, n) for name, rows in STEP_INPUTS]
        Xs, Us, es, codes = acc(X0, ca.repmat(P, 1, n), *per_step)
        return ca.Function("closed_loop_chunk", [X0, P] + per_step, [Xs, Us, es, codes],
                           ["X0", "P"] + [name for name, _ in STEP_INPUTS],
                           ["X", "U", "position_error", "code"])
    return cached_compile(("chunk", controller.cache_key(), actuation, limits, n), build)


_flight_kernels: dict[Hashable, FlightKernel | None] = {}


def flight_kernel(controller: Controller, actuation: Actuation, limits: Limits
                  ) -> FlightKernel | None:
    """The closed-loop step of one flight as a compiled C loop (built once per process).

    ``quadcog.codegen.flight_kernel`` emits the loop from ``closed_loop_step``: the same
    operations, rounded the same way, as the CasADi chunk of ``chunk_function``, with what
    depends only on P run once and what depends only on P and the CoG profile
    (``SLOW_INPUTS``) run again only where the profile changes.

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.

    Returns
    -------
    FlightKernel or None
        Its inputs are (P, *STEP_INPUTS), its per-step outputs U_applied and
        position_error (then the code); None without
        a C compiler or where the loop does not build (the caller then runs
        ``chunk_function``).
    """
    key = (controller.cache_key(), actuation, limits, kernel_isa())
    if key not in _flight_kernels:
        names = [name for name, _ in STEP_INPUTS]
        try:
            _flight_kernels[key] = FlightKernel(
                closed_loop_step(controller, actuation, limits), constant=(1,),
                slow=[2 + names.index(name) for name in SLOW_INPUTS])
        except (KernelError, CompileError):
            _flight_kernels[key] = None
    return _flight_kernels[key]


# accumulators of a monitored step, after X: sums over the counted samples
ACCUMULATORS = ("sum_sq", "max", "sum_sq_tail", "count", "count_tail", "last", "code",
                "diverged_at")


def monitored_step(controller: Controller, actuation: Actuation, limits: Limits
                   ) -> ca.Function:
    """Step with metric accumulators, for batches that keep no trajectory.

    State Z = [X; accumulators (``ACCUMULATORS``)]: the position error e of the sample at the
    start of each real step (dt > 0) is added to the sums unless that sample has diverged
    (``divergence_code``); then the code and the time are kept and the state is frozen.

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.

    Returns
    -------
    casadi.Function
        ``monitored_step(Z, P, *per_step) -> Z_next`` (SX).
    """
    step = closed_loop_step(controller, actuation, limits)
    nX = step.size1_in(0)
    Z, P = ca.SX.sym("Z", nX + len(ACCUMULATORS)), ca.SX.sym("P", N_PARAM)
    s = _step_symbols()
    X, a = Z[:nX], dict(zip(ACCUMULATORS, ca.vertsplit(Z[nX:])))
    X_next, _, e, code = step(X, P, *[s[name] for name, _ in STEP_INPUTS])
    real = s["dt"] > 0
    counted = ca.vertcat(
        a["sum_sq"] + real * e ** 2, ca.if_else(real, ca.fmax(a["max"], e), a["max"]),
        a["sum_sq_tail"] + real * s["tail"] * e ** 2, a["count"] + real,
        a["count_tail"] + real * s["tail"], ca.if_else(real, e, a["last"]), 0, -1)
    stopped = ca.vertcat(X, ca.vertcat(*[a[k] for k in ACCUMULATORS[:6]]), code, s["t"])
    running = ca.if_else(code > 0, stopped, ca.vertcat(X_next, counted))
    Z_next = ca.if_else(a["code"] > 0, Z, running)
    return ca.Function("monitored_step", [Z, P] + [s[name] for name, _ in STEP_INPUTS],
                       [Z_next])


def chunk_of(step: ca.Function, key: Hashable, n: int = CHUNK) -> ca.Function:
    """n steps of an SX step Function, compiled: the CasADi path of every batch.

    It is the vector kernel's fallback.

    Parameters
    ----------
    step : casadi.Function
        ``step(Z, Q, *per_step) -> Z_next``.
    key : hashable
        The compile-cache key of ``step``.
    n : int
        Steps per call.

    Returns
    -------
    casadi.Function
        ``(Z, Q, per-step inputs (n columns each)) -> Z`` after n steps.
    """
    def build():
        acc = step.mapaccum(step.name() + "_chunk", n)
        Z, Q = ca.MX.sym("Z", step.size1_in(0)), ca.MX.sym("Q", step.size1_in(1))
        per_step = [ca.MX.sym(f"in{i}", step.size1_in(i), n) for i in range(2, step.n_in())]
        return ca.Function(step.name() + "_last", [Z, Q] + per_step,
                           [acc(Z, ca.repmat(Q, 1, n), *per_step)[:, -1]])
    return cached_compile(("chunk", key, n), build)


def monitored_chunk_function(controller: Controller, actuation: Actuation, limits: Limits,
                             n: int = CHUNK) -> ca.Function:
    """n monitored steps (``monitored_step``) as one compiled Function.

    Parameters
    ----------
    controller : Controller
        The law (designed for its model already).
    actuation : Actuation
        The truth's rotors.
    limits : Limits
        The divergence limits.
    n : int
        Steps per call.

    Returns
    -------
    casadi.Function
        ``(Z, P, per-step inputs (n columns)) -> Z`` after n monitored steps.
    """
    return chunk_of(monitored_step(controller, actuation, limits),
                    ("batch", controller.cache_key(), actuation, limits), n)


def packed(step: ca.Function) -> ca.Function:
    """A step Function with its per-step inputs stacked into one row.

    For the vector kernel (``quadcog.codegen.vector_kernel``), which takes one row per step;
    ``Schedule.rows`` writes them in the same order.

    Parameters
    ----------
    step : casadi.Function
        The SX Function ``step(Z, Q, *per_step) -> Z_next``.

    Returns
    -------
    casadi.Function
        ``step(Z, Q, row) -> Z_next``, with row the per-step inputs stacked in their order.
    """
    Z, Q = ca.SX.sym("Z", step.size1_in(0)), ca.SX.sym("Q", step.size1_in(1))
    sizes = [step.size1_in(i) for i in range(2, step.n_in())]
    row = ca.SX.sym("row", sum(sizes))
    parts = ca.vertsplit(row, [0] + list(itertools.accumulate(sizes)))
    return ca.Function(step.name() + "_packed", [Z, Q, row], [step(Z, Q, *parts)],
                       ["Z", "Q", "row"], ["Z_next"])

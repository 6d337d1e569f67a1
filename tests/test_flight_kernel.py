"""The single-flight kernel (quadcog.codegen.flight_kernel) against CasADi's own code of the same
step: bit for bit without reciprocals, FMA or inline sines, within an ulp per division
with them, also while the slow inputs (CoG ramp, payloads) change every step; the stop at the
first diverged sample; and the controller designs kept per process never stand in for another
design."""
import dataclasses
import shutil

import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.codegen.flight_kernel import FlightKernel, emit_flight_c
from quadcog.errors import KernelError
from quadcog.sim import flight as qf
from quadcog.sim.closed_loop import SLOW_INPUTS, closed_loop_step
from quadcog.sim.prepare import prepare_flight
from quadcog.sim.schedule import STEP_INPUTS

pytestmark = pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
NAMES = [name for name, _ in STEP_INPUTS]
SLOW = [2 + NAMES.index(name) for name in SLOW_INPUTS]


def _setup(cog, duration=1.5, x0=None, limits=None):
    return prepare_flight(quadcog.AdaptiveFeedbackLinearization(), "hover", duration, None,
                          None, None, cog, (), None, x0, "compiled", limits, None, True)


def _fly(kernel, setup):
    """X, U, codes and the stop of a flight through ``kernel``."""
    s, n = setup.schedule, setup.schedule.n_steps
    X, U, codes = np.empty((n + 1, setup.X0.size)), np.empty((n, 4)), np.empty(n)
    X[0] = setup.X0
    stop = kernel.bind(X, [np.ascontiguousarray(setup.P)] + [getattr(s, k) for k in NAMES],
                       [U, np.empty(n), codes])(0, n)
    return X, U, codes, stop


def _casadi(setup):
    """The same flight step by step through CasADi's virtual machine: the oracle."""
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    s, n = setup.schedule, setup.schedule.n_steps
    X = np.empty((n + 1, setup.X0.size))
    X[0] = setup.X0
    for k in range(n):
        out = step(X[k], setup.P, *[getattr(s, name)[k] for name in NAMES])
        X[k + 1] = np.array(out[0]).ravel()
        if float(out[3]):
            return X[:k + 1], k
    return X, n


# a CoG that moves in every step (a ramp over the whole flight) and a payload that is
# attached and moved: the slow block runs again at every step where they change
RAMP = [(0.0, (0.04, -0.03, 0.0), 1.5)]


@pytest.mark.parametrize("cog", [[(0.5, (0.06, 0.06, 0.0))], RAMP], ids=["step", "ramp"])
def test_exact_kernel_is_casadis_step_bit_for_bit(cog, monkeypatch):
    setup = _setup(cog)
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    real_emit = emit_flight_c
    monkeypatch.setattr("quadcog.codegen.flight_kernel.emit_flight_c",
                        lambda *a, **k: real_emit(*a, **{**k, "reciprocals": False,
                                                        "trig": "libm", "fma": False}))
    exact = FlightKernel(step, constant=(1,), slow=SLOW)
    X, _, _, stop = _fly(exact, setup)
    oracle, n = _casadi(setup)
    assert stop == n == setup.schedule.n_steps
    assert X.tobytes() == oracle.tobytes()


def test_reciprocals_change_only_the_last_bits_and_so_does_simulate():
    setup = _setup(RAMP)
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    X, _, _, _ = _fly(FlightKernel(step, constant=(1,), slow=SLOW), setup)
    oracle, _ = _casadi(setup)
    assert np.abs(X - oracle).max() < 1e-12
    chunks, _, _, _ = qf._run_chunks(setup, None)    # CasADi's compiled mapaccum
    assert np.abs(qf._run_compiled(setup, None)[0] - chunks).max() < 1e-12


def test_slow_inputs_that_change_rerun_their_instructions():
    """A kernel whose slow block were kept from the first step would fly the CoG of t = 0;
    the CoG ramp makes the two flights differ by far more than rounding."""
    setup = _setup(RAMP)
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    X, _, _, _ = _fly(FlightKernel(step, constant=(1,), slow=SLOW), setup)
    frozen = _setup([(0.0, (0.0, 0.0, 0.0), 0.0)])
    Y, _, _, _ = _fly(FlightKernel(step, constant=(1,), slow=SLOW), frozen)
    oracle, _ = _casadi(setup)
    assert np.abs(Y - oracle).max() > 1e-3 > 1e-12 > np.abs(X - oracle).max()


def test_the_kernel_stops_at_the_first_diverged_sample_with_its_code():
    x0 = np.zeros(12)
    x0[2] = 1.0
    x0[9] = 40.0                       # a violent roll rate: past 0.3 rad of tilt soon
    setup = _setup([], duration=2.0, x0=x0, limits=quadcog.Limits(max_tilt=0.3))
    oracle, k = _casadi(setup)
    assert k < setup.schedule.n_steps
    X, U, e, code = qf._run_compiled(setup, None)
    assert X.shape[0] == e.shape[0] == k + 1
    with np.errstate(invalid="ignore"):
        assert np.nanmax(np.abs(X[:k] - oracle[:k])) < 1e-9
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    assert code == int(float(step(X[k], setup.P, *[getattr(setup.schedule, n)[k]
                                                   for n in NAMES])[3]))


def test_the_kernel_refuses_a_step_of_another_form_and_wrong_arrays():
    x = ca.SX.sym("x", 2)
    with pytest.raises(KernelError, match="X_next"):
        emit_flight_c(ca.Function("f", [x], [x[0]]))
    setup = _setup([])
    step = closed_loop_step(setup.controller, setup.actuation, setup.limits)
    kernel = FlightKernel(step, constant=(1,), slow=SLOW)
    with pytest.raises(KernelError, match="input 1"):
        kernel.bind(np.zeros((3, setup.X0.size)), [np.zeros(3)] + [np.zeros((2, 14))] * 8,
                    [np.zeros((2, 4)), np.zeros(2), np.zeros(2)])


def test_designs_kept_per_process_are_never_another_designs():
    a = quadcog.AdaptiveFeedbackLinearization(gamma=0.01)
    b = quadcog.AdaptiveFeedbackLinearization(gamma=0.02)
    again = quadcog.AdaptiveFeedbackLinearization(gamma=0.01)
    assert again.function() is a.function()          # kept: not built again
    assert b.function() is not a.function()
    assert b.cache_key() != a.cache_key()
    heavier = a.for_vehicle(dataclasses.replace(quadcog.HUMMINGBIRD, m=0.6))
    assert heavier.function() is not a.function() and heavier.cache_key() != a.cache_key()

    class Mine(quadcog.AdaptiveFeedbackLinearization):   # outside quadcog.controllers
        pass
    assert Mine(gamma=0.01).function() is not a.function()

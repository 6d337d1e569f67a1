"""Hostile input to the simulation's Python surface (fifth pass, issue 33): a batch whose CoG
shape takes a flight where no rigid body is, user callbacks that raise, a central-difference
step that overflows, sensing accuracies beyond any sensor. Each case answered with a number,
a raw traceback or a message naming something else before."""
import re

import numpy as np
import pytest

import quadcog
from quadcog import AdaptiveFeedbackLinearization, simulate, simulate_batch
from quadcog.errors import InputError, ParameterError
from quadcog.model.parameters import check_parameters, inertia_ratio
from quadcog.sim.sensing import SENSING_LIMITS, Sensing
from quadcog.trajectories.analytic import DIFFERENCE_STEP, FromCallable


@pytest.fixture(scope="module")
def law():
    return AdaptiveFeedbackLinearization()


VEHICLES = [quadcog.HUMMINGBIRD.with_cog([0.01, 0.02, 0.0]),
            quadcog.HUMMINGBIRD.with_cog([0.02, -0.01, 0.0])]


@pytest.mark.parametrize("shape, said", [
    (lambda t: -20.0, r"vehicles\[0\] at t = 0.0 s \(cog_shape -20.0 x its r_G\).*not positive "
                      r"definite"),
    (lambda t: 1e300, r"cog_shape 1e\+300 x its r_G.*overflows"),
    # admissible at both ends of the run, not at one instant between: the extremes of the
    # shape are checked, not its first and last samples
    (lambda t: 25.0 if 0.5 <= t < 0.6 else 1.0, r"at t = 0.5 s \(cog_shape 25.0"),
])
def test_a_batch_refuses_a_cog_shape_that_leaves_every_rigid_body(law, shape, said):
    with pytest.raises(ParameterError, match=said):
        simulate_batch(law, VEHICLES, "hover", duration=1.0, cog_shape=shape, threads=1)


def test_a_batch_names_the_first_flight_whose_cog_is_not_admissible(law):
    far = quadcog.HUMMINGBIRD.with_cog([0.05, 0.0, 0.0])
    # 0.05 m is admissible; three times it is not for this airframe (vehicles[0]: it is)
    assert inertia_ratio(far.parameters()) > 0.01
    with pytest.raises(ParameterError, match=r"^vehicles\[1\] at t = "):
        simulate_batch(law, [VEHICLES[0], far], "hover", duration=0.5,
                       cog_shape=lambda t: 3.0, threads=1)


def test_a_batch_within_the_admissible_cogs_flies(law):
    r = simulate_batch(law, VEHICLES, "hover", duration=0.5,
                       cog_shape=lambda t: float(t >= 0.2), threads=1)
    assert not r.diverged.any()


def _boom(*args):
    raise RuntimeError("boom")


def test_a_cog_shape_that_raises_is_named(law):
    with pytest.raises(InputError, match=r"^cog_shape\(0.0\) raised RuntimeError: boom") as e:
        simulate_batch(law, VEHICLES, "hover", duration=0.5, cog_shape=_boom, threads=1)
    assert isinstance(e.value.__cause__, RuntimeError)


@pytest.mark.parametrize("run", [
    lambda law: simulate(law, duration=0.5, progress=_boom),
    lambda law: simulate(law, duration=0.5, progress=_boom, path="python"),
    lambda law: simulate_batch(law, VEHICLES, "hover", duration=0.5, progress=_boom, threads=1),
])
def test_a_progress_callback_that_raises_is_named(law, run):
    with pytest.raises(InputError, match=r"^progress\([\d.]+\) raised RuntimeError: boom"):
        run(law)


def test_a_keyboard_interrupt_in_a_callback_is_not_turned_into_an_input_error(law):
    def stop(fraction):
        raise KeyboardInterrupt
    with pytest.raises(KeyboardInterrupt):
        simulate(law, duration=0.5, progress=stop)


@pytest.mark.parametrize("h", [0.0, -1e-3, 1e300, float("nan"), float("inf"), True, "1e-3",
                               DIFFERENCE_STEP[0] / 2, DIFFERENCE_STEP[1] * 2])
def test_from_callable_refuses_a_difference_step_outside_its_range(h):
    with pytest.raises(InputError, match=r"^FromCallable: h: expected a number in "):
        FromCallable(lambda t: [0.0, 0.0, t], h=h)


def test_from_callable_takes_its_range_and_refuses_what_is_not_a_function():
    for h in DIFFERENCE_STEP:
        row = FromCallable(lambda t: [t, 0.0, 0.0], h=h).sample([1.0])[0]
        assert abs(row[3] - 1.0) < 1e-6          # the velocity of x = t
    with pytest.raises(InputError, match=r"^FromCallable: f: expected a function of time"):
        FromCallable(5)


@pytest.mark.parametrize("field", sorted(SENSING_LIMITS))
def test_sensing_refuses_accuracies_beyond_any_sensor(field):
    hi, unit = SENSING_LIMITS[field]
    Sensing(**{field: hi})                       # the limit itself is taken
    for bad in (hi * 1.01, 1e300, -1e-9, float("nan"), True, "0.1", 1j):
        with pytest.raises(InputError, match=rf"^Sensing\.{field}: expected a number in "
                                             rf".*\({re.escape(unit)}\)"):
            Sensing(**{field: bad})


def test_inertia_ratio_of_a_stack_is_each_vectors():
    rng = np.random.default_rng(5)
    P = np.tile(quadcog.HUMMINGBIRD.parameters(), (50, 1))
    P[:, 11:14] = rng.uniform(-0.2, 0.2, (50, 3))
    P[3, 11] = 1e300                             # overflows: NaN, as for one vector
    stack = inertia_ratio(P)
    one = np.array([inertia_ratio(p) for p in P])
    assert np.isnan(stack[3]) and np.isnan(one[3])
    np.testing.assert_array_equal(np.delete(stack, 3), np.delete(one, 3))


def test_an_overflowing_cog_is_said_to_overflow_not_to_keep_nan():
    p = quadcog.HUMMINGBIRD.parameters().copy()
    p[11] = 1e298
    with pytest.raises(ParameterError, match="overflows the float range") as e:
        check_parameters(p)
    assert "nan" not in str(e.value)


@pytest.mark.parametrize("value", [np.timedelta64(5, "s"), np.datetime64("2026-12-06")])
def test_numpy_times_are_no_numbers(value):
    from quadcog import validate
    with pytest.raises(InputError, match=r"^duration: expected "):
        validate.real(value, "duration")
    with pytest.raises(InputError, match=r"^x0\[1\]: expected a real number"):
        validate.array([0.0, value, 1.0], "x0", (3,))


def test_a_masked_array_with_masked_entries_is_refused_not_unmasked():
    from quadcog import validate
    masked = np.ma.array([1.0, 2.0, 3.0], mask=[False, True, False])
    with pytest.raises(InputError, match=r"^r_G: expected .* got a masked array with 1 masked"):
        validate.array(masked, "r_G", (3,))
    np.testing.assert_array_equal(validate.array(np.ma.array([1.0, 2.0, 3.0]), "r_G", (3,)),
                                  [1.0, 2.0, 3.0])

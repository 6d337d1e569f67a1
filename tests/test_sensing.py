"""Realistic sensing: noise statistics, the gyroscope bias, the one-period delay, scenarios."""
import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.scenarios.scenario import load_scenario
from quadcog.sim.sensing import Sensed, Sensing, gaussian


def test_noise_is_standard_normal_and_seeded():
    t = ca.SX.sym("t")
    f = ca.Function("g", [t], [gaussian(t, 3, 1), gaussian(t, 4, 1), gaussian(t, 3, 2)])
    times = np.arange(20000) * 1e-3
    a, b, c = (np.array(v).ravel() for v in f.map(len(times))(times))
    for v in (a, b, c):
        assert abs(v.mean()) < 0.03 and abs(v.std() - 1.0) < 0.03
        assert abs(np.mean(v ** 4) / v.var() ** 2 - 3.0) < 0.2       # Gaussian kurtosis
    assert abs(np.corrcoef(a, b)[0, 1]) < 0.03 and abs(np.corrcoef(a, c)[0, 1]) < 0.03
    assert abs(np.corrcoef(a[:-1], a[1:])[0, 1]) < 0.03               # white


def test_measured_state_has_the_datasheet_spread_and_bias():
    dt = 1e-3
    ctl = Sensed(quadcog.FeedbackLinearization(), Sensing(seed=5), dt)
    t, x = ca.SX.sym("t"), ca.SX.sym("x", 12)
    meas = ca.Function("m", [t, x], [ctl.measured(t, x)]).map(5000)
    y = np.array(meas(np.arange(5000) * dt, np.zeros((12, 5000)))).T
    gyro = 0.005 * np.pi / 180 * np.sqrt(1 / (2 * dt))       # MPU-6000 density, 1 kHz
    expected = np.repeat([0.001, 0.2 * np.pi / 180, 0.01, gyro], 3)
    assert np.allclose(y.std(axis=0), expected, rtol=0.06)
    bias = np.random.default_rng(5).normal(scale=0.1 * np.pi / 180, size=3)
    assert np.allclose(y[:, 9:].mean(axis=0), bias, atol=4 * gyro / np.sqrt(5000))


def test_delay_applies_the_previous_input():
    inner = quadcog.FeedbackLinearization()
    ctl = Sensed(inner, Sensing(noise=False, delay=True), 1e-3)
    x0, x1 = np.zeros(12), np.r_[0.1, -0.2, 0.9, np.zeros(9)]
    ref = np.zeros(14)
    ref[2] = 1.0
    c = ctl.initial_state()
    U0, c_dot = ctl(0.0, x0, ref, c)
    assert np.allclose(U0, ctl.vehicle.hover_input())            # nothing computed yet
    c = c + 1e-3 * c_dot
    U1, _ = ctl(1e-3, x1, ref, c)
    assert np.allclose(U1, inner(0.0, x0, ref)[0])               # the input of step 0


def test_bad_sensing_values_are_refused():
    with pytest.raises(quadcog.InputError, match="Sensing.position"):
        Sensing(position=-1.0)
    with pytest.raises(quadcog.InputError, match="Sensing.seed"):
        Sensing(seed=1.5)


def test_real_scenarios_load_with_everything_on():
    for name in ("fig6-real", "fig7-real", "fig8-real"):
        sc = load_scenario(name)
        assert sc.truth.parallel_axis and sc.truth.rotor_saturation and sc.truth.motor_lag
        assert sc.sensing.noise and sc.sensing.delay
        assert isinstance(sc.make_controller(), Sensed)

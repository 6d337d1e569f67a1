"""Guard of the noise the Crazyflie loop adds to what the firmware is told
(quadcog.crazyflie.loop.sensing_noise): its columns are the firmware's order, position, world
velocity, Euler angles, body rates (loop.c's), not the state's, so each column's sample
standard deviation must be the Sensing field of its quantity, the rates' the gyro density
over sqrt(2 dt) at the 1 kHz tick. No firmware is needed.
(bench/mutations.py: crazyflie_noise_columns_unordered.)"""
import math

import numpy as np

from quadcog.crazyflie.loop import DT, sensing_noise
from quadcog.sim.sensing import Sensing


def test_noise_columns_are_position_velocity_angles_rates():
    s = Sensing(seed=5, position=0.01, velocity=0.3, attitude=0.1, gyro_density=0.0005,
                gyro_bias=0.0)
    rows = sensing_noise(s, 40_000)
    gyro = 0.0005 * math.sqrt(1.0 / (2.0 * DT))         # 0.0158 rad/s per 1 ms sample
    assert DT == 0.001
    expected = np.repeat([0.01, 0.3, 0.1, gyro], 3)
    np.testing.assert_allclose(rows.std(axis=0), expected, rtol=0.03)
    np.testing.assert_allclose(rows.mean(axis=0), 0.0, atol=0.03 * expected.max())
    assert sensing_noise(Sensing(noise=False), 10) is None

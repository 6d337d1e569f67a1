"""PX4 in the loop, lean: the FLU/z-up <-> FRD/NED conversion and the sensor readings PX4
gets, against textbook values (an accelerometer at rest reads -g on FRD z; a nose-up pitch
reads +g sin(pitch) on x; a yaw rate to the left is negative about FRD z; a heading west sees
the north field on its right), the ISA barometer, the GPS offsets, and agreement with the
ULog reader's convention (the ULog PX4 writes must read back in the frame the plant flew)."""
import math

import numpy as np
import pytest

from quadcog.logs.ulog import euler_to_quaternion, px4_to_quadcog_quaternion, quaternion_to_euler
from quadcog.model.conventions import rotation_matrix
from quadcog.px4.compare import Comparison
from quadcog.px4.frames import flip, flip_rotation
from quadcog.px4.sensors import EARTH_RADIUS, HOME, Px4Sensing, Sensors, isa_pressure
from quadcog.sim.sensing import Sensing

G = 9.81
QUIET = Px4Sensing(Sensing(noise=False), mag=0.0, baro=0.0, gps_position=0.0, gps_velocity=0.0)
FIELD_NED = np.array([0.21, 0.013, 0.43])          # gauss, about Zurich's


def sensors():
    return Sensors(FIELD_NED, G, 250.0, QUIET)


def test_flip_is_the_half_turn_about_x_and_its_own_inverse():
    assert flip([1.0, 2.0, 3.0]).tolist() == [1.0, -2.0, -3.0]
    v = np.array([[0.3, -1.2, 2.5], [1.0, 0.0, -4.0]])
    assert np.array_equal(flip(flip(v)), v)


@pytest.mark.parametrize("phi,theta,psi", [(0.1, -0.2, 0.3), (-0.5, 0.4, 2.9), (0.0, 0.0, -1.0)])
def test_rotation_in_px4_frames_has_angles_phi_minus_theta_minus_psi(phi, theta, psi):
    # PX4's own ZYX rotation with (roll, pitch, yaw) = (phi, -theta, -psi), written out
    c, s = math.cos, math.sin
    r, p, y = phi, -theta, -psi
    Rz = np.array([[c(y), -s(y), 0], [s(y), c(y), 0], [0, 0, 1]])
    Ry = np.array([[c(p), 0, s(p)], [0, 1, 0], [-s(p), 0, c(p)]])
    Rx = np.array([[1, 0, 0], [0, c(r), -s(r)], [0, s(r), c(r)]])
    assert np.allclose(flip_rotation(rotation_matrix(phi, theta, psi)), Rz @ Ry @ Rx,
                       atol=1e-14)
    # and the ULog reader maps PX4's quaternion of those angles back to (phi, theta, psi)
    q_px4 = euler_to_quaternion(r, p, y)
    back = quaternion_to_euler(px4_to_quadcog_quaternion(q_px4))
    assert np.allclose(back, (phi, theta, psi), atol=1e-12)


def test_accelerometer_at_rest_reads_minus_g_on_frd_z():
    acc, gyro, mag, *_ = sensors().imu(np.eye(3), np.zeros(3), np.zeros(3), 0.0)
    assert np.allclose(acc, (0.0, 0.0, -G), atol=1e-6)
    assert np.allclose(gyro, 0.0)
    assert np.allclose(mag, FIELD_NED, atol=1e-7)     # level, heading north: body = NED


def test_nose_up_pitch_reads_plus_g_sin_pitch_on_x():
    pitch_px4 = math.radians(10.0)                   # nose up in PX4 = theta < 0 in quadcog
    R = rotation_matrix(0.0, -pitch_px4, 0.0)
    acc, *_ = sensors().imu(R, np.zeros(3), np.zeros(3), 0.0)
    assert acc[0] == pytest.approx(G * math.sin(pitch_px4), abs=1e-6)
    assert acc[2] == pytest.approx(-G * math.cos(pitch_px4), abs=1e-6)


def test_right_roll_reads_minus_g_sin_roll_on_y():
    roll = math.radians(15.0)                        # right wing down: phi > 0 in both
    acc, *_ = sensors().imu(rotation_matrix(roll, 0.0, 0.0), np.zeros(3), np.zeros(3), 0.0)
    assert acc[1] == pytest.approx(-G * math.sin(roll), abs=1e-6)


def test_climbing_adds_to_the_specific_force():
    acc, *_ = sensors().imu(np.eye(3), np.zeros(3), np.array([0.0, 0.0, 2.0]), 0.0)
    assert acc[2] == pytest.approx(-(G + 2.0), abs=1e-6)


def test_rates_in_frd():
    _, gyro, *_ = sensors().imu(np.eye(3), np.array([0.1, 0.2, 0.3]), np.zeros(3), 0.0)
    # roll rate about forward is the same; pitch about left is minus pitch about right
    assert np.allclose(gyro, (0.1, -0.2, -0.3), atol=1e-7)


def test_heading_west_sees_north_on_its_right():
    R = rotation_matrix(0.0, 0.0, math.pi / 2)       # quadcog psi = +90 deg: nose to +y = west
    _, _, mag, *_ = sensors().imu(R, np.zeros(3), np.zeros(3), 0.0)
    north, east, down = FIELD_NED
    # body x (west) sees -east, body y (right of west: north) sees north, z down sees down
    assert np.allclose(mag, (-east, north, down), atol=1e-7)


def test_isa_barometer_textbook_values():
    assert isa_pressure(0.0)[0] == pytest.approx(1013.25)
    assert isa_pressure(1000.0)[0] == pytest.approx(898.76, abs=0.05)     # ISA table
    assert isa_pressure(1000.0)[1] == pytest.approx(8.5)
    *_, pressure, alt, _ = sensors().imu(np.eye(3), np.zeros(3), np.zeros(3), 12.0)
    assert alt == pytest.approx(HOME[2] + 12.0, abs=1e-6)


def test_gps_offsets_north_and_west():
    lat, lon, alt, vn, ve, vd, cog = sensors().gps([100.0, 10.0, 5.0], [1.0, -2.0, 0.5])
    assert lat == round((HOME[0] + math.degrees(100.0 / EARTH_RADIUS)) * 1e7)
    west = math.degrees(10.0 / (EARTH_RADIUS * math.cos(math.radians(HOME[0]))))
    assert lon == round((HOME[1] - west) * 1e7)        # +y is west: longitude decreases
    assert alt == round((HOME[2] + 5.0) * 1000)
    assert (vn, ve, vd) == (100, 200, -50)            # 2 m/s east = -2 m/s along +y (west)
    assert cog == round(math.degrees(math.atan2(200, 100)) * 100)


def test_noise_is_there_and_seeded():
    a = Sensors(FIELD_NED, G, 250.0, Px4Sensing(Sensing(seed=3)))
    b = Sensors(FIELD_NED, G, 250.0, Px4Sensing(Sensing(seed=3)))
    ra = [a.imu(np.eye(3), np.zeros(3), np.zeros(3), 0.0) for _ in range(200)]
    rb = [b.imu(np.eye(3), np.zeros(3), np.zeros(3), 0.0) for _ in range(200)]
    assert ra == rb
    baro = np.array([r[3] for r in ra])
    assert 0.005 < baro.std() < 0.02                  # the 0.01 hPa PX4 needs to see change


def test_side_by_side_figures_of_a_known_error():
    """compare() on a made-up flight: the error is 0.2 m at the event, decays as
    0.2 exp(-t) (below 5 cm after ln 4 = 1.39 s), one rotor at its limit for 0.5 s."""
    from quadcog.px4.compare import compare
    from quadcog.sim.result import SimulationResult, flight_metrics
    from quadcog.vehicles.vehicle import X500
    t = np.arange(0.0, 20.0, 0.01)
    x = np.zeros((t.size, 12))
    after = t >= 5.0
    x[after, 0] = 0.2 * np.exp(-(t[after] - 5.0))
    ref = np.zeros((t.size, 14))
    f = np.full((t.size, 4), 5.0)
    f[(t >= 5.0) & (t < 5.5), 2] = X500.max_rotor_thrust
    e = np.abs(x[:, 0])
    result = SimulationResult(t, x, np.zeros((t.size, 4)), ref, np.zeros((t.size, 3)),
                              np.zeros((t.size, 3)), flight_metrics(e, t > 15),
                              rotor_thrust=f)
    c = compare("made up", result, X500, 5.0, 15.0)
    assert not c.diverged
    assert c.largest == pytest.approx(0.2)
    assert c.settling == pytest.approx(math.log(4.0), abs=0.011)
    assert c.at_limit == pytest.approx(0.5, abs=0.011)
    assert c.tail_rms < 1e-3
    # PX4's time counts from its arming: the same flight shifted by 3 s, offset 3 s
    shifted = SimulationResult(t + 3.0, x, result.U, ref, result.r_hat, result.r_G,
                               result.metrics, rotor_thrust=f)
    s = compare("shifted", shifted, X500, 5.0, 15.0, offset=3.0)
    assert isinstance(s, Comparison) and s.diverged == c.diverged
    assert (s.tail_rms, s.largest, s.settling, s.at_limit) == pytest.approx(
        (c.tail_rms, c.largest, c.settling, c.at_limit), abs=1e-9)
    # an error that is still 0.2 m at the span's end never settles (None, not nan), and a
    # reference given per sample replaces the result's: here the error itself, error 0
    from quadcog.px4.compare import settling_text
    held = SimulationResult(t, np.where(after[:, None], 0.2, 0.0) * np.eye(12)[0], result.U,
                            ref, result.r_hat, result.r_G, result.metrics, rotor_thrust=f)
    never = compare("held off", held, X500, 5.0, 15.0)
    assert never.settling is None and settling_text(never.settling) == "never settles"
    assert never.largest == pytest.approx(0.2) and settling_text(1.234) == "1.23"
    on_ref = compare("own ref", held, X500, 5.0, 15.0, reference=held.x[:, :3])
    assert on_ref.largest == 0.0 and on_ref.settling == 0.0
    gaps = held.x[:, :3].copy()
    gaps[after & (t < 6.0)] = np.nan                   # PX4 set no position: left out
    assert compare("gaps", held, X500, 5.0, 15.0, reference=gaps).largest == 0.0


def _at_rest(sensing, n):
    s = Sensors(FIELD_NED, G, 250.0, Px4Sensing(sensing))
    rows = [s.imu(np.eye(3), np.zeros(3), np.zeros(3), 0.0) for _ in range(n)]
    return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])


def test_imu_at_rest_has_the_sensing_models_noise_and_bias():
    """The IMU PX4 reads is quadcog's Sensing model: at rest, over 20000 samples at 250 Hz, the
    gyroscope's std is the MPU-6000 density 0.005 deg/s/sqrt(Hz) x sqrt(250 / 2) (white noise
    of one-sided density d up to Nyquist), 0.0559 deg/s; the accelerometer's 400 ug/sqrt(Hz) x
    sqrt(125), 0.0439 m/s^2; their means are the seed's constant biases (numpy's normal of
    seed, scale 0.1 deg/s; of (seed, 1), scale 0.02 m/s^2), turned to FRD (y, z negated)."""
    n, seed = 20000, 7
    acc, gyro = _at_rest(Sensing(seed=seed), n)
    gyro_std = 0.005 * math.pi / 180.0 * math.sqrt(250.0 / 2.0)
    accel_std = 400e-6 * 9.80665 * math.sqrt(250.0 / 2.0)
    assert gyro_std == pytest.approx(9.76e-4, rel=1e-3)
    assert np.allclose(gyro.std(axis=0), gyro_std, rtol=0.03)     # 1/sqrt(2n) = 0.5 %
    assert np.allclose(acc.std(axis=0), accel_std, rtol=0.03)
    frd = np.array([1.0, -1.0, -1.0])
    gyro_bias = np.random.default_rng(seed).normal(scale=0.1 * math.pi / 180.0, size=3) * frd
    accel_bias = np.random.default_rng((seed, 1)).normal(scale=0.02, size=3) * frd
    assert np.abs(gyro_bias).max() > 5 * gyro_std / math.sqrt(n)   # a bias the test can see
    assert np.allclose(gyro.mean(axis=0), gyro_bias, atol=4 * gyro_std / math.sqrt(n))
    assert np.allclose(acc.mean(axis=0) - (0.0, 0.0, -G), accel_bias,
                       atol=4 * accel_std / math.sqrt(n))


def test_imu_follows_the_scenarios_sensing_table():
    """A [sensing] table's densities and biases reach the IMU (10x the gyro density: 10x the
    std; no noise: the truth, no bias); the magnetometer and barometer keep their noise."""
    acc, gyro = _at_rest(Sensing(seed=2, gyro_density=0.05 * math.pi / 180.0, gyro_bias=0.0,
                                 accel_bias=0.0), 5000)
    assert np.allclose(gyro.std(axis=0), 0.05 * math.pi / 180 * math.sqrt(125.0), rtol=0.05)
    quiet = Sensors(FIELD_NED, G, 250.0, Px4Sensing(Sensing(noise=False)))
    rows = [quiet.imu(np.eye(3), np.zeros(3), np.zeros(3), 0.0) for _ in range(200)]
    assert all(r[0] == (0.0, 0.0, -G) and r[1] == (0.0, 0.0, 0.0) for r in rows)
    assert np.std([r[3] for r in rows]) > 0.005                   # PX4's barometer: not stale


def test_px4_sensing_refuses_a_bad_imu_or_noise():
    from quadcog.errors import Px4Error
    with pytest.raises(Px4Error, match="Px4Sensing.imu"):
        Px4Sensing(imu=3)
    with pytest.raises(Px4Error, match="Px4Sensing.baro"):
        Px4Sensing(baro=-1.0)

"""CoG and mass identification (issue 19): rotor models against their sources, the hover
balance against the textbook moment balance, and the round trip simulate -> log (every format)
-> identify with the known CoG."""
import dataclasses

import numpy as np
import pytest

import quadcog
from quadcog import CRAZYFLIE, HUMMINGBIRD, Sensed, Sensing, make_controller, simulate
from quadcog.errors import IdentificationError, InputError
from quadcog.identification import JSON_KEYS, identify
from quadcog.identification.segments import hover_window, rotor_thrusts
from quadcog.identification.simulated import simulated_log
from quadcog.logs import LOG_FORMATS, FlightLog, read_log, write_log
from quadcog.vehicles.rotor_model import (
    CRAZYFLIE_BITCRAZE_VOLTAGE,
    CRAZYFLIE_FIRMWARE_COMMAND,
    CRAZYFLIE_FOERSTER,
    ROTOR_MODELS,
    RotorModel,
    px4_thrust_curve,
)

G0 = 9.80665e-3          # N per gram-force

# Bitcraze's 2015 thrust stand (wiki "PWM to Thrust"): PWM (%), supply voltage (V), thrust of
# the whole Crazyflie 2.X (g); the firmware's map is a quadratic fit of these rows
BITCRAZE_TABLE = [(6.25, 3.98, 1.6), (12.5, 3.95, 4.8), (18.75, 3.92, 7.9), (25, 3.88, 10.9),
                  (31.25, 3.84, 13.9), (37.5, 3.80, 17.3), (43.25, 3.76, 21.0),
                  (50, 3.71, 24.4), (56.25, 3.67, 28.6), (62.5, 3.65, 32.8),
                  (68.75, 3.62, 37.3), (75, 3.56, 41.7), (81.25, 3.48, 46.0),
                  (87.5, 3.40, 51.9), (93.75, 3.30, 57.9)]


@pytest.mark.parametrize("pwm, volts, grams", BITCRAZE_TABLE)
def test_bitcraze_voltage_map_reproduces_the_thrust_stand(pwm, volts, grams):
    f = CRAZYFLIE_BITCRAZE_VOLTAGE.thrust(np.full((1, 4), pwm / 100), np.array([volts]))
    # a quarter of the whole vehicle's thrust per rotor; the fit stays within 0.5 g of the
    # table over its range
    assert f[0, 0] == pytest.approx(grams / 4 * G0, abs=0.5 / 4 * G0)


def test_foerster_and_firmware_maps_by_their_formulas():
    c = np.array([[0.0, 20000.0, 40000.0, 65535.0]])
    expected = 2.130295e-11 * c ** 2 + 1.032633e-6 * c + 5.484560e-4
    assert np.allclose(CRAZYFLIE_FOERSTER.thrust(c / 65535), expected, rtol=1e-12)
    # 65536 <==> 60 g for the whole vehicle: 15 g per rotor, linear
    f = CRAZYFLIE_FIRMWARE_COMMAND.thrust(np.array([[0.5, 1.0, 0.25, 0.0]]))
    assert np.allclose(f, np.array([[0.5, 1.0, 0.25, 0.0]]) * 15 * G0 * 65535 / 65536)


def test_px4_thr_mdl_fac_curve():
    model = px4_thrust_curve(max_thrust=8.0, thr_mdl_fac=0.3)
    u = np.array([[0.0, 0.3, 0.6, 1.0]])
    assert np.allclose(model.thrust(u), 8.0 * (0.7 * u + 0.3 * u ** 2))
    assert np.allclose(px4_thrust_curve(8.0, 0.0).thrust(u), 8.0 * u)
    with pytest.raises(InputError, match="THR_MDL_FAC"):
        px4_thrust_curve(8.0, 1.5)


@pytest.mark.parametrize("model", list(ROTOR_MODELS.values())
                         + [px4_thrust_curve(0.2, 0.6)], ids=lambda m: m.name)
def test_command_inverts_thrust(model):
    u = np.random.default_rng(0).uniform(0.15, 0.75, size=(50, 4))   # 2.1+ cubic: 0 N below 0.13
    v = np.linspace(3.5, 4.1, 50)
    assert np.allclose(model.command(model.thrust(u, v), v), u, atol=1e-12)


def test_rotor_model_is_validated_data():
    with pytest.raises(InputError, match="kind"):
        RotorModel(name="x", kind="cubic", signal="motor_pwm", coefficients=(1, 2), source="s")
    with pytest.raises(InputError, match="source"):
        dataclasses.replace(CRAZYFLIE_FOERSTER, source=" ")
    with pytest.raises(InputError, match="needs the battery voltage"):
        CRAZYFLIE_BITCRAZE_VOLTAGE.thrust(np.full((1, 4), 0.5))
    assert CRAZYFLIE.rotor_model is CRAZYFLIE_BITCRAZE_VOLTAGE and HUMMINGBIRD.rotor_model is None
    with pytest.raises(InputError, match="rotor_model"):
        CRAZYFLIE.replace(rotor_model="bitcraze")
    assert CRAZYFLIE.replace(rotor_model="foerster").rotor_model is CRAZYFLIE_FOERSTER
    # vehicle.json (as_dict) names the model; reading it back gives the same vehicle
    d = CRAZYFLIE.as_dict()
    assert d["rotor_model"] == "bitcraze-voltage"
    back = quadcog.Vehicle(**{k: tuple(map(tuple, v)) if k == "rotor_positions" else
                              tuple(v) if isinstance(v, list) else v for k, v in d.items()})
    assert back == CRAZYFLIE


def test_crazyflie_motor_order_follows_the_firmware():
    """The firmware's legacy power distribution (power_distribution_quadrotor.c) written
    here: m1 = T - r + p + y, m2 = T - r - p - y, m3 = T + r - p + y, m4 = T + r + p - y
    (r = roll / 2, p = pitch / 2). Roll raises the left rotors, the Crazyflie's pitch (nose
    up) the front ones, yaw the counter-clockwise M1 and M3."""
    def motors(T, roll, pitch, yaw):
        r, p = roll / 2, pitch / 2
        return np.array([T - r + p + yaw, T - r - p - yaw, T + r - p + yaw, T + r + p - yaw])
    B = CRAZYFLIE.mixer()
    base = motors(30000, 0, 0, 0)
    U_roll = B @ (motors(30000, 2000, 0, 0) - base)
    U_pitch = B @ (motors(30000, 0, 2000, 0) - base)
    U_yaw = B @ (motors(30000, 0, 0, 2000) - base)
    assert U_roll[1] > 0 and abs(U_roll[2]) < 1e-9 * abs(U_roll[1])       # +U2: left side up
    assert U_pitch[2] < 0 and abs(U_pitch[1]) < 1e-9 * abs(U_pitch[2])    # nose up: -U3
    assert U_yaw[3] < 0 and np.allclose(U_yaw[:3], 0)     # M1, M3 counter-clockwise: d = -1
    pos = np.asarray(CRAZYFLIE.rotor_positions)
    # M1 front-right, M2 back-right, M3 back-left, M4 front-left (body x forward, y left)
    assert (np.sign(pos) == [[1, -1], [-1, -1], [-1, 1], [1, 1]]).all()
    # the firmware's force-torque distribution: lever arm 0.707106781 * arm length about each
    # axis, the arm length 0.046 m (CRAZYFLIE_ARM_LENGTH of its power distribution)
    assert np.allclose(np.abs(pos), 0.707106781 * 0.046, rtol=1e-8)


def _log(t, z, f, vehicle=CRAZYFLIE, **signals):
    """A FlightLog with height z, rotor thrusts f written as firmware commands."""
    pos = np.column_stack([np.zeros_like(t), np.zeros_like(t), z])
    u = CRAZYFLIE_FIRMWARE_COMMAND.command(f)
    return FlightLog("synthetic", "csv", t, dict(position=pos, motor_command=u, **signals),
                     {}, {})


def test_hover_window_finds_each_plateau_of_two_hops():
    t = np.arange(0, 30, 0.01)
    z = np.where((t > 3) & (t < 12), 0.5, 0.0) + np.where((t > 17) & (t < 27), 0.5, 0.0)
    f = np.full((len(t), 4), 0.07)
    w = hover_window(_log(t, z, f))
    assert np.allclose(w.segments, [(4.51, 10.49), (18.51, 25.49)], atol=0.011)
    assert w.height == pytest.approx(0.5)
    with pytest.raises(IdentificationError, match="too few hover samples"):
        hover_window(_log(t, np.where((t > 3) & (t < 7), 0.5, 0.0), f))


def test_static_balance_solves_the_moment_balance():
    """Thrusts made from the hover trim of docs/model.md sec. 3.3 with a known r_G, mass and a
    vertical acceleration: U = [m (g + a_z), m g y_G, -m g x_G, 0] through the mixer."""
    m, r = 0.031, np.array([0.0021, -0.0013, 0.0])
    t = np.arange(0, 20, 0.01)
    a_z = 0.3 * np.sin(2 * np.pi * 0.4 * t)
    g = CRAZYFLIE.g
    U = np.column_stack([m * (g + a_z), np.full_like(t, m * g * r[1]),
                         np.full_like(t, -m * g * r[0]), np.zeros_like(t)])
    f = U @ np.linalg.inv(CRAZYFLIE.mixer()).T
    acc = np.column_stack([np.zeros_like(t), np.zeros_like(t), a_z])
    res = identify(_log(t, np.full_like(t, 0.5), f, acceleration=acc), "crazyflie")
    assert res.method.startswith("static")
    assert np.allclose(res.r_G[:2], r[:2], atol=1e-8)
    assert res.mass == pytest.approx(m, rel=1e-6)
    assert res.identifiable == ("x_G", "y_G") and res.r_G_ci95[2] is None
    assert "lacks" in res.method          # auto says why it did not run the regression


def test_missing_signals_are_named():
    t = np.arange(0, 20, 0.01)
    pos = np.column_stack([np.zeros((len(t), 2)), np.full(len(t), 0.5)])
    log = FlightLog("nothing.csv", "csv", t, {"position": pos}, {}, {})
    with pytest.raises(IdentificationError, match="bitcraze-voltage.*motor_pwm.*battery_voltage"):
        identify(log, "crazyflie")
    log = _log(t, np.full_like(t, 0.5), np.full((len(t), 4), 0.07))
    with pytest.raises(IdentificationError, match="regression.*velocity, roll, pitch, yaw, "
                                                  "body_rates"):
        identify(log, "crazyflie", method="regression")
    with pytest.raises(IdentificationError, match="^vehicle: expected a preset name .*, got 'x900'$"):
        identify(log, "x900")
    with pytest.raises(IdentificationError, match="^method: expected one of auto, static, regression, got 'best'$"):
        identify(log, "crazyflie", method="best")
    with pytest.raises(IdentificationError, match="no rotor_model"):
        identify(log, HUMMINGBIRD)


# -- round trip ---------------------------------------------------------------------------
R_TRUE = np.array([0.004, -0.003, 0.002])


@pytest.fixture(scope="module")
def flight():
    """20 s of hover of the Crazyflie with a known CoG, flown by feedback linearization with
    integral action under the sensing of the *-real scenarios (noise, gyro bias, delay)."""
    vehicle = CRAZYFLIE.with_cog(R_TRUE)
    sensing = Sensing(seed=1)
    ctl = Sensed(make_controller("fl_integral", vehicle=CRAZYFLIE), sensing, 0.001)
    result = simulate(ctl, "hover", duration=20.0, dt=0.001, vehicle=vehicle)
    assert not result.diverged
    return result, vehicle, sensing


EXTENSIONS = {"crazyflie-usd": "", "ulog": ".ulg", "csv": ".csv", "parquet": ".parquet"}


@pytest.mark.parametrize("fmt", LOG_FORMATS)
def test_round_trip_recovers_the_known_cog(flight, fmt, tmp_path):
    result, vehicle, sensing = flight
    if fmt == "ulog":
        # a PX4 log carries the normalized motor outputs: a THR_MDL_FAC rotor model
        vehicle = vehicle.replace(rotor_model=px4_thrust_curve(2 * vehicle.max_rotor_thrust,
                                                               0.5))
    log = simulated_log(result, vehicle, sensing=sensing)
    back = read_log(write_log(log, tmp_path / f"flight{EXTENSIONS[fmt]}", fmt))
    model = vehicle.with_cog(np.zeros(3))       # what the user knows: the vehicle, not r_G
    for method in ("static", "regression"):
        res = identify(back, model, method=method)
        err = np.abs(np.array(res.r_G[:2]) - R_TRUE[:2])
        assert (err < 1e-3).all(), (fmt, method, res.r_G)
        assert (err <= np.array(res.r_G_ci95[:2])).all(), (fmt, method, err, res.r_G_ci95)
        assert res.mass == pytest.approx(vehicle.m, rel=2e-3)
        assert set(res.identifiable) == {"x_G", "y_G"}
        assert "z_G not estimated" in res.verdict
        assert list(res.as_json()) == list(JSON_KEYS)


def test_baseline_removes_a_weak_rotor(flight):
    """A rotor 5 % weaker than the model: alone it reads as a CoG shift toward it; against a
    baseline flown with the same rotor and no payload the shift is the payload's."""
    result, vehicle, sensing = flight
    log = simulated_log(result, vehicle, sensing=sensing)
    weak = np.array([1.0, 1.0, 0.95, 1.0])      # M3 gives 5 % less thrust per command
    u = CRAZYFLIE_BITCRAZE_VOLTAGE.command(
        CRAZYFLIE_BITCRAZE_VOLTAGE.thrust(log.signal("motor_pwm"),
                                          log.signal("battery_voltage")) / weak,
        log.signal("battery_voltage"))
    weak_log = dataclasses.replace(log, signals=dict(log.signals, motor_pwm=u))
    alone = identify(weak_log, CRAZYFLIE, method="static")
    pos3 = np.asarray(CRAZYFLIE.rotor_positions[2])
    # f_3 / 0.95 at hover: the apparent moment grows by (1/0.95 - 1) f_3 r_3, f_3 ~ m g / 4
    # (0.43 mm toward M3; the apparent mass grows too, which scales r_G by 1.3 %)
    assert np.allclose(np.array(alone.r_G[:2]) - R_TRUE[:2], (1 / 0.95 - 1) / 4 * pos3,
                       atol=1e-4)
    # the baseline: the same vehicle and weak rotor with its CoG at O
    base_vehicle = CRAZYFLIE
    ctl = Sensed(make_controller("fl_integral", vehicle=CRAZYFLIE), sensing, 0.001)
    base_res = simulate(ctl, "hover", duration=20.0, dt=0.001, vehicle=base_vehicle)
    base = simulated_log(base_res, base_vehicle, sensing=sensing)
    ub = CRAZYFLIE_BITCRAZE_VOLTAGE.command(
        CRAZYFLIE_BITCRAZE_VOLTAGE.thrust(base.signal("motor_pwm"),
                                          base.signal("battery_voltage")) / weak,
        base.signal("battery_voltage"))
    base = dataclasses.replace(base, signals=dict(base.signals, motor_pwm=ub))
    shift = identify(weak_log, CRAZYFLIE, baseline=base, method="static")
    assert np.allclose(shift.r_G[:2], R_TRUE[:2], atol=1e-4)
    # alone the weak rotor adds 1.3 % (0.36 g) to the mass; the baseline leaves what the
    # rotor's share of the thrust changes with the CoG (0.03 % of the thrust here)
    f3 = CRAZYFLIE_BITCRAZE_VOLTAGE.thrust(log.signal("motor_pwm"),
                                           log.signal("battery_voltage"))[:, 2]
    assert alone.mass - vehicle.m == pytest.approx((1 / 0.95 - 1) * f3.mean() / vehicle.g,
                                                   rel=0.05)
    assert shift.mass_change == pytest.approx(0.0, abs=1e-4)
    assert "baseline" in shift.verdict


def test_rotor_thrusts_fall_back_to_the_commands():
    t = np.arange(0, 20, 0.01)
    f = np.full((len(t), 4), 0.07)
    thrust, how, model = rotor_thrusts(_log(t, np.full_like(t, 0.5), f), CRAZYFLIE)
    assert model is CRAZYFLIE_FIRMWARE_COMMAND and "no motor_pwm" in how
    assert np.allclose(thrust, f)


def test_speed_proportional_moment_is_not_taken_for_the_cog():
    """Blocks flown forward at +0.47 m/s and back at -0.47 m/s (as the CrazyPAD flights) with
    a rotor moment proportional to the speed, 2 mm of apparent x_G per m/s, and unequal time
    each way: the mean of the blocks is biased, the zero-speed intercept is not."""
    from quadcog.identification.segments import speed_corrected
    r = np.array([-0.0012, 0.0005, 0.0])
    v = np.r_[np.full(6, 0.47), np.full(3, -0.47)]
    noise = 1e-5 * np.sin(np.arange(9.0))
    blocks_r = np.column_stack([r[0] + 0.002 * v + noise, np.full(9, r[1]) + noise,
                                np.zeros(9)])
    blocks_v = np.column_stack([v, np.zeros(9)])
    est, half, slopes = speed_corrected(blocks_r, blocks_v)
    assert abs(blocks_r[:, 0].mean() - r[0]) > 3e-4          # the plain mean is 0.3 mm off
    assert abs(est[0] - r[0]) < 2e-5 and abs(est[0] - r[0]) < half[0]
    assert slopes[0] == pytest.approx(0.002, rel=0.02) and slopes[1] == 0.0
    assert est[1] == pytest.approx(r[1], abs=1e-5)


@pytest.mark.parametrize("noise", [False, True])
def test_regression_in_a_circle(noise):
    """A 0.6 m circle in 2.5 s (23 deg of tilt), r_G = [4, -3, 3] mm. Without sensor noise
    the filtered regression recovers all of r_G, z_G too (through the force rows' m w_dot x
    r_G): a check of the generated regressor and the filter against the simulation's truth.
    With the *-real noise x_G, y_G stay within 0.03 mm, z_G is pulled toward 0 and is not
    reported determined; the static balance says the flight is not a hover."""
    r = np.array([0.004, -0.003, 0.003])
    vehicle = CRAZYFLIE.with_cog(r)
    sensing = Sensing(seed=1) if noise else Sensing(noise=False, delay=False)
    ctl = Sensed(make_controller("fl_integral", vehicle=CRAZYFLIE), sensing, 0.001)
    result = simulate(ctl, quadcog.Circle(radius=0.6, period=2.5), duration=20.0, dt=0.001,
                      vehicle=vehicle)
    log = simulated_log(result, vehicle, sensing=sensing)
    res = identify(log, CRAZYFLIE)
    assert res.method.startswith("regression")
    assert np.allclose(res.r_G[:2], r[:2], atol=3e-5)
    assert res.identifiable == ("x_G", "y_G") and "z_G estimated" in res.verdict
    if not noise:
        assert res.r_G[2] == pytest.approx(r[2], abs=2e-4)
    else:
        assert abs(res.r_G[2] - r[2]) > 3 * res.r_G_ci95[2]      # biased: errors in variables
    static = identify(log, CRAZYFLIE, method="static")
    assert "not a hover" in static.verdict


def test_px4_rotor_model_reads_thr_mdl_fac_from_the_ulog():
    from pathlib import Path

    from quadcog.vehicles.rotor_model import px4_thrust_curve_from_log
    log = read_log(Path(__file__).parent / "data" / "ulog" / "sample_px4_events.ulg")
    model = px4_thrust_curve_from_log(log, 7.0)
    assert model.coefficients == (float(log.meta["param.THR_MDL_FAC"]),)
    assert model.signal == "motor_command" and log.has("motor_command")
    with pytest.raises(InputError, match="THR_MDL_FAC"):
        px4_thrust_curve_from_log(dataclasses.replace(log, meta={}), 7.0)

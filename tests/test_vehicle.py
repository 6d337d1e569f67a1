"""The Vehicle and the truth model's rotors, against numbers derived here by hand: the mixer of
the "+" and "X" frames (moments as r x F plus the rotor drag moments), its inverse, the thrust
floor and saturation, the first-order motor lag, and what the controller believes."""
from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog import CRAZYFLIE, HUMMINGBIRD, FeedbackLinearization, TruthOptions, Vehicle, simulate
from quadcog.scenarios.scenario import ScenarioError, parse

F = np.array([1.0, 2.0, 3.0, 4.5])         # distinct rotor thrusts (N): every sign shows


def _wrench_by_hand(positions, directions, k, f):
    """[U1, U2, U3, U4] of rotor thrusts f: sum of forces, sum of r_i x (0, 0, f_i) about O,
    plus each rotor's drag moment d_i k f_i about body z."""
    moment = np.zeros(3)
    for (x, y), d, fi in zip(positions, directions, f):
        moment += np.cross([x, y, 0.0], [0.0, 0.0, fi]) + [0.0, 0.0, d * k * fi]
    return np.concatenate([[np.sum(f)], moment])


def test_plus_mixer_by_hand():
    """Hummingbird "+": rotor 1 front (+x), 2 left (+y), 3 back, 4 right; 1 and 3 turn
    clockwise (RotorS), so their drag moment is +k f about z."""
    l, k = 0.17, 0.016
    expected = [1 + 2 + 3 + 4.5,          # thrust
                l * (2 - 4.5),            # roll: the left rotor lifts the +y side
                -l * (1 - 3),             # pitch: the front rotor noses up, a negative moment
                k * (1 - 2 + 3 - 4.5)]    # yaw: clockwise rotors turn the body anticlockwise
    assert_close(HUMMINGBIRD.mixer() @ F, expected, 1e-15, "U of the + frame")
    assert_close(HUMMINGBIRD.mixer() @ F,
                 _wrench_by_hand(HUMMINGBIRD.rotor_positions, HUMMINGBIRD.rotor_directions,
                                 k, F), 1e-15, "U as r x F")


def test_x_mixer_by_hand():
    """Crazyflie "X": rotors at 45 deg, 1 front-right, 2 back-right, 3 back-left, 4 front-left;
    1 and 3 turn counter-clockwise (RotorS crazyflie2)."""
    h, k = 0.046 / np.sqrt(2), 5.964552e-3
    f1, f2, f3, f4 = F
    expected = [f1 + f2 + f3 + f4,
                h * (-f1 - f2 + f3 + f4),     # left rotors (+y) roll positive
                h * (-f1 + f2 + f3 - f4),     # front rotors (+x) pitch negative
                k * (-f1 + f2 - f3 + f4)]
    assert_close(CRAZYFLIE.mixer() @ F, expected, 1e-15, "U of the X frame")
    assert_close(CRAZYFLIE.mixer() @ F,
                 _wrench_by_hand(CRAZYFLIE.rotor_positions, CRAZYFLIE.rotor_directions, k, F),
                 1e-15, "U as r x F")


@pytest.mark.parametrize("vehicle", [HUMMINGBIRD, CRAZYFLIE])
def test_rotor_thrusts_invert_the_mixer(vehicle):
    assert_close(vehicle.rotor_thrusts(vehicle.mixer() @ F), F, 1e-12, "f from U")
    hover = vehicle.rotor_thrusts([vehicle.m * vehicle.g, 0, 0, 0])
    assert_close(hover, np.full(4, vehicle.m * vehicle.g / 4), 1e-12, "hover thrusts")


def test_any_layout_is_data():
    """A 450 mm "X" frame with the directions flipped: the mixer follows the data."""
    frame = HUMMINGBIRD.replace(rotor_positions=quadcog.x_layout(0.225),
                                rotor_directions=(1, -1, 1, -1), name="450")
    assert frame.arm_length == pytest.approx(0.225)
    assert_close(frame.mixer() @ F, _wrench_by_hand(frame.rotor_positions, (1, -1, 1, -1),
                                                    0.016, F), 1e-15, "U")


@pytest.mark.parametrize("changes, message", [
    (dict(m=-1.0), "m = -1.0 must be > 0"),
    (dict(min_rotor_thrust=-0.1), "min_rotor_thrust = -0.1 N must be >= 0"),
    (dict(max_rotor_thrust=0.0), "max_rotor_thrust = 0.0 must be > 0"),
    (dict(min_rotor_thrust=7.0), "must be below max_rotor_thrust"),
    (dict(motor_time_constant=-1.0), "motor_time_constant = -1.0 s must be >= 0"),
    (dict(rotor_directions=(1, 1, 1, 1)), "mixer .* is singular"),
    (dict(rotor_directions=(1, -1, 2, -1)), "each \\+1 or -1"),
    (dict(rotor_positions=((0.1, 0.0),) * 3), "4 pairs"),
    (dict(x_G=0.5), "inertia about the CoG keeps only"),
    (dict(m="heavy"), "m must be a number, got 'heavy'"),
    (dict(mass=1.0), "unknown vehicle field"),
])
def test_bad_vehicle(changes, message):
    with pytest.raises(quadcog.InputError, match=message):
        HUMMINGBIRD.replace(**changes)


def _open_loop(U, duration=0.2, **kw):
    """A flight under a constant commanded input U (a Python controller)."""
    x0 = np.zeros(12)
    x0[2] = 1.0
    return simulate(lambda t, x, ref, c: np.array(U, float), "hover", duration=duration, x0=x0,
                    path="python", check_dt=False, **kw)


def test_rotor_thrust_is_never_negative():
    """U = [1, 0.5, 0, 0] needs f = [0.25, 0.25 + 0.5 / 0.34, 0.25, 0.25 - 0.5 / 0.34]: rotor 4
    would pull; it delivers 0, and the others what was asked."""
    res = _open_loop([1.0, 0.5, 0.0, 0.0], duration=0.01)
    f = [0.25, 0.25 + 0.5 / 0.34, 0.25, 0.0]
    l, k = 0.17, 0.016
    expected = [sum(f), l * (f[1] - f[3]), -l * (f[0] - f[2]), k * (f[0] - f[1] + f[2] - f[3])]
    assert_close(res.U[0], expected, 1e-12, "applied U")


def test_rotor_saturation():
    """Each rotor clipped to [min, max] = [0.5, 2] N: an asked 3 N per rotor gives 8 N."""
    v = HUMMINGBIRD.replace(min_rotor_thrust=0.5, max_rotor_thrust=2.0)
    on = TruthOptions(rotor_saturation=True)
    assert_close(_open_loop([12.0, 0, 0, 0], vehicle=v, truth=on, duration=0.01).U[0],
                 [8.0, 0, 0, 0], 1e-12, "upper limit")
    assert_close(_open_loop([0.4, 0, 0, 0], vehicle=v, truth=on, duration=0.01).U[0],
                 [2.0, 0, 0, 0], 1e-12, "lower limit")
    # without the option only the floor at zero acts
    assert_close(_open_loop([12.0, 0, 0, 0], vehicle=v, duration=0.01).U[0],
                 [12.0, 0, 0, 0], 1e-12, "no saturation")


def test_motor_lag_step_response():
    """First-order lag: each rotor thrust goes f(t) = f_c + (f_0 - f_c) exp(-t / tau) from
    the hover thrust f_0 = m g / 4 to the command f_c (the compiled path agrees with this
    one in test_simulate.test_paths_agree)."""
    tau = 0.02
    v = HUMMINGBIRD.replace(motor_time_constant=tau)
    U = np.array([9.0, 0.1, -0.05, 0.02])
    res = _open_loop(U, vehicle=v, truth=TruthOptions(motor_lag=True), duration=0.1)
    f_c = v.rotor_thrusts(U)
    f_0 = np.full(4, v.m * v.g / 4)
    expected = f_c + (f_0 - f_c) * np.exp(-res.t[:, None] / tau)
    f = np.linalg.solve(v.mixer(), res.U[:-1].T).T
    # RK4 with h / tau = 0.05 is exact to about (h / tau)^5 / 120 = 3e-9 of the jump per step
    assert_close(f, expected[:-1], 5e-8, "rotor thrusts")
    # no lag: the command acts at once
    assert_close(_open_loop(U, vehicle=v, duration=0.01).U[0], U, 1e-12, "instant")


def test_motor_lag_dt_check():
    v = HUMMINGBIRD.replace(motor_time_constant=1e-4)
    with pytest.raises(quadcog.InputError, match="too large for the motor time constant"):
        simulate(FeedbackLinearization(), "hover", duration=0.1, vehicle=v,
                 truth=TruthOptions(motor_lag=True))


def test_controller_model_defaults_to_the_truth_without_cog():
    ctl = FeedbackLinearization()
    heavy = HUMMINGBIRD.replace(m=0.8).with_cog((0.02, 0.0, 0.0))
    res = simulate(ctl, "hover", duration=0.5, vehicle=heavy)
    believed = ctl.for_vehicle(heavy.with_cog((0, 0, 0)))
    assert believed.vehicle.m == 0.8 and believed.vehicle.x_G == 0.0
    assert believed is ctl.for_vehicle(heavy.with_cog((0, 0, 0)))       # designed once
    # a controller that believes the lighter default vehicle holds a standing height error
    wrong = simulate(ctl, "hover", duration=6.0, vehicle=heavy.with_cog((0, 0, 0)),
                     controller_model=HUMMINGBIRD)
    right = simulate(ctl, "hover", duration=6.0, vehicle=heavy.with_cog((0, 0, 0)))
    assert right.metrics.max_position_error < 1e-9
    # the PD part of the z loop against the missing weight (0.12 kg * g) / (kp m) ...
    assert wrong.metrics.final_position_error > 0.05
    assert not res.diverged


def test_scenario_vehicle_and_controller_model():
    data = {"name": "t", "controller": "fl", "duration": 1.0,
            "vehicle": {"preset": "crazyflie", "m": 0.03, "motor_time_constant": 0.01,
                        "rotor_positions": [[0.05, 0], [0, 0.05], [-0.05, 0], [0, -0.05]]},
            "controller_model": {"m": 0.027},
            "truth": {"motor_lag": True, "rotor_saturation": True}}
    s = parse(data, "my.toml")
    assert isinstance(s.vehicle, Vehicle) and s.vehicle.m == 0.03
    assert s.vehicle.rotor_positions[1] == (0.0, 0.05)
    assert s.vehicle.Ixx == CRAZYFLIE.Ixx
    model = s.model_vehicle()
    assert model.m == 0.027 and model.rotor_positions == s.vehicle.rotor_positions
    assert s.make_controller().vehicle == model
    assert s.truth == TruthOptions(motor_lag=True, rotor_saturation=True)
    with pytest.raises(ScenarioError, match="vehicle.preset': expected one of 'hummingbird'"):
        parse(dict(data, vehicle={"preset": "x900"}), "my.toml")
    with pytest.raises(ScenarioError, match="my.toml: key 'vehicle': .*min_rotor_thrust"):
        parse(dict(data, vehicle={"min_rotor_thrust": -1.0}), "my.toml")
    with pytest.raises(ScenarioError, match="rotor_positions': expected an array of 4"):
        parse(dict(data, vehicle={"rotor_positions": [[0.1, 0.0]]}), "my.toml")

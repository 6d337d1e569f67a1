"""Ninth hostile pass: vehicles, payloads, rotor models, vehicle files, trajectories and a run's
timeline (quadcog.vehicles, quadcog.trajectories, quadcog.sim.prepare/schedule/timeline).

Each test names what the old code did with the input: a raw numpy/Python exception, a silent
NaN or inf, an answer from impossible data (a 1e6 kg parcel on a 27 g Crazyflie, a loop flown
in a nanosecond), or a cost that grew faster than the input (a vehicle loaded payload by
payload re-placed every payload it carried: N^2 / 2 placements)."""
from contextlib import contextmanager
from pathlib import Path
import re
import time
import warnings

import numpy as np
import pytest

import quadcog
from quadcog.errors import InputError, ParameterError, VehicleFileError
from quadcog.sim.prepare import (
    as_payload_profile,
    batch_start,
    check_cog_changes,
    check_payload_events,
    check_step_size,
    start_at_reference,
    whole_body,
)
from quadcog.sim.schedule import Schedule, tail_start
from quadcog.sim.timeline import CogChange, CogProfile, PayloadProfile, wrench_table
from quadcog.trajectories import waypoints
from quadcog.trajectories.aerobatic import BankedCircle, Flip, septic_step
from quadcog.trajectories.analytic import FromCallable, Hover
from quadcog.trajectories.feasibility import check_reference, reference_limits
from quadcog.trajectories.registry import make_trajectory
from quadcog.trajectories.template import VerticalSine
from quadcog.trajectories.waypoints import MinimumSnap, allocate_times
from quadcog.vehicles import payload as payload_module
from quadcog.vehicles.payload import Payload
from quadcog.vehicles.rotor_model import RotorModel, cubic_voltage, px4_thrust_curve_from_log
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD, Vehicle, preset_drag

DATA = Path(__file__).parent / "data" / "vehicles"
CF2X = DATA / "gym-pybullet-drones" / "cf2x.urdf"
X500 = DATA / "px4-gazebo-models" / "x500" / "model.sdf"
NUMPY_REPR = re.compile(r"np\.(float|int|str|bool)|array\(")


@contextmanager
def _no_warnings():
    """Any warning (numpy's overflow ones) is an error inside."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


# -- leftover 1: loading a vehicle payload by payload is linear ------------------------------

def test_loading_payloads_one_by_one_places_each_payload_once(monkeypatch):
    """with_payload re-validated the whole vehicle: every payload carried was placed again
    (parallel-axis theorem) at each call, N (N + 1) / 2 placements for N payloads (1,600
    payloads took minutes). Now each is placed once, and the whole body's pi is the sum."""
    calls = []
    real = payload_module.placed
    monkeypatch.setattr(payload_module, "placed",
                        lambda *a: calls.append(1) or real(*a))
    loads = [Payload(1e-5, (0.01 * (k % 3), 0.0, -0.01), (0.01, 0.01, 0.01), f"p{k}")
             for k in range(60)]
    v = HUMMINGBIRD
    for p in loads:
        v = v.with_payload(p)
    assert len(calls) == len(loads)
    # the same whole body as the vehicle made with all of them at once, and as the sum
    at_once = HUMMINGBIRD.replace(payloads=tuple(loads))
    assert v == at_once
    assert np.allclose(v.inertial_parameters(), at_once.inertial_parameters(), rtol=1e-14,
                       atol=0)
    expected = HUMMINGBIRD.inertial_parameters() + sum(p.inertial_parameters() for p in loads)
    assert np.allclose(v.inertial_parameters(), expected, rtol=1e-13, atol=0)
    assert v.without_payload("p0").payloads == tuple(loads[1:])


def test_loading_many_payloads_takes_time_linear_in_their_number():
    """1,000 payloads one by one: under a second or two now (0.2 ms each); the old quadratic
    form took about five minutes."""
    loads = [Payload(1e-6, (0.01, 0.0, 0.0), name=f"p{k}") for k in range(1000)]
    start = time.process_time()
    v = HUMMINGBIRD
    for p in loads:
        v = v.with_payload(p)
    assert time.process_time() - start < 15.0
    assert len(v.payloads) == 1000


def test_a_loaded_vehicle_still_refuses_a_payload_of_a_name_it_carries():
    v = HUMMINGBIRD.with_payload(Payload(0.01, (0, 0, 0), name="a"))
    with pytest.raises(InputError, match="two payloads are named 'a'"):
        v.with_payload(Payload(0.02, (0.01, 0, 0), name="a"))


# -- leftover 2: payloads the rotors cannot lift ---------------------------------------------

@pytest.mark.parametrize("mass", [1e6, 1.0, 0.01])
def test_a_payload_the_rotors_cannot_lift_is_refused(mass):
    """A Crazyflie (27 g, 4 x 0.088 N of thrust: it lifts 35.8 g) took a 1e6 kg parcel and
    flew it; now the message says what the mass was compared with."""
    message = (r"payload 'payload': mass: expected a mass below 0\.008\d* kg, what the rotors' "
               r"largest total thrust 0\.3514 N at g = 9\.81 m/s\^2 .* lifts beyond the 0\.027 kg "
               r"already on board")
    with pytest.raises(ParameterError, match=message):
        CRAZYFLIE.with_payload(Payload(mass, (0.0, 0.0, 0.0)))
    with pytest.raises(ParameterError, match="mass: expected a mass below"):
        CRAZYFLIE.replace(payloads=(Payload(mass, (0.0, 0.0, 0.0)),))
    with pytest.raises(ParameterError, match=r"payload\[0\] \(attach 'p' at t = 0\.1 s\): mass: "
                                             r"expected a mass below"):
        loads = as_payload_profile([dict(t=0.1, action="attach", name="p", mass=mass,
                                         position=[0, 0, 0])], CRAZYFLIE)
        check_payload_events(CRAZYFLIE, loads, 1.0)


def test_what_the_rotors_lift_counts_what_is_on_board():
    """Two payloads of 5 g each fit a Crazyflie alone (8.8 g of lift to spare), not together;
    a heavier airframe that does not lift itself carries nothing."""
    one = CRAZYFLIE.with_payload(Payload(0.005, (0, 0, 0), name="a"))
    with pytest.raises(ParameterError, match=r"below 0\.00382\d* kg.*0\.032 kg already on board"):
        one.with_payload(Payload(0.005, (0, 0, 0), name="b"))
    heavy = CRAZYFLIE.replace(m=0.05)
    with pytest.raises(ParameterError, match="expected no payload: .* does not lift even the "
                                             r"0\.05 kg already on board"):
        heavy.with_payload(Payload(1e-6, (0, 0, 0)))
    events = [dict(t=0.1, action="attach", name="a", mass=0.005, position=[0, 0, 0]),
              dict(t=0.2, action="drop", name="a"),
              dict(t=0.3, action="attach", name="b", mass=0.005, position=[0, 0, 0])]
    check_payload_events(CRAZYFLIE, as_payload_profile(events, CRAZYFLIE), 1.0)   # one at a time
    events[1] = dict(t=0.2, action="move", name="a", position=[0.01, 0, 0])
    with pytest.raises(ParameterError, match=r"payload\[2\] \(attach 'b'"):
        check_payload_events(CRAZYFLIE, as_payload_profile(events, CRAZYFLIE), 1.0)


def test_simulate_refuses_a_parcel_heavier_than_the_rotors_lift():
    with pytest.raises(ParameterError, match="mass: expected a mass below 1.76"):
        quadcog.simulate(quadcog.FeedbackLinearization(), "hover", 0.5,
                         payloads=[dict(t=0.1, action="attach", name="p", mass=1e6,
                                        position=[0, 0, 0])])


# -- the vehicle's fields ----------------------------------------------------------------------

@pytest.mark.parametrize("field, value, words", [
    ("max_rotor_thrust", 1e308, r"max_rotor_thrust: expected a number <= 1e\+06 \(N"),
    ("thrust_constant", 1e300, r"thrust_constant: expected a number <= 1e\+06"),
    ("moment_constant", 5.0, r"moment_constant: expected a number <= 1 \(m"),
    ("motor_time_constant", 1e308, r"motor_time_constant: expected a number <= 10 \(s"),
])
def test_rotor_constants_beyond_any_rotor_are_refused(field, value, words):
    """Accepted before: 1e308 N per rotor made the reference limits inf; a motor time constant
    of 1e308 s is no motor (the vehicle-file readers refused both already)."""
    with pytest.raises(ParameterError, match=words):
        HUMMINGBIRD.replace(**{field: value})


@pytest.mark.parametrize("positions, words", [
    ([("0.17", "0"), ("0", "0.17"), ("-0.17", "0"), ("0", "-0.17")],
     r"rotor_positions\[0, 0\]: expected a real number, got '0.17'"),
    ([(True, False), (False, True), (-1, 0), (0, -1)],
     r"rotor_positions\[0, 0\]: expected a real number, got True"),
    (np.array([[0.17, 0], [0, 0.17], [-0.17, 0], [0, -0.17]]) + 1e-3j, "not complex numbers"),
    ([(1e300, 0), (0, 1e300), (-1e300, 0), (0, -1e300)], r"within \+-1e\+06 m"),
])
def test_rotor_positions_are_real_numbers_within_the_scale(positions, words):
    """Strings were cast to numbers ('0.17' flew), bools to 1.0 and 0.0, complex numbers lost
    their imaginary part, and 1e300 m arms were called a 'singular mixer'."""
    with pytest.raises(InputError, match=words):
        HUMMINGBIRD.replace(rotor_positions=positions)


@pytest.mark.parametrize("changes", [
    dict(name=np.float64(1.0)), dict(rotor_directions=np.float64(1.0)),
    dict(rotor_model=np.array([1.0])), dict(payloads=np.float64(1.0)),
    dict(payloads=np.array(1.0)),
])
def test_vehicle_messages_write_values_plainly(changes):
    """np.float64(1.0) and array(1.) reprs in the messages; a 0-d array of payloads raised
    numpy's 'iteration over a 0-d array' TypeError."""
    with pytest.raises(InputError) as info:
        HUMMINGBIRD.replace(**changes)
    assert not NUMPY_REPR.search(str(info.value)), str(info.value)


@pytest.mark.parametrize("call", [lambda: HUMMINGBIRD.without_payload(np.float64(1.0)),
                                  lambda: Payload(0.1, (0, 0, 0), name=np.array([1.0]))])
def test_payload_names_that_are_not_strings_are_written_plainly(call):
    with pytest.raises(InputError) as info:
        call()
    assert not NUMPY_REPR.search(str(info.value)), str(info.value)


@pytest.mark.parametrize("m, Ixx", [(None, 0.01), ("abc", 0.01), (1.0, [0.01]),
                                    (10 ** 400, 0.01), (1.0, float("nan")), (0.0, 0.01)])
def test_preset_drag_checks_its_arguments(m, Ixx):
    """Raw TypeError / OverflowError before, and NaN drag for NaN."""
    with pytest.raises(InputError, match=r"preset_drag: (m|Ixx): expected a number in"):
        preset_drag(m, Ixx)


# -- vehicle files ---------------------------------------------------------------------------

@pytest.mark.parametrize("call, words", [
    (lambda: Vehicle.from_urdf(CF2X, bogus=1), r"Vehicle\.from_urdf: expected options among "
                                                r"rotor_directions, g, name, got unknown 'bogus'"),
    (lambda: Vehicle.from_sdf(X500, colour="red"), r"Vehicle\.from_sdf: .*unknown 'colour'"),
    (lambda: Vehicle.from_file(CF2X, model_paths=()), r"from_file \(a \.urdf file\): .*"
                                                       r"unknown 'model_paths'"),
    (lambda: Vehicle.from_urdf(CF2X, rotor_directions=5), r"rotor_directions \(Vehicle\.from_urdf\)"),
    (lambda: Vehicle.from_urdf(CF2X, drag={"c_x": 0.1}), r"drag: expected None or a table of the "
                                                          r"six drag coefficients .*got a table with keys \['c_x'\]"),
    (lambda: Vehicle.from_urdf(CF2X, drag="abc"), "drag: expected None or a table"),
    (lambda: Vehicle.from_urdf(CF2X, drag={**preset_drag(1, 1), "m": 5.0}), "drag: expected"),
])
def test_vehicle_file_options_and_drag_are_checked(call, words):
    """Each was a raw TypeError ('urdf_fields() got an unexpected keyword argument', 'Vehicle
    .__init__() missing 5 required positional arguments', "'int' object is not iterable")."""
    with pytest.raises(InputError, match=words):
        call()


def _cf2x(tmp_path, old, new, name="cf.urdf"):
    text = CF2X.read_text()
    assert text.count(old) >= 1, old
    path = tmp_path / name
    path.write_text(text.replace(old, new, 1))
    return path


@pytest.mark.parametrize("old, new, words", [
    ('<joint name="prop0_joint" type="fixed">',
     '<joint name="prop0_joint" type="fixed"><origin xyz="1e200 0 0"/>',
     r"joint 'prop0_joint'/origin@xyz = '1e200 0 0'; expected 3 number\(s\) within \+-1e\+06"),
    ('<origin rpy="0 0 0" xyz="0 0 0"/>\n      <mass value="0.027"/>',
     '<origin rpy="0 0 0" xyz="1e300 0 0"/>\n      <mass value="0.027"/>',
     r"link 'base_link' <inertial>/origin@xyz = '1e300 0 0'"),
    ('ixx="1.4e-5" ixy="0.0" ixz="0.0" iyy="1.4e-5" iyz="0.0" izz="2.17e-5"',
     'ixx="1e308" ixy="0.0" ixz="0.0" iyy="1e308" iyz="0.0" izz="1e308"',
     r"inertia@ixx = '1e308'; expected 1 number\(s\) within"),
    ('<mass value="0.027"/>', '<mass value="1e308"/>', r"mass@value = '1e308'"),
])
def test_urdf_numbers_beyond_the_scale_are_named(tmp_path, old, new, words):
    """Their parallel-axis sums overflowed: 'vehicle ...: Ixx = nan is not finite' named a NaN
    the file does not hold, with numpy overflow warnings on the way."""
    with _no_warnings():
        with pytest.raises(VehicleFileError, match=words):
            Vehicle.from_urdf(_cf2x(tmp_path, old, new))


def test_a_chain_of_joints_that_sums_beyond_the_scale_is_named(tmp_path):
    """Each joint within 1e6 m, their sum not: the rotor link's place is refused by name."""
    chain = "".join(f'<link name="c{i}"/><joint name="cj{i}" type="fixed"><parent link='
                    f'"{"base_link" if i == 0 else f"c{i - 1}"}"/><child link="c{i}"/>'
                    '<origin xyz="900000 0 0"/></joint>' for i in range(3))
    text = CF2X.read_text().replace('<parent link="base_link"/>\n    <child link="prop0_link"/>',
                                    '<parent link="c2"/>\n    <child link="prop0_link"/>')
    path = tmp_path / "chain.urdf"
    path.write_text(text.replace("</robot>", chain + "</robot>"))
    with pytest.raises(VehicleFileError, match=r"rotor link 'prop0_link' is at \[2700000\.0"):
        Vehicle.from_urdf(path)


def test_an_inertia_in_the_wrong_unit_is_refused(tmp_path):
    """cf2x's inertia written in g mm^2's numbers (1e6 times kg m^2): a 27 g vehicle with
    rotors 4 cm out whose mass sits 30 m from its CoG was accepted and flown."""
    path = _cf2x(tmp_path, 'ixx="1.4e-5" ixy="0.0" ixz="0.0" iyy="1.4e-5" iyz="0.0" izz="2.17e-5"',
                 'ixx="14" ixy="0.0" ixz="0.0" iyy="14" iyz="0.0" izz="21.7"')
    with pytest.raises(VehicleFileError, match=r"puts their mass 30\.3 m from the CoG .*beyond "
                                               r"10 arm lengths \(0\.396 m\)"):
        Vehicle.from_urdf(path)
    for shipped in (CF2X, DATA / "gym-pybullet-drones" / "racer.urdf",
                    DATA / "gym-pybullet-drones" / "cf2p.urdf"):
        Vehicle.from_urdf(shipped)
    Vehicle.from_sdf(X500)


# -- rotor models ----------------------------------------------------------------------------

@pytest.mark.parametrize("kind, coefficients, scale", [
    ("polynomial", (1e308, 1e308, 1e308), 65535.0), ("polynomial", (0.0, 0.0, 1e300), 65535.0),
    ("voltage_cubic", (0.0, 1.0, 0.0, 1e300), 1.0), ("voltage", (0.0, 1e-300, 0.0), 1.0),
])
def test_a_rotor_map_that_overflows_is_refused(kind, coefficients, scale):
    """thrust() returned inf (with numpy's overflow warning) for a map whose value at full
    output is beyond the float range."""
    with pytest.raises(InputError, match="coefficients: expected a map whose thrust stays "
                                         "within the float range"):
        model = RotorModel("x", kind, "motor_pwm", coefficients, "test", scale=scale,
                           thrust_unit=1e10 if kind == "voltage" else 1.0)
        model.thrust([[1.0] * 4], 1000.0)


@pytest.mark.parametrize("c, f", [(None, 0.1), ("abc", 0.1), ((1.0, 2.0, 3.0), 0.1),
                                  ((0.0, 1.0, 0.0, 1.0), "x"), ((0.0, 1.0, 0.0, 1.0), np.nan),
                                  ((0.0, 1.0, 5.0, 1.0), 0.1), ((0.0, 1.0, 0.0, -1.0), 0.1)])
def test_cubic_voltage_checks_its_arguments(c, f):
    """Raw TypeError / ValueError ('not enough values to unpack'), NaN for NaN, and a cubic
    without one inverse answered with a wrong root."""
    with pytest.raises(InputError, match=r"cubic_voltage: (c|f)"):
        cubic_voltage(c, f)


@pytest.mark.parametrize("log", [None, "log.ulg", 5, {"param.THR_MDL_FAC": 0.5}])
def test_px4_thrust_curve_from_log_names_a_log_that_is_none(log):
    """AttributeError: 'NoneType' object has no attribute 'meta'."""
    with pytest.raises(InputError, match="px4_thrust_curve_from_log: log: expected a flight log"):
        px4_thrust_curve_from_log(log, 1.0)


# -- trajectories ----------------------------------------------------------------------------

def test_minimum_snap_builds_without_a_python_call_per_row(monkeypatch):
    """The system was assembled one row at a time (_derivative_row per row: 10,000 waypoints
    took 13 s); now in whole arrays, and solved as a band (linear in the waypoints)."""
    monkeypatch.setattr(waypoints, "_derivative_row",
                        lambda *a: pytest.fail("a Python call per row of the system"))
    rng = np.random.default_rng(7)
    pts = np.cumsum(rng.uniform(0.5, 1.0, (10_000, 3)), axis=0)
    start = time.process_time()
    traj = MinimumSnap(pts)
    assert time.process_time() - start < 8.0
    assert np.allclose(traj.sample(traj.times[::97])[:, :3], pts[::97], atol=1e-9)


def test_minimum_snap_equals_the_dense_system_with_times_given():
    """The banded solve against numpy's dense solve of the same constraints (rows in the
    order of the old sparse system), for uneven segment times."""
    from quadcog.trajectories.waypoints import N_COEF, _derivative_row
    rng = np.random.default_rng(11)
    pts = rng.normal(size=(25, 3))
    times = np.r_[0.0, np.cumsum(rng.uniform(0.05, 20.0, 24))]
    traj = MinimumSnap(pts, times=times)
    n, T = len(pts) - 1, np.diff(times)
    A, b = np.zeros((N_COEF * n, N_COEF * n)), np.zeros((N_COEF * n, 3))
    rows = []
    for i in range(n):
        rows += [[(i, 0.0, 0, 1.0)], [(i, T[i], 0, 1.0)]]
        b[2 * i], b[2 * i + 1] = pts[i], pts[i + 1]
    for order in (1, 2, 3):
        rows += [[(0, 0.0, order, 1.0)], [(n - 1, T[-1], order, 1.0)]]
    for i in range(n - 1):
        rows += [[(i, T[i], order, 1.0), (i + 1, 0.0, order, -1.0)] for order in range(1, 7)]
    for r, entries in enumerate(rows):
        for seg, tau, order, sign in entries:
            A[r, N_COEF * seg:N_COEF * (seg + 1)] += sign * _derivative_row(tau, order)
    dense = np.linalg.solve(A, b).reshape(n, N_COEF, 3)
    assert np.allclose(traj.coefficients, dense, rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("speed, acc", [(1e-320, 1.0), (1.0, 5e-324)])
def test_allocate_times_refuses_a_segment_time_past_the_float_range(speed, acc):
    """allocate_times returned inf (numpy overflow warning) for a speed of 1e-320 m/s."""
    with _no_warnings():
        with pytest.raises(InputError, match="would take longer than a float can hold"):
            allocate_times([[0, 0, 0], [1, 0, 0]], max_speed=speed, max_acceleration=acc)


@pytest.mark.parametrize("tau", [np.nan, [0.5, np.inf], "0.5", None, [[0.1], [0.2, 0.3]], 1j])
def test_septic_step_refuses_what_is_not_a_finite_time(tau):
    """A NaN step for NaN; raw ValueError/TypeError for the rest."""
    with pytest.raises(InputError, match="septic_step: tau"):
        septic_step(tau)


@pytest.mark.parametrize("t", [np.nan, [[0.0, 1.0]], "abc", 1j, 10 ** 400])
def test_user_trajectories_are_sampled_at_finite_times_only(t):
    """FromCallable.sample(nan) called the function at t = nan and answered; a 2-D array was
    'only 0-dimensional arrays can be converted'; VerticalSine.sample(nan) gave NaN rows."""
    with pytest.raises(InputError, match=r"^t"):
        FromCallable(lambda s: [s, 0.0, 0.0]).sample(t)
    with pytest.raises(InputError, match=r"^t"):
        VerticalSine().sample(t)


@pytest.mark.parametrize("kwargs", [dict(amplitude=1e308), dict(period=1e-320),
                                    dict(period=5e-324)])
def test_the_example_trajectory_refuses_settings_that_give_no_finite_rows(kwargs):
    with pytest.raises(InputError, match="amplitude|period"):
        VerticalSine(**kwargs)


def test_make_trajectory_names_an_unknown_setting():
    """TypeError: Circle.__init__() got an unexpected keyword argument 'bogus'."""
    with pytest.raises(InputError, match=r"trajectory 'circle': expected settings among center, "
                                         r"radius, period, yaw, got unknown 'bogus'"):
        make_trajectory("circle", bogus=1)


@pytest.mark.parametrize("call, words", [
    (lambda: reference_limits(None), "vehicle: expected a quadcog Vehicle"),
    (lambda: reference_limits(HUMMINGBIRD, "abc"), "max_tilt: expected"),
    (lambda: reference_limits(HUMMINGBIRD, 10.0), "max_tilt: expected"),
    (lambda: check_reference(np.zeros(3), np.zeros((3, 14)), "hb"), "vehicle"),
    (lambda: check_reference(None, np.zeros((3, 14)), HUMMINGBIRD), "t: expected"),
    (lambda: check_reference(np.zeros(3), np.zeros((3, 12)), HUMMINGBIRD), "ref: expected"),
    (lambda: check_reference(np.zeros(2), np.zeros((3, 14)), HUMMINGBIRD),
     "t, ref: expected one time per reference row"),
    (lambda: check_reference(np.zeros(3), np.full((3, 14), np.nan), HUMMINGBIRD),
     r"ref\[0, 0\]: expected a finite number, got nan"),
    (lambda: check_reference(np.zeros(3), np.zeros((3, 14)), HUMMINGBIRD, None, 1), "constant"),
])
def test_the_feasibility_check_checks_its_arguments(call, words):
    """Raw AttributeError ('has no attribute mixer'), IndexError and broadcast errors before;
    NaN rows gave a 'feasible' check with NaN maxima."""
    with pytest.raises(InputError, match=words):
        call()


@pytest.mark.parametrize("make, words", [
    (lambda: Flip(duration=1e-9), r"flip: expected settings whose reference stays within "
                                  r"\+-1e\+12 \(SI units\), got radius 1\.0 m and duration 1e-09 s"),
    (lambda: Flip(duration=1e-300), "flip: expected settings"),
    (lambda: Flip(radius=1000.0, duration=1e-3), r"m/s\^3 of jerk"),
    (lambda: BankedCircle(ramp=1e-300), "banked_circle: expected settings"),
    (lambda: BankedCircle(radius=1e-300), "more than a float holds"),
])
def test_an_aerobatic_motion_beyond_the_reference_limit_is_refused_when_made(make, words):
    """A loop flown in a nanosecond fell between a flight's samples: the reference stayed a
    hover and the run said nothing; a ramp of 1e-300 s was reported as 'jx is nan'."""
    with pytest.raises(InputError, match=words):
        make()


def test_aerobatic_motions_within_the_limit_still_fly():
    Flip(duration=0.3)
    BankedCircle(ramp=1e-3)
    Flip()
    BankedCircle()


# -- a run's timeline ------------------------------------------------------------------------

@pytest.mark.parametrize("call", [
    lambda: CogProfile.step(1.0, 0.5), lambda: CogProfile.step(1.0, None),
    lambda: CogProfile.step(1.0, (0.01, 0.0, 0.0)).sample("abc"),
    lambda: CogProfile.step(1.0, (0.01, 0.0, 0.0)).sample([[0.0, 1.0], [2.0]]),
    lambda: CogProfile(np.array(1.0)),
    lambda: wrench_table([], "abc"), lambda: wrench_table(np.array(1.0), [0.0]),
    lambda: PayloadProfile(np.array(1.0)),
    lambda: CogProfile([(1e308, (0.01, 0, 0), 1e308)]),
])
def test_timeline_arguments_that_are_not_times_or_changes_are_refused(call):
    """Raw TypeError ('float' object is not iterable, iteration over a 0-d array), ValueError
    (could not convert string to float) before; a ramp ending at inf was taken."""
    with pytest.raises(InputError):
        call()


def test_two_cog_steps_at_one_instant_are_refused():
    """The first step was never held (the second replaced it at once), silently."""
    with pytest.raises(InputError, match=r"cog change 1: t = 0\.5 s is the time of the step of "
                                         r"change 0 to r = \[0\.01, 0\.0, 0\.0\] m, which is then "
                                         "never held"):
        CogProfile([(0.5, (0.01, 0, 0)), (0.5, (0.02, 0, 0))])
    CogProfile([(0.5, (0.01, 0, 0)), (0.5, (0.02, 0, 0), 1.0)])        # a step, then a ramp
    CogProfile([(0.5, (0.01, 0, 0), 1.0), (1.5, (0.02, 0, 0))])        # at the ramp's end


ATTACH = dict(t=1.0, action="attach", name="a", mass=0.01, position=[0.01, 0, 0])


@pytest.mark.parametrize("second, words", [
    (dict(t=1.0, action="move", name="a", position=[0, 0.01, 0]), r"attached at \[0\.01, 0\.0, "
                                                                  r"0\.0\] m, which is then never"),
    (dict(t=1.0, action="drop", name="a"), "never carried"),
])
def test_a_payload_event_that_undoes_the_one_before_at_once_is_refused(second, words):
    """An attach at one place and a move at the same instant: the first place was never held.
    The profile itself refuses it now (as_payload_profile, PayloadProfile), not only the run."""
    with pytest.raises(InputError, match=words):
        PayloadProfile([ATTACH, second])
    moved = dict(t=2.0, action="move", name="a", position=[0.0, 0.0, 0.0])
    with pytest.raises(InputError, match=r"moved to \[0\.0, 0\.0, 0\.0\] m, which is then never"):
        PayloadProfile([ATTACH, moved, dict(t=2.0, action="drop", name="a")])
    PayloadProfile([ATTACH, dict(t=1.0, action="move", name="a", position=[0, 0.01, 0],
                                 ramp=0.5)])                  # a slide from where it was put


SCHEDULE = Schedule.build(Hover(), 1.0, 0.01)


@pytest.mark.parametrize("call, words", [
    (lambda: Schedule.build("hover", 1.0, 0.01), "trajectory: expected a quadcog Trajectory"),
    (lambda: Schedule.build(Hover(), "1", 0.01), "duration"),
    (lambda: Schedule.build(Hover(), 1.0, float("inf")), "dt"),
    (lambda: Schedule.build(Hover(), 1.0, 0.01, cog="abc"), "cog: expected None or a CogProfile"),
    (lambda: Schedule.build(Hover(), 1.0, 0.01, payloads={"a": 1}), "payloads"),
    (lambda: Schedule.build(Hover(), 1.0, 0.01, cog_scale=2.0), "cog_scale"),
    (lambda: Schedule.build(Hover(), 1.0, 0.01, cog_scale=lambda t: float("nan")),
     r"cog_scale\(0\.0\): expected a finite real number, got nan"),
    (lambda: SCHEDULE.rows("a", 5), "start, stop"),
    (lambda: SCHEDULE.rows(0, 0), "start, stop"),
    (lambda: SCHEDULE.block(0, 10 ** 6), "start, stop"),
    (lambda: SCHEDULE.matrices(True, 5), "start, stop"),
    (lambda: SCHEDULE.padded("4"), "multiple"),
    (lambda: SCHEDULE.padded(10 ** 400), "multiple"),
    (lambda: SCHEDULE.r_G("abc"), "r_vehicle"),
    (lambda: tail_start("abc"), "duration"),
    (lambda: start_at_reference("abc"), "ref"),
    (lambda: whole_body("abc", np.zeros(10)), "p"),
    (lambda: whole_body(HUMMINGBIRD.parameters(), {"a": 1}), "payload"),
    (lambda: check_cog_changes(HUMMINGBIRD.parameters(), "abc"), "cog: expected a CogProfile"),
    (lambda: batch_start(None, None, np.zeros((1, 14)), np.zeros(12)), "controller"),
    (lambda: check_step_size(None, np.zeros(12), np.zeros(14), np.zeros(14), 0.01, None),
     "actuation"),
])
def test_schedule_and_prepare_arguments_are_checked(call, words):
    """Each was a raw AttributeError ('str' object has no attribute 'sample'), TypeError
    (slice indices must be integers, float object is not callable), ValueError (cannot
    reshape), OverflowError or IndexError."""
    with pytest.raises(InputError, match=words):
        call()


# -- costs linear in the pulses, the changes and the samples ---------------------------------

def _pulses_by_mask(pulses, t):
    """The table pulse by pulse over every sample (the old form), the oracle of its bits."""
    w = np.zeros((t.size, 6))
    for d in pulses:
        w[(t >= d.t) & (t < d.t + d.duration)] += np.concatenate([d.force, d.moment])
    return w


def _cog_by_mask(changes, t):
    """r_G(t) change by change over every sample (the old form)."""
    r, prev = np.zeros((t.size, 3)), np.zeros(3)
    for c in changes:
        target, on = np.array(c.r), t >= c.t
        s = np.clip((t[on] - c.t) / c.ramp, 0.0, 1.0) if c.ramp > 0 else np.ones(on.sum())
        r[on] = prev + s[:, None] * (target - prev)
        prev = target
    return r


def test_the_wrench_table_has_the_bits_of_adding_pulse_by_pulse():
    rng = np.random.default_rng(5)
    for _ in range(50):
        pulses = [quadcog.Disturbance(float(rng.uniform(0, 5)), float(rng.uniform(1e-3, 2)),
                                      tuple(rng.normal(size=3)), tuple(rng.normal(size=3)))
                  for _ in range(int(rng.integers(0, 10)))]
        t = np.arange(601) * 0.01
        assert np.array_equal(wrench_table(pulses, t), _pulses_by_mask(pulses, t))
        shuffled = rng.uniform(0, 6, 40)
        assert np.array_equal(wrench_table(pulses, shuffled), _pulses_by_mask(pulses, shuffled))


def test_a_cog_profile_has_the_bits_of_writing_change_by_change():
    rng = np.random.default_rng(6)
    for _ in range(50):
        changes, start = [], 0.0
        for _ in range(int(rng.integers(0, 8))):
            start += float(rng.uniform(0.01, 1.0))
            ramp = float(rng.choice([0.0, rng.uniform(0.0, 1.0)]))
            changes.append(CogChange(start, tuple(rng.uniform(-0.02, 0.02, 3)), ramp))
            start += ramp
        profile = CogProfile(changes)
        t = np.arange(801) * 0.01
        assert np.array_equal(profile.sample(t), _cog_by_mask(profile.changes, t))


def test_wrench_table_and_cog_profile_cost_linear_in_pulses_and_samples():
    """1,000 pulses or changes over a million samples: a mask per pulse or change over every
    sample took 5 s and 28 s (pulses x samples); now a fraction of a second."""
    t = np.arange(1_000_001) * 1e-5
    pulses = [quadcog.Disturbance(0.01 * k, 0.005, (0.1, 0.0, 0.0)) for k in range(1000)]
    changes = CogProfile([(0.01 * k, (0.001 * (k % 5), 0.0, 0.0), 0.002 * (k % 2))
                          for k in range(1000)])
    start = time.process_time()
    wrench_table(pulses, t)
    changes.sample(t)
    assert time.process_time() - start < 4.0


@pytest.mark.parametrize("layout", [quadcog.plus_layout, quadcog.x_layout])
def test_layouts_refuse_an_arm_beyond_the_scale(layout):
    """plus_layout(1e308) answered with rotors 1e308 m out, which no Vehicle takes."""
    with pytest.raises(InputError, match=r"arm: expected a number in \(0, 1000000\.0\] \(m\)"):
        layout(1e308)


@pytest.mark.parametrize("kwargs, words", [
    (dict(vehicle=np.ones(14)), r"^vehicle: expected a quadcog Vehicle, got an array of shape "
                                r"\(14,\)"),
    (dict(controller_model=np.float64(1.0)), r"^controller_model: expected a quadcog Vehicle, "
                                             r"got 1\.0$"),
    (dict(controller=np.zeros(3)), r"^controller: expected a quadcog Controller, or a callable"),
])
def test_simulate_names_a_vehicle_that_is_none_plainly(kwargs, words):
    """'vehicle must be a quadcog Vehicle, got array([1., 1., ...])': numpy's repr."""
    args = {"controller": quadcog.FeedbackLinearization(), "trajectory": "hover",
            "duration": 0.5, **kwargs}
    with pytest.raises(InputError, match=words):
        quadcog.simulate(**args)


def test_minimum_snap_names_long_times_by_their_shape():
    """The message printed every one of 10,000 times (a 200 kB message)."""
    pts = np.column_stack([np.arange(10_000.0), np.zeros(10_000), np.zeros(10_000)])
    with pytest.raises(InputError) as info:
        MinimumSnap(pts, times=np.arange(10_000.0)[::-1])
    assert len(str(info.value)) < 300
    assert "an array of shape (10000,)" in str(info.value)


@pytest.mark.parametrize("max_thrust", ["abc", None, float("nan"), -1.0, [1.0]])
def test_px4_thrust_curve_from_log_checks_max_thrust_first(max_thrust):
    """A string max_thrust raised ValueError ('Unknown format code g') from the model's
    source text, before any check."""
    class Log:
        source, meta = "x.ulg", {"param.THR_MDL_FAC": "0.3"}
    with pytest.raises(InputError, match="px4_thrust_curve_from_log: max_thrust"):
        px4_thrust_curve_from_log(Log(), max_thrust)

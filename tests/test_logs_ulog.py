"""PX4 ULog: the NED/FRD -> z-up conversion on known rotations, the SITL sample of
tests/data/ulog read into signals (checked against its own physics), the writer read by
pyulog itself, round trips, and damaged files."""
from pathlib import Path
import struct

import numpy as np
import pytest

from quadcog.errors import LogFormatError, LogSignalError
from quadcog.logs import FlightLog, read_log, write_log
from quadcog.logs.ulog import euler_to_quaternion, px4_to_quadcog_quaternion, quaternion_to_euler
from quadcog.model.conventions import rotation_matrix

SAMPLE = Path(__file__).resolve().parent / "data" / "ulog" / "sample_px4_events.ulg"
T = np.diag([1.0, -1.0, -1.0])          # NED -> NWU and FRD -> FLU


def rx(a):
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def quat_matrix(q):
    """The rotation matrix of a unit quaternion (w, x, y, z), the textbook formula."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def px4_quaternion(roll, pitch, yaw):
    """PX4's q (FRD -> NED) of its own ZYX angles, by half-angle products (PX4's Eulerf)."""
    return euler_to_quaternion(roll, pitch, yaw)


@pytest.mark.parametrize("px4_euler", [(0, 0, 0), (0.3, 0, 0), (0, 0.3, 0), (0, 0, 1.2),
                                       (0.2, -0.4, 2.5), (-1.0, 0.7, -3.0)])
def test_frame_conversion_on_known_rotations(px4_euler):
    """R_quadcog = T R_px4 T: the converted quaternion's matrix and the ZYX angles read from
    it (as quadcog's rotation_matrix) both give it."""
    r_px4 = rz(px4_euler[2]) @ ry(px4_euler[1]) @ rx(px4_euler[0])
    q_px4 = px4_quaternion(*px4_euler)
    assert np.allclose(quat_matrix(q_px4), r_px4)
    q = px4_to_quadcog_quaternion(q_px4)
    assert np.allclose(quat_matrix(q), T @ r_px4 @ T)
    roll, pitch, yaw = quaternion_to_euler(q)
    assert np.allclose(rotation_matrix(roll, pitch, yaw), T @ r_px4 @ T)
    assert np.allclose([roll, pitch, yaw], [px4_euler[0], -px4_euler[1],
                                            np.angle(np.exp(-1j * px4_euler[2]))])


def test_known_attitudes_in_words():
    """PX4 nose east (yaw +90 deg about down) is quadcog nose at -y (y points west): yaw
    -90 deg; PX4 nose up 10 deg is quadcog pitch -10 deg (positive pitch lowers the nose);
    PX4 right wing down 10 deg is quadcog roll +10 deg."""
    east = quaternion_to_euler(px4_to_quadcog_quaternion(px4_quaternion(0, 0, np.pi / 2)))
    assert np.allclose(east, [0, 0, -np.pi / 2])
    r = rotation_matrix(*quaternion_to_euler(px4_to_quadcog_quaternion(
        px4_quaternion(0, np.radians(10), 0))))
    assert r[2, 0] > 0                                 # body x (nose) has a z-up component
    r = rotation_matrix(*quaternion_to_euler(px4_to_quadcog_quaternion(
        px4_quaternion(np.radians(10), 0, 0))))
    assert r[2, 1] > 0                                 # body y (left wing) goes up


@pytest.fixture(scope="module")
def sample():
    return read_log(SAMPLE)


def test_sample_reads_into_signals(sample):
    assert sample.format == "ulog" and sample.meta["sys_name"] == "PX4"
    assert set(sample.signals) == {"position", "velocity", "acceleration", "roll", "pitch",
                                   "yaw", "body_rates", "motor_command", "motor_pwm",
                                   "battery_voltage", "thrust_command"}
    assert sample.meta["time_base"] == "vehicle_local_position"
    assert 300 < sample.n_samples < 320 and 30.0 < sample.t[-1] < 31.5
    steps = np.diff(sample.t)                   # logged at 10 Hz, steps of 96 and 104 ms
    assert np.allclose(steps.mean(), 0.1, atol=1e-3)
    assert (np.isclose(steps, 0.096) | np.isclose(steps, 0.104)).all()
    z = sample.signal("position")[:, 2]
    # idle until 16.5 s, up to 2.15 m (z up) at 22.5 s, landed at 27 s with the estimate 0.4 m
    # below the take-off point (docs/logs.md)
    assert abs(z[0]) < 0.01 and 2.0 < z.max() < 2.3 and 21 < sample.t[np.argmax(z)] < 24
    assert 15.0 < sample.signal("battery_voltage").min() < 16.5
    assert 0.0 <= sample.signal("motor_command").min() and \
        sample.signal("motor_command").max() < 0.6
    assert np.degrees(np.abs(sample.signal("roll")).max()) < 5


def test_sample_rotor_order_from_the_parameters(sample):
    """CA_ROTOR0..3 (FRD) of the sample: PX4's quad X. In quadcog's order they must be
    front-right, back-right, back-left, front-left, spinning -1, 1, -1, 1 (KM > 0: CCW)."""
    assert sample.meta["rotor_order"] == "from CA_ROTOR{i}_PX/PY"
    pos = np.array([[float(v) for v in p.split()] for p in
                    sample.meta["rotor_positions_m"].split(";")])
    assert (np.sign(pos) == [[1, -1], [-1, -1], [-1, 1], [1, 1]]).all()
    assert sample.meta["rotor_directions"] == "-1 1 -1 1"
    assert sample.meta["param.THR_MDL_FAC"] == "0.0"


def test_sample_outputs_are_the_motor_controls(sample):
    """actuator_outputs (channels by PWM_MAIN_FUNC, 1000..2000 us) and actuator_motors (rotors
    by CA_ROTOR positions) are two routes to the same motors: when running they agree to the
    us rounding of the outputs; disarmed (900 us) is 0."""
    m, pwm = sample.signal("motor_command"), sample.signal("motor_pwm")
    on = m > 0.01
    assert on.sum() > 400 and np.abs(m[on] - pwm[on]).max() < 1e-3
    assert (pwm[m == 0] == 0).all()
    assert sample.meta["pwm_range"].startswith("PX4's defaults")


def _corr(x, y):
    return np.corrcoef(x, y)[0, 1]


def test_sample_physics(sample):
    """The sample's signals against each other after the conversion: vertical velocity is
    dz/dt (0.95), vertical acceleration dvz/dt (0.98), the thrust set-point the mean motor
    output (1.00): each would be negative with a wrong sign. Attitude and rates are small in
    this climb but keep their signs: p, q against the derivatives of roll, pitch (0.35, 0.47),
    a_x against g tan(pitch) (0.31)."""
    t = sample.t
    p, v, a = (sample.signal(n) for n in ("position", "velocity", "acceleration"))
    assert _corr(v[:, 2], np.gradient(p[:, 2], t)) > 0.9
    assert _corr(a[:, 2], np.gradient(v[:, 2], t)) > 0.9
    assert _corr(sample.signal("thrust_command"), sample.signal("motor_command").mean(1)) > 0.99
    w = sample.signal("body_rates")
    assert _corr(w[:, 0], np.gradient(sample.signal("roll"), t)) > 0.2
    assert _corr(w[:, 1], np.gradient(sample.signal("pitch"), t)) > 0.2
    assert _corr(a[:, 0], 9.81 * np.tan(sample.signal("pitch"))) > 0.2


def test_written_ulog_is_read_by_pyulog_in_px4_frames(sample, tmp_path):
    from pyulog import ULog
    path = write_log(sample, tmp_path / "out.ulg", "ulog")
    u = ULog(str(path))
    # the info names the log's vehicle (the sample's, read from its ULog), and quadcog's writer
    assert not u.file_corruption and u.msg_info_dict["sys_name"] == sample.meta["vehicle"]
    assert u.msg_info_dict["ver_hw"] == "quadcog.logs.write_log"
    topics = {d.name: d.data for d in u.data_list}
    assert set(topics) == {"vehicle_local_position", "vehicle_attitude",
                           "vehicle_angular_velocity", "actuator_motors", "actuator_outputs",
                           "battery_status", "vehicle_thrust_setpoint"}
    lp = topics["vehicle_local_position"]
    assert lp["timestamp"].size == sample.n_samples
    assert np.allclose(lp["z"], -sample.signal("position")[:, 2], atol=1e-6)      # NED down
    assert np.allclose(lp["vy"], -sample.signal("velocity")[:, 1], atol=1e-6)
    av = topics["vehicle_angular_velocity"]
    assert np.allclose(av["xyz[2]"], -sample.signal("body_rates")[:, 2], atol=1e-6)  # FRD
    q = np.column_stack([topics["vehicle_attitude"][f"q[{i}]"] for i in range(4)])
    yaw_px4 = np.arctan2(2 * (q[:, 0] * q[:, 3] + q[:, 1] * q[:, 2]),
                         1 - 2 * (q[:, 2] ** 2 + q[:, 3] ** 2))
    assert np.allclose(np.angle(np.exp(1j * (yaw_px4 + sample.signal("yaw")))), 0, atol=1e-5)
    am = topics["actuator_motors"]                   # PX4 motor 2 is back-left: quadcog's 3
    assert np.allclose(am["control[1]"], sample.signal("motor_command")[:, 2], atol=1e-6)
    assert np.isnan(am["control[4]"]).all()
    assert np.allclose(topics["actuator_outputs"]["output[1]"],
                       1000 + 1000 * sample.signal("motor_pwm")[:, 2], atol=1e-3)
    assert u.initial_parameters["PWM_MAIN_FUNC2"] == 102
    assert np.allclose(topics["vehicle_thrust_setpoint"]["xyz[2]"],
                       -sample.signal("thrust_command"), atol=1e-6)
    assert u.initial_parameters["CA_ROTOR_COUNT"] == 4
    assert u.initial_parameters["CA_ROTOR1_PX"] < 0 < u.initial_parameters["CA_ROTOR1_PY"] * -1


def test_ulog_round_trip(sample, tmp_path):
    back = read_log(write_log(sample, tmp_path / "out.ulg", "ulog"))
    assert np.array_equal(back.t, sample.t)
    assert back.meta["rotor_positions_m"] == sample.meta["rotor_positions_m"]
    for name in sample.signals:
        scale = max(1.0, np.abs(sample.signal(name)).max())
        assert np.abs(back.signal(name) - sample.signal(name)).max() < 1e-6 * scale, name


def test_ulog_round_trip_of_large_attitudes(tmp_path):
    rng = np.random.default_rng(11)
    n = 60
    t = np.arange(n) * 0.02
    s = {"roll": rng.uniform(-2.5, 2.5, n), "pitch": rng.uniform(-1.4, 1.4, n),
         "yaw": rng.uniform(-np.pi + 1e-6, np.pi, n), "body_rates": rng.normal(size=(n, 3)),
         "position": rng.normal(size=(n, 3)), "motor_command": rng.uniform(0, 1, (n, 4))}
    log = FlightLog("sim", "csv", t, s, {}, {})
    back = read_log(write_log(log, tmp_path / "big.ulg", "ulog"))
    for name in s:
        assert np.allclose(back.signal(name), s[name], atol=2e-6), name
    assert back.meta["rotor_order"] == "from CA_ROTOR{i}_PX/PY"


def test_ulog_writer_refuses_what_it_cannot_carry(tmp_path):
    t = np.arange(5) * 0.1
    for signals, match in [({"moment_command": np.zeros((5, 3))}, "does not carry"),
                           ({"roll": np.zeros(5)}, "needs roll, pitch and yaw"),
                           ({}, "no standard signal")]:
        with pytest.raises(LogSignalError, match=match):
            write_log(FlightLog("x", "csv", t, signals, {}, {}), tmp_path / "x.ulg", "ulog")


def _small(tmp_path):
    t = np.arange(6) * 0.1
    log = FlightLog("x", "csv", t, {"position": np.ones((6, 3)), "battery_voltage": np.ones(6)},
                    {}, {})
    return write_log(log, tmp_path / "small.ulg", "ulog")


def test_damaged_ulog_files(tmp_path):
    data = SAMPLE.read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(data[:len(data) // 2])
    with pytest.raises(LogFormatError, match="truncated ULog"):
        read_log(cut)
    magic = tmp_path / "magic.ulg"
    magic.write_bytes(b"ULog\x01\x12\x36" + data[7:200])
    with pytest.raises(LogFormatError, match="not a ULog"):
        read_log(magic, format="ulog")
    small = _small(tmp_path).read_bytes()
    at = small.rindex(b"D")                            # the last data message's type byte
    unknown = bytearray(small)
    unknown[at + 1:at + 3] = struct.pack("<H", 99)     # a subscription that does not exist
    p = tmp_path / "corrupt.ulg"
    p.write_bytes(bytes(unknown))
    with pytest.raises(LogFormatError, match="corrupt"):
        read_log(p)


def test_ulog_time_must_increase(tmp_path):
    path = _small(tmp_path)
    data = bytearray(path.read_bytes())
    stamps = [i for i in range(len(data) - 12) if data[i] == ord("D") and
              data[i + 1:i + 3] == b"\x00\x00"]       # data of vehicle_local_position (id 0)
    a, b = stamps[1] + 3, stamps[2] + 3                # swap two samples' time stamps
    data[a:a + 8], data[b:b + 8] = data[b:b + 8], data[a:a + 8]
    path.write_bytes(bytes(data))
    with pytest.raises(LogFormatError, match="vehicle_local_position: time stamp of sample"):
        read_log(path)


def test_ulog_without_a_time_base_topic(tmp_path, monkeypatch):
    """The writer refuses such a log (its reader would); written with the writer's check
    switched off, as another tool could write it, the reader refuses it."""
    import quadcog.logs.ulog as ulog_module
    t = np.arange(5) * 0.1
    log = FlightLog("x", "csv", t, {"battery_voltage": np.full(5, 3.9)}, {}, {})
    with pytest.raises(LogSignalError, match="time base"):
        write_log(log, tmp_path / "bat.ulg", "ulog")
    with monkeypatch.context() as m:
        m.setattr(ulog_module, "BASE_TOPICS", ("battery_status",))
        path = write_log(log, tmp_path / "bat.ulg", "ulog")
    with pytest.raises(LogSignalError, match="none of the topics"):
        read_log(path)


def test_a_signal_with_nan_samples_is_left_out_and_said_so(tmp_path):
    """PX4 publishes NaN for an estimate that is not valid yet: that signal is left out, the
    rest of the log is read, and asking for it quotes why."""
    path = _small(tmp_path)
    data = bytearray(path.read_bytes())
    first = next(i for i in range(len(data) - 12) if data[i] == ord("D")
                 and data[i + 1:i + 3] == b"\x00\x00")
    data[first + 11:first + 15] = struct.pack("<f", float("nan"))     # its x after timestamp
    path.write_bytes(bytes(data))
    log = read_log(path)
    assert not log.has("position") and log.has("battery_voltage")
    assert log.meta["signals_dropped"] == "position (1 of 6 samples not finite)"
    with pytest.raises(LogSignalError, match=r"left out position \(1 of 6 samples"):
        log.signal("position")

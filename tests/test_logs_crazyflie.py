"""The Crazyflie uSD-deck log: files built byte by byte here from the firmware's format
(usddeck.c), damaged files, the writer decoded by this file's own decoder, and what the real
CrazyPAD flights in tests/data/crazypad show (CRC, 100 Hz, hover height, battery, motor
ranges, velocity and acceleration against derivatives, the roll sign against the lateral
acceleration, the firmware's battery compensation, the gyro's pitch sign, and the controller
logs against the motor logs of the same drones)."""
from pathlib import Path
import struct
import zlib

import numpy as np
import pytest
from scipy.integrate import cumulative_trapezoid

from quadcog.errors import LogCRCError, LogFormatError, LogSignalError
from quadcog.logs import FlightLog, read_log, write_log
from quadcog.logs.checks import airborne_segments, bandpass, fit_gain, lowpass

DATA = Path(__file__).resolve().parent / "data" / "crazypad"
G = 9.81
# Firmware layout, written out here (not imported): type characters and their struct codes.
TYPES = {"B": "B", "b": "b", "H": "H", "h": "h", "I": "I", "i": "i", "f": "f", "e": "e"}


def usd_bytes(events, records, version=2, crc=True):
    """A uSD log: ``events`` = [(id, name, [(var, T), ...])], ``records`` = [(id, tick,
    values)] with tick in the version's unit (1: ms, 2: us)."""
    out = bytearray(struct.pack("<BHH", 0xBC, version, len(events)))
    layout = {}
    for eid, name, variables in events:
        out += struct.pack("<H", eid) + name.encode() + b"\0" + struct.pack("<H", len(variables))
        for var, typ in variables:
            out += f"{var}({typ})".encode() + b"\0"
        layout[eid] = "<" + "".join(TYPES[t] for _, t in variables)
    for eid, tick, values in records:
        out += struct.pack("<H" + ("I" if version == 1 else "Q"), eid, tick)
        out += struct.pack(layout[eid], *values)
    if crc:
        out += struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF)
    return bytes(out)


MOTOR_VARS = ([(f"motor.m{k}", "I") for k in range(1, 5)]
              + [(f"pwm.m{k}_pwm", "I") for k in range(1, 5)] + [("pm.vbatMV", "H")]
              + [(f"stateEstimate.{c}", "f") for c in ("x", "y", "z", "vx", "vy", "vz", "ax",
                                                        "ay", "az", "roll", "pitch", "yaw")]
              + [(f"controller.{c}", "f") for c in ("r_roll", "r_pitch", "r_yaw", "cmd_thrust",
                                                     "cmd_roll", "cmd_pitch", "cmd_yaw")])


def motor_values(k):
    """One record's values (firmware units) for MOTOR_VARS, varying with k."""
    return ([13107 * (j + 1) // 2 + k for j in range(4)] + [6553 * (j + 1) + k for j in range(4)]
            + [3700 + k, 0.5, -0.25, 0.55 + 0.01 * k, 0.1, -0.2, 0.3, 0.5, -0.25, 0.125,
               10.0, 20.0, 170.0 + 5 * k, 0.5, 0.25, -0.125, 39321.0, 1000.0, -500.0, 250.0])


@pytest.fixture
def hand_built(tmp_path):
    """Three fixed-frequency records at 10 ms and an event record in between (version 2)."""
    events = [(0xFFFF, "fixedFrequency", MOTOR_VARS), (12, "takeoff", [("height", "e")])]
    records = [(0xFFFF, 5_000_000 + 10_000 * k, motor_values(k)) for k in range(3)]
    records.insert(2, (12, 5_012_000, [0.5]))
    p = tmp_path / "log00"
    p.write_bytes(usd_bytes(events, records))
    return p


def test_hand_built_file_decodes_to_firmware_conversions(hand_built):
    log = read_log(hand_built)
    assert log.format == "crazyflie-usd" and log.meta["usd_version"] == "2"
    assert np.allclose(log.t, [0.0, 0.01, 0.02], atol=1e-12)
    assert log.meta["time_origin_us"] == "5000000" and log.meta["events"] == "takeoff: 1 records"
    m = log.signal("motor_command")
    assert np.allclose(m[0], [6553 / 65535, 13107 / 65535, 19660 / 65535, 26214 / 65535])
    assert np.allclose(log.signal("motor_pwm")[1], [6554 / 65535, 13107 / 65535,
                                                    19660 / 65535, 26213 / 65535])
    assert np.allclose(log.signal("battery_voltage"), [3.7, 3.701, 3.702])
    assert np.allclose(log.signal("position")[0], [0.5, -0.25, 0.55])
    assert np.allclose(log.signal("velocity")[0], [0.1, -0.2, 0.3])
    assert np.allclose(log.signal("acceleration")[0], [0.5 * G, -0.25 * G, 0.125 * G])
    assert np.allclose(log.signal("roll"), np.radians(10.0))
    assert np.allclose(log.signal("pitch"), -np.radians(20.0))     # legacy inverted pitch
    # yaw wraps to (-pi, pi]: 170, 175, 180 deg
    assert np.allclose(log.signal("yaw"), np.radians([170.0, 175.0, 180.0]))
    assert np.allclose(log.signal("body_rates")[0], [0.5, -0.25, -0.125])  # q = -r_pitch
    assert np.allclose(log.signal("thrust_command"), 39321 / 65535)
    # mixer: M1 = T - r + p + y with r = cmd_roll/2, p = cmd_pitch/2, y = cmd_yaw
    assert np.allclose(log.signal("moment_command")[0], [500 / 65535, 250 / 65535,
                                                         -250 / 65535])
    assert log.raw["pm.vbatMV"][2] == 3702 and log.raw["stateEstimate.pitch"][0] == 20.0
    assert "motor.m1" in log.meta["variables"]


def test_moment_command_reproduces_the_legacy_mixer():
    """moment_command's definition against the firmware's legacy power distribution."""
    from quadcog.vehicles.vehicle import CRAZYFLIE
    T, r, p, y = 30000.0, 800.0, -600.0, 400.0       # cmd_thrust, cmd_roll, cmd_pitch, cmd_yaw
    firmware = np.array([T - r / 2 + p / 2 + y, T - r / 2 - p / 2 - y,
                         T + r / 2 - p / 2 + y, T + r / 2 + p / 2 - y]) / 65535
    mx, my, mz = np.array([r / 2, -p / 2, -y]) / 65535
    pos = np.asarray(CRAZYFLIE.rotor_positions)
    d = np.asarray(CRAZYFLIE.rotor_directions)
    ours = T / 65535 + np.sign(pos[:, 1]) * mx - np.sign(pos[:, 0]) * my + d * mz
    assert np.allclose(ours, firmware)


def test_version_1_time_stamps_are_milliseconds(tmp_path):
    events = [(0xFFFF, "fixedFrequency", [("stateEstimate.z", "f"), ("pm.vbatMV", "H")])]
    records = [(0xFFFF, 1000 + 10 * k, [0.1 * k, 4000]) for k in range(4)]
    p = tmp_path / "v1"
    p.write_bytes(usd_bytes(events, records, version=1))
    log = read_log(p)
    assert np.allclose(log.t, [0.0, 0.01, 0.02, 0.03]) and log.meta["usd_version"] == "1"
    assert np.allclose(log.raw["stateEstimate.z"], [0.0, 0.1, 0.2, 0.3])
    assert not log.has("position")                     # z alone is not a position


def test_later_firmware_motor_variables(tmp_path):
    """Firmware after 2022-11: motor.m* (H) is the applied PWM, motor.m*req the request."""
    vars_ = [(f"motor.m{k}", "H") for k in range(1, 5)] + [(f"motor.m{k}req", "i")
                                                           for k in range(1, 5)]
    records = [(0xFFFF, 10_000 * k, [100, 200, 300, 400, -10, 70000, 3, 4]) for k in range(2)]
    p = tmp_path / "new"
    p.write_bytes(usd_bytes([(0xFFFF, "fixedFrequency", vars_)], records))
    log = read_log(p)
    assert np.allclose(log.signal("motor_pwm")[0] * 65535, [100, 200, 300, 400])
    assert np.allclose(log.signal("motor_command")[0] * 65535, [-10, 70000, 3, 4])


def test_crc_mismatch_names_file_expected_and_found(hand_built):
    data = bytearray(hand_built.read_bytes())
    data[40] ^= 0x01
    hand_built.write_bytes(bytes(data))
    with pytest.raises(LogCRCError) as e:
        read_log(hand_built)
    stored = struct.unpack("<I", bytes(data[-4:]))[0]
    found = zlib.crc32(bytes(data[:-4])) & 0xFFFFFFFF
    assert (e.value.expected, e.value.found, e.value.path) == (stored, found, str(hand_built))
    assert f"0x{stored:08x}" in str(e.value) and f"0x{found:08x}" in str(e.value)
    assert isinstance(e.value, LogFormatError)


def _damaged(tmp_path, name, data):
    p = tmp_path / name
    p.write_bytes(data)
    return p


def test_truncated_files(tmp_path, hand_built):
    data = hand_built.read_bytes()
    with pytest.raises(LogCRCError):                    # cut anywhere: the CRC no longer fits
        read_log(_damaged(tmp_path, "cut", data[:-30]))
    body = data[:-4][:-7]                               # cut inside the last record, CRC fixed
    fixed = body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF)
    with pytest.raises(LogFormatError, match="truncated record of event 'fixedFrequency'"):
        read_log(_damaged(tmp_path, "cut2", fixed))
    header = data[:60]                                  # cut inside the header, CRC fixed
    with pytest.raises(LogFormatError, match="truncated header|no NUL end"):
        read_log(_damaged(tmp_path, "cut3", header + struct.pack(
            "<I", zlib.crc32(header) & 0xFFFFFFFF)))
    with pytest.raises(LogFormatError, match="too short"):
        read_log(_damaged(tmp_path, "tiny", b"\xbc\x02\x00"))


@pytest.mark.parametrize("events, records, version, match", [
    ([(0xFFFF, "fixedFrequency", [("a.b", "f")])], [(0xFFFF, 1, [0.0])], 3, "version 3"),
    ([(0xFFFF, "fixedFrequency", [("a.b", "f")])], [(7, 1, None)], 2, "event id 7"),
    ([(0xFFFF, "fixedFrequency", [("a.b", "f")])], [(0xFFFF, 5, [0.0]), (0xFFFF, 5, [1.0])], 2,
     "expected increasing"),
    ([(0xFFFF, "fixedFrequency", [("a.b", "f")])], [(0xFFFF, 5, [0.0])], 2,
     "fewer than 2 'fixedFrequency' records"),
    ([(3, "other", [("a.b", "f")])], [(3, 5, [0.0]), (3, 6, [0.0])], 2,
     r"the events hold \{'other': 2\}"),
])
def test_bad_content(tmp_path, events, records, version, match):
    if records and records[0][2] is None:              # a record of an undeclared event
        data = usd_bytes(events, [], version, crc=False) + struct.pack("<HQ", 7, 1)
        data += struct.pack("<I", zlib.crc32(data) & 0xFFFFFFFF)
    else:
        data = usd_bytes(events, records, version=version if version != 3 else 2)
        if version == 3:
            data = data[:1] + struct.pack("<H", 3) + data[3:-4]
            data += struct.pack("<I", zlib.crc32(data) & 0xFFFFFFFF)
    with pytest.raises(LogFormatError, match=match):
        read_log(_damaged(tmp_path, "bad", data))


def test_unknown_type_and_magic(tmp_path):
    data = bytearray(usd_bytes([(0xFFFF, "fixedFrequency", [("a.b", "f")])],
                               [(0xFFFF, 1, [0.0]), (0xFFFF, 2, [0.0])], crc=False))
    data[data.index(b"(f)") + 1] = ord("d")            # a double: not a type of the firmware
    data += struct.pack("<I", zlib.crc32(bytes(data)) & 0xFFFFFFFF)
    with pytest.raises(LogFormatError, match=r"variable 'a.b\(d\)' is not 'name\(T\)'"):
        read_log(_damaged(tmp_path, "type", bytes(data)))
    with pytest.raises(LogFormatError, match="first byte 0x41"):
        read_log(_damaged(tmp_path, "magic", b"ABCDEFGHIJKL"), format="crazyflie-usd")


def decode(path):
    """This file's own decoder of a version-2 uSD log: {var: (type, values)}, ticks (us)."""
    data = Path(path).read_bytes()
    assert data[0] == 0xBC and struct.unpack("<I", data[-4:])[0] == zlib.crc32(data[:-4])
    version, n = struct.unpack_from("<HH", data, 1)
    assert version == 2 and n == 1
    eid, = struct.unpack_from("<H", data, 5)
    end = data.index(b"\0", 7)
    assert eid == 0xFFFF and data[7:end] == b"fixedFrequency"
    nvars, = struct.unpack_from("<H", data, end + 1)
    i, names = end + 3, []
    for _ in range(nvars):
        j = data.index(b"\0", i)
        names.append(data[i:j].decode())
        i = j + 1
    fmt = "<HQ" + "".join(s[-2] for s in names)
    rows = list(struct.iter_unpack(fmt, data[i:-4]))
    cols = list(zip(*rows))
    return {s[:-3]: (s[-2], np.array(cols[2 + k])) for k, s in enumerate(names)}, \
        np.array(cols[1])


def full_log(n=40):
    rng = np.random.default_rng(3)
    t = np.arange(n) * 0.01
    s = {"position": rng.normal(size=(n, 3)), "velocity": rng.normal(size=(n, 3)),
         "acceleration": rng.normal(size=(n, 3)), "roll": rng.uniform(-1, 1, n),
         "pitch": rng.uniform(-1, 1, n), "yaw": rng.uniform(-3, 3, n),
         "body_rates": rng.normal(size=(n, 3)), "motor_command": rng.uniform(0, 1, (n, 4)),
         "motor_pwm": rng.uniform(0, 1, (n, 4)), "battery_voltage": rng.uniform(3, 4.2, n),
         "thrust_command": rng.uniform(0, 1, n),
         "moment_command": rng.uniform(-0.1, 0.1, (n, 3))}
    return FlightLog("sim", "csv", t, s, {}, {})


def test_writer_writes_the_firmware_variables(tmp_path):
    log = full_log()
    path = write_log(log, tmp_path / "out.bin", "crazyflie-usd")
    variables, ticks = decode(path)
    assert np.array_equal(ticks, np.round(log.t * 1e6))
    typ, m1 = variables["motor.m1"]
    assert typ == "I" and np.array_equal(m1, np.round(log.signal("motor_command")[:, 0] * 65535))
    typ, mv = variables["pm.vbatMV"]
    assert typ == "H" and np.array_equal(mv, np.round(log.signal("battery_voltage") * 1000))
    assert np.allclose(variables["stateEstimate.pitch"][1], -np.degrees(log.signal("pitch")),
                       atol=1e-4)
    assert np.allclose(variables["stateEstimate.az"][1], log.signal("acceleration")[:, 2] / G,
                       atol=1e-5)
    assert np.allclose(variables["controller.r_pitch"][1], -log.signal("body_rates")[:, 1],
                       atol=1e-6)
    assert np.allclose(variables["controller.cmd_yaw"][1],
                       -log.signal("moment_command")[:, 2] * 65535, atol=1e-2)


def test_round_trip_to_the_format_precision(tmp_path):
    log = full_log()
    back = read_log(write_log(log, tmp_path / "out.bin", "crazyflie-usd"))
    assert set(back.signals) == set(log.signals)
    assert np.allclose(back.t, log.t, atol=1e-6)
    tol = {"motor_command": 0.5 / 65535, "motor_pwm": 0.5 / 65535, "battery_voltage": 5e-4,
           "thrust_command": 1e-6, "moment_command": 1e-6}
    for name in log.signals:
        err = np.abs(back.signal(name) - log.signal(name)).max()
        assert err <= tol.get(name, 1e-6 * max(1.0, np.abs(log.signal(name)).max())), name


def test_writer_refuses_what_the_format_cannot_hold(tmp_path):
    log = full_log()
    bad = FlightLog("sim", "csv", log.t, {"motor_command": log.signal("motor_command") * 2},
                    {}, {})
    with pytest.raises(LogSignalError, match="motor.m"):
        write_log(bad, tmp_path / "x.bin", "crazyflie-usd")
    with pytest.raises(LogSignalError, match="no signal a Crazyflie log carries"):
        write_log(FlightLog("e", "csv", log.t, {}, {}, {}), tmp_path / "y.bin", "crazyflie-usd")


# -- the real flights ----------------------------------------------------------------------
FILES = sorted(p for p in DATA.glob("*/*/E*_log*"))
flights, fit = airborne_segments, fit_gain


@pytest.fixture(scope="module")
def real():
    return {p.relative_to(DATA).as_posix(): read_log(p) for p in FILES}


def test_the_shipped_files(real):
    assert len(FILES) == 20
    assert (DATA / "LICENSE").read_text().startswith("MIT License")
    assert "doi:10.3390/data9060079" in (DATA / "README.md").read_text()


def test_real_logs_pass_the_crc_and_run_at_100_hz(real):
    """Every file's CRC passes (read_log checks it); the fixed-frequency records come at a
    nominal 100 Hz (101.15 Hz on E8's clock, 100.88 Hz on E9's) and regularly, except a few
    dropped records in the first 0.6 s, before take-off."""
    for name, log in real.items():
        assert log.meta["usd_version"] == "2", name
        steps = np.diff(log.t)
        rate = 1.0 / np.median(steps)
        assert 100.5 < rate < 101.5, (name, rate)
        late = steps[log.t[1:] > 1.0]
        assert late.max() < 1.1 * np.median(steps) and late.min() > 0.9 * np.median(steps), name


def test_real_flights_hover_near_half_a_metre(real):
    """Two airborne stretches per log (there and back along x), each near 0.52 m."""
    for name, log in real.items():
        segs = flights(log)
        assert len(segs) == 2, name
        for s in segs:
            assert 0.5 < np.median(log.signal("position")[s, 2]) < 0.56, name


def test_real_battery_and_motor_ranges(real):
    motor = {k: v for k, v in real.items() if k.startswith("motor_data")}
    assert len(motor) == 10
    for name, log in motor.items():
        v = log.signal("battery_voltage")
        assert 3.0 < v.min() and v.max() < 4.2, name          # one LiPo cell
        for sig in ("motor_command", "motor_pwm"):
            m = log.signal(sig)
            assert m.min() >= 0.0 and m.max() <= 1.0, (name, sig)
        hover = np.concatenate([log.signal("motor_command")[s] for s in flights(log)])
        assert 0.5 < np.median(hover) < 0.75, name


def test_real_pwm_is_the_firmware_battery_compensation(real):
    """pwm.m*_pwm is motor.m* compensated for the battery voltage by the firmware's formula
    (motors.c, motorsCompensateBatteryVoltage, written out here): units of motor, pwm and
    vbatMV agree to 20 of 65535 counts."""
    for name, log in real.items():
        if not log.has("motor_pwm"):
            continue
        vbat = log.signal("battery_voltage")
        for k in range(4):
            m = log.signal("motor_command")[:, k] * 65535
            thrust = m / 65536 * 60
            volts = -0.0006239 * thrust ** 2 + 0.088 * thrust
            pwm = np.minimum(volts / vbat, 1.0) * 65535
            on = m > 1000
            assert np.abs(pwm[on] - log.signal("motor_pwm")[on, k] * 65535).max() < 25, name


def test_real_velocity_and_acceleration_are_the_derivatives(real):
    """Low-passed at 2 Hz: velocity x is the derivative of position x (gain 1.04 +- 0.03),
    velocity z follows dz/dt with a gain of about 0.7 (the estimator's; docs/logs.md);
    acceleration (g -> m/s^2, gravity out) follows the derivative of velocity."""
    for name, log in real.items():
        if not log.has("velocity"):
            continue
        t = log.t
        dp = np.gradient(lowpass(log.signal("position")), t, axis=0)
        dv = np.gradient(lowpass(log.signal("velocity")), t, axis=0)
        v, a = lowpass(log.signal("velocity")), lowpass(log.signal("acceleration"))
        for s in flights(log):
            gain, corr = fit(dp[s, 0], v[s, 0])
            assert 0.95 < gain < 1.08 and corr > 0.97, (name, gain, corr)
            gain, corr = fit(dp[s, 2], v[s, 2])
            assert 0.5 < gain < 0.9 and corr > 0.8, (name, gain, corr)
            for k in (0, 2):
                gain, corr = fit(dv[s, k], a[s, k])
                assert 0.45 < gain < 1.35 and corr > 0.75, (name, k, gain, corr)


def test_real_roll_sign_from_the_lateral_acceleration(real):
    """In the yaw-rotated frame the lateral acceleration is -g sin(roll) (thrust ~ g at
    hover): pooled over the motor flights, gain 0.99 and correlation 0.83; a wrong roll sign
    gives -0.83."""
    ay, rhs = [], []
    for name, log in real.items():
        if not log.has("roll"):
            continue
        a = lowpass(log.signal("acceleration"))
        phi, psi = lowpass(log.signal("roll")), lowpass(np.unwrap(log.signal("yaw")))
        lateral = -np.sin(psi) * a[:, 0] + np.cos(psi) * a[:, 1]
        for s in flights(log):
            ay.append(lateral[s])
            rhs.append(-G * np.sin(phi[s]))
    gain, corr = fit(np.concatenate(rhs), np.concatenate(ay))
    assert 0.9 < gain < 1.1 and corr > 0.75, (gain, corr)


def test_real_gyro_signs_from_the_position(real):
    """The integrated pitch rate q follows x''/g (a forward tilt accelerates forward) and the
    integrated roll rate p follows -y''/g, band-passed 0.2-2 Hz: q = -controller.r_pitch."""
    for name, log in real.items():
        if not log.has("body_rates"):
            continue
        t = log.t
        angle = bandpass(cumulative_trapezoid(log.signal("body_rates"), t, axis=0, initial=0))
        acc = np.gradient(np.gradient(bandpass(log.signal("position")), t, axis=0), t, axis=0)
        for s in flights(log):
            assert np.corrcoef(angle[s, 1], acc[s, 0] / G)[0, 1] > 0.5, name
            assert np.corrcoef(angle[s, 0], -acc[s, 1] / G)[0, 1] > 0.5, name


def _hover_medians(log, name):
    segs = flights(log)
    return np.median(np.concatenate([log.signal(name)[s] for s in segs]), axis=0)


def test_real_controller_logs_agree_with_the_motor_logs(real):
    """Different flights of the same drones: the controller's thrust command is the mean
    motor command (within 3 %), and its moment commands have the signs (and within a factor
    2 the sizes) of the motor splits m_x = (-M1 - M2 + M3 + M4)/4, m_y = (-M1 + M2 + M3 - M4)/4,
    m_z = -(M1 - M2 + M3 - M4)/4, which the legacy mixer implies: the motor order, the
    mixer signs and moment_command's definition checked against data."""
    groups = {}
    for name, log in real.items():
        folder = name.split("/")[1]
        drone = name.split("/")[2][:2]
        groups.setdefault((drone, folder), {"motor": [], "ctrl": []})
        if log.has("motor_command"):
            m = _hover_medians(log, "motor_command")
            split = np.array([(-m[0] - m[1] + m[2] + m[3]) / 4, (-m[0] + m[1] + m[2] - m[3]) / 4,
                              -(m[0] - m[1] + m[2] - m[3]) / 4])
            groups[(drone, folder)]["motor"].append(np.r_[m.mean(), split])
        else:
            groups[(drone, folder)]["ctrl"].append(np.r_[_hover_medians(log, "thrust_command"),
                                                         _hover_medians(log, "moment_command")])
    assert len(groups) == 4
    for key, g in groups.items():
        motor, ctrl = np.median(g["motor"], axis=0), np.median(g["ctrl"], axis=0)
        assert abs(ctrl[0] - motor[0]) < 0.03 * motor[0], (key, ctrl[0], motor[0])
        for k in (1, 2, 3):
            if min(abs(motor[k]), abs(ctrl[k])) > 0.01:
                assert np.sign(motor[k]) == np.sign(ctrl[k]), (key, k, motor[k], ctrl[k])
                assert 0.5 < ctrl[k] / motor[k] < 2.0, (key, k, motor[k], ctrl[k])
        assert np.sign(motor[3]) == np.sign(ctrl[3]) == -1, key     # the yaw trim, always

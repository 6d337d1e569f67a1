"""Issue 33, third hostile pass: inputs of the kinds the issue lists, other than its examples.

- a PX4 ULog whose topic lacks its time stamp or the fields the reader needs, holds stamps
  beyond an int64, or NaN rotor parameters: a LogFormatError naming the topic (were raw
  KeyError and ValueError, or a log silently cut where the stamps wrapped);
- payload profiles: ``carried``, the time of ``on_board`` and ``sample``, and the name of a
  move or drop checked (were raw TypeError, AttributeError, ValueError, OverflowError; a
  time of None or NaN gave an answer);
- identification: a moment command beyond full scale, the mixer's saturated commands, and a
  yaw no flight turns are refused in the log's terms (an answer was given, exit 0).
"""
import struct

import numpy as np
import pytest
from test_harden_identify import hover_log

from quadcog.errors import IdentificationError, InputError, LogFormatError
from quadcog.identification import identify
from quadcog.logs import FlightLog, read_log
from quadcog.logs.ulog import ULOG_MAGIC
from quadcog.sim.timeline import PayloadEvent, PayloadProfile
from quadcog.vehicles.payload import Payload


# -- ULog: what the reader needs of a topic, checked ----------------------------------------
def _message(kind, payload):
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _ulog(path, topics, params=(), stamp="uint64_t timestamp", n=20, step_us=10_000):
    """A ULog written here, byte by byte (the format's spec, not quadcog's writer): topics
    ``{name: [(ctype, field, count, value)]}`` of float fields, the time stamp declared as
    ``stamp``; ``params`` ``(name, value)`` of float parameters."""
    out = bytearray(ULOG_MAGIC + bytes([1]) + struct.pack("<Q", 0))
    out += _message("B", bytes(40))
    for name, value in params:
        key = f"float {name}".encode()
        out += _message("P", bytes([len(key)]) + key + struct.pack("<f", value))
    stamp_format = "<Q" if stamp.startswith("uint64_t") else "<d"
    for msg_id, (name, fields) in enumerate(topics.items()):
        spec = ";".join([stamp] + [f"{c} {f}" for c, f, _, _ in fields]) + ";"
        out += _message("F", f"{name}:{spec}".encode())
    for msg_id, name in enumerate(topics):
        out += _message("A", bytes([0]) + struct.pack("<H", msg_id) + name.encode())
    for k in range(n):
        for msg_id, (name, fields) in enumerate(topics.items()):
            stamp_value = 1_000_000 + k * step_us
            body = struct.pack("<H", msg_id) + struct.pack(
                stamp_format, stamp_value if stamp_format == "<Q" else float(stamp_value))
            for _, _, count, value in fields:
                body += struct.pack(f"<{count}f", *([value] * count))
            out += _message("D", body)
    path.write_bytes(bytes(out))
    return path


POSITION = [("float", "x", 1, 0.0), ("float", "y", 1, 0.0), ("float", "z", 1, -0.5)]
ROTORS = [(f"CA_ROTOR{i}_{k}", v) for i, (x, y) in enumerate([(1, 1), (-1, -1), (1, -1), (-1, 1)])
          for k, v in (("PX", 0.1 * x), ("PY", 0.1 * y), ("KM", 0.05 * (-1) ** i))]


def test_the_hand_written_ulog_is_read(tmp_path):
    log = read_log(_ulog(tmp_path / "ok.ulg", {"vehicle_local_position": POSITION}))
    assert np.allclose(log.signal("position")[:, 2], 0.5) and log.n_samples == 20


@pytest.mark.parametrize("what, kw, message", [
    ("no time stamp", dict(topics={"vehicle_local_position": POSITION},
                           stamp="uint64_t time"), r"vehicle_local_position has no field "
                                                   r"'timestamp'"),
    ("a float time stamp", dict(topics={"vehicle_local_position": POSITION},
                                stamp="double timestamp"), r"'timestamp' of type float64"),
    ("stamps past an int64", dict(topics={"vehicle_local_position": POSITION},
                                  step_us=2 ** 59), r"time stamp \d+ us is beyond"),
    ("a quaternion of two", dict(topics={"vehicle_local_position": POSITION,
                                         "vehicle_attitude": [("float[2]", "q", 2, 0.5)]}),
     r"vehicle_attitude lacks the field\(s\) q\[2\], q\[3\]"),
    ("two motor controls", dict(topics={"vehicle_local_position": POSITION,
                                        "actuator_motors": [("float[2]", "control", 2, 0.5)]}),
     r"actuator_motors lacks the field\(s\) control\[2\], control\[3\]"),
])
def test_a_ulog_topic_without_what_the_reader_needs_is_a_format_error(tmp_path, what, kw,
                                                                      message):
    """Were raw KeyErrors; stamps past 2**63 us wrapped in the int64 steps and the samples
    after the wrap were silently left out."""
    with pytest.raises(LogFormatError, match=message):
        read_log(_ulog(tmp_path / "bad.ulg", **kw))


def test_ulog_rotor_parameters_that_are_not_numbers_leave_the_order_unknown(tmp_path):
    """A NaN CA_ROTOR0_PX was int(nan): a raw ValueError. Now the rotor order is unknown
    (said in meta), so the motor outputs are not assigned to rotors."""
    params = [(k, float("nan") if k == "CA_ROTOR0_PX" else v) for k, v in ROTORS]
    params += [("CA_ROTOR_COUNT", 4.0)]
    motors = [("float[4]", "control", 4, 0.5)]
    log = read_log(_ulog(tmp_path / "nan.ulg", {"vehicle_local_position": POSITION,
                                                 "actuator_motors": motors}, params))
    assert "not finite" in log.meta["rotor_order"] and not log.has("motor_command")
    # a NaN output function is no motor's: the channels' own order is kept
    outputs = [("float[4]", "output", 4, 1500.0)]
    log = read_log(_ulog(tmp_path / "pwm.ulg", {"vehicle_local_position": POSITION,
                                                 "actuator_outputs": outputs},
                         [("PWM_MAIN_FUNC1", float("nan"))]))
    assert np.allclose(log.signal("motor_pwm"), 0.5)


# -- payload profiles: every argument checked ------------------------------------------------
ATTACH = dict(t=1.0, action="attach", name="box", mass=0.005, position=[0.01, 0.0, 0.0])
NOT_A_TIME = [None, "abc", b"1", 1j, 10 ** 400, float("nan"), float("inf"), True, [[1.0]],
              {"t": 1}]


@pytest.mark.parametrize("t", NOT_A_TIME, ids=repr)
def test_payload_times_that_are_not_times_are_refused(t):
    """on_board(None) and sample('abc') were raw TypeError or ValueError; sample(None) and
    sample(nan) answered with the box on board, on_board(nan) with nothing."""
    profile = PayloadProfile([ATTACH])
    with pytest.raises(InputError, match=r"^t"):
        profile.on_board(t)
    if not isinstance(t, list):
        with pytest.raises(InputError, match=r"^t"):
            profile.sample(t)
    with pytest.raises(InputError, match=r"^t\[1\]"):
        profile.sample([0.0, float("nan"), 2.0])


@pytest.mark.parametrize("carried", [None, 5, "box", {"a": 1}, [None], [1.5], ["box"],
                                     [object()]],
                         ids=lambda v: repr(v).split(" at 0x")[0])   # no address: the same ids in every process
def test_payloads_carried_that_are_not_payloads_are_refused(carried):
    """Were raw TypeError (not iterable) or AttributeError (no .name)."""
    with pytest.raises(InputError, match=r"^carried"):
        PayloadProfile([ATTACH], carried=carried)


def test_payloads_carried_are_taken_as_payloads_of_different_names():
    box = Payload(0.01, (0.0, 0.0, 0.0), name="box")
    profile = PayloadProfile([], carried=[{"mass": 0.01, "position": [0, 0, 0], "name": "b"}])
    assert profile.carried == (Payload(0.01, (0.0, 0.0, 0.0), name="b"),)
    with pytest.raises(InputError, match="different names"):
        PayloadProfile([], carried=[box, box])


@pytest.mark.parametrize("name", [None, [], ["box"], 5, ""], ids=repr)
@pytest.mark.parametrize("action", ["move", "drop"])
def test_a_move_or_drop_names_its_payload_with_a_string(name, action):
    """A list as the name of a move or drop was a raw 'unhashable type' TypeError."""
    event = dict(t=2.0, action=action, name=name)
    if action == "move":
        event["position"] = [0.0, 0.0, 0.0]
    with pytest.raises(InputError, match="name: expected a non-empty string"):
        PayloadProfile([ATTACH, event])


def test_a_move_whose_ramp_ends_past_the_float_range_is_refused():
    """t + ramp overflowed to inf: times() held inf."""
    with pytest.raises(InputError, match="ramp"):
        PayloadEvent(t=1e308, action="move", name="box", position=(0, 0, 0), ramp=1e308)


# -- identification: moment commands and yaw -------------------------------------------------
def _commanded(moment, yaw=None):
    """The hover log with thrust_command and moment_command instead of motor outputs."""
    full = hover_log(full=True)
    n = full.n_samples
    s = {k: np.array(v) for k, v in full.signals.items() if k != "motor_command"}
    s["thrust_command"] = full.signal("motor_command").mean(axis=1)
    s["moment_command"] = np.tile(np.asarray(moment, float), (n, 1))
    if yaw is not None:
        s["yaw"] = np.full(n, yaw)
    return FlightLog("hover.csv", "csv", full.t, s, {}, {})


@pytest.mark.parametrize("method", ["static", "regression"])
@pytest.mark.parametrize("moment, message", [
    ([1e200, 0.0, 0.0], r"'moment_command_x' is 1e\+200.*beyond full scale of a motor"),
    ([0.0, -3.0, 0.0], r"'moment_command_y' is -3.*beyond full scale"),
    ([0.9, 0.0, 0.0], r"the command of rotor \d that thrust_command and moment_command give "
                      r"through the mixer is at full scale"),
])
def test_moment_commands_beyond_the_motors_are_refused(method, moment, message):
    """A moment command of 1e200 gave y_G = 32.5 mm 'determined', exit 0: the mixer clipped
    two rotors to full and two to off, and nothing looked at the commands it made."""
    with pytest.raises(IdentificationError, match=message):
        identify(_commanded(moment), method=method)


def test_moment_commands_within_the_motors_are_identified():
    res = identify(_commanded([0.0, 0.0, 0.0]), method="static")
    assert res.mass == pytest.approx(0.027, rel=1e-6)


@pytest.mark.parametrize("yaw", [1e200, -1e9])
def test_a_yaw_no_flight_turns_is_refused(yaw):
    """A yaw of 1e200 rad was accepted (only cos and sin of it are used)."""
    with pytest.raises(IdentificationError, match=r"'yaw_rad' is .* rad.*gyroscope"):
        identify(_commanded([0.0, 0.0, 0.0], yaw=yaw))
    identify(_commanded([0.0, 0.0, 0.0], yaw=50.0))      # unwrapped over a few turns: fine


# -- CSV: a byte-order mark -------------------------------------------------------------------
def test_a_csv_log_with_a_byte_order_mark_is_read(tmp_path):
    """A spreadsheet's "CSV UTF-8" starts with a byte-order mark: it was read as the start of
    the first name, and the log refused with "no time column 't_s'; columns are \\ufefft_s"."""
    text = "t_s,position_x_m,position_y_m,position_z_m\n0,0,0,0\n0.01,0,0,0.5\n"
    p = tmp_path / "bom.csv"
    p.write_bytes(b"\xef\xbb\xbf" + text.encode())
    log = read_log(p)
    assert np.array_equal(log.t, [0.0, 0.01]) and log.signal("position")[1, 2] == 0.5
    p.write_bytes(b"\xef\xbb\xbf" + (text + "0.02,0,0,x\n").encode())    # the cell by cell path
    with pytest.raises(LogFormatError, match=r"line 4, column 'position_z_m': 'x' is not"):
        read_log(p)

"""Ninth hostile pass on quadcog.logs: values no firmware logs, damage pyulog cannot leave,
and every table source held to one check of its cells.

- Crazyflie uSD: ``controller.cmd_thrust`` outside the firmware's 0..65535, moment commands
  beyond its int16, body rates beyond any gyroscope's full scale (``gyro.*`` in deg/s,
  ``controller.r_*`` in rad/s) and a battery voltage outside 0..65.535 V were read (a thrust
  command of 1e30 became thrust_command 1.5e25); now refused with variable, value, record
  and time, and the writer refuses what its reader would. A signalling NaN leaked numpy's
  "invalid value in cast" warning before its refusal.
- ULog: a NaN attitude quaternion was reported as a norm "after interpolation"; now the
  attitude signals are left out and the logged sample is named (field, index, time stamp).
  A ``CA_ROTOR_COUNT`` that is NaN, or of another airframe, fell back to PX4's quad X: now the
  rotor order is unknown and no motor output is read as quadcog's rotors. A message pyulog
  takes for damage (type 0) in the header made pyulog rescan the file for ever (a 3 kB log
  with one byte changed never returned); rotor and output parameters of a damaged type
  (bytes) raised ValueError and TypeError.
- Tables: a Parquet cell below the normal range of its type (a subnormal) or an integer
  beyond 2^53 was read with its digits lost (a CSV cell below the range was already
  refused); repeated Parquet column names gave pyarrow's multi-line message.
- FlightLog: text, bools, complex numbers, dates and masked entries were taken as numbers
  ("1", True, the real part, days), a time span beyond the float range passed with numpy's
  overflow warning, a source of None became 'None', raw keys 1 and '1' became one name.
- Parquet pages carry a CRC-32 the reader checks (a changed byte was read as another value);
  a schema name that is not UTF-8 raised UnicodeDecodeError; the table writers refuse a
  subnormal time (written as 0 it repeated the time before).
- The public functions of the format modules and of quadcog.logs.checks check their
  arguments: read_table(True, 'csv') read and closed the standard output (file descriptor
  1), readers opened str(None), writers raised AttributeError, table_columns('roll') read
  the letters, quaternion_to_euler of a zero quaternion answered, fit_gain of a constant
  answered nan, lowpass of 5 samples raised scipy's padlen error.
"""
import math
import re
import signal
import struct
import warnings
import zlib

import numpy as np
import pytest
from test_harden_logs_6 import _one_bad, _ulog, _usd

from quadcog.errors import InputError, LogError, LogFormatError, LogSignalError
from quadcog.logs import FlightLog, checks, crazyflie, limits, read_log, samples, signals, table, ulog, write_log


@pytest.fixture(autouse=True)
def _no_warnings():
    """Every hostile input here must give a typed error or an answer, never a warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


# -- Crazyflie uSD: every converted variable within what the firmware logs ------------------
XYZ = [("stateEstimate.x", "f"), ("stateEstimate.y", "f"), ("stateEstimate.z", "f")]
GYRO = [("gyro.x", "f"), ("gyro.y", "f"), ("gyro.z", "f")]
RATES = [("controller.r_roll", "f"), ("controller.r_pitch", "f"), ("controller.r_yaw", "f")]
MOMENTS = [("controller.cmd_roll", "f"), ("controller.cmd_pitch", "f"),
           ("controller.cmd_yaw", "f")]
W_MAX = math.radians(4000.0)


@pytest.mark.parametrize("variables, edge, bad, expected", [
    ([("controller.cmd_thrust", "f")] + XYZ, 65535.0, 65536.0, "the firmware's thrust"),
    ([("controller.cmd_thrust", "f")] + XYZ, 0.0, -5.0, "the firmware's thrust"),
    ([("controller.cmd_thrust", "f")] + XYZ, 65535.0, 1e30, "the firmware's thrust"),
    (MOMENTS + XYZ, -32768.0, -40000.0, "the firmware's int16 moment command"),
    (MOMENTS[::-1] + XYZ, 32768.0, 1e9, "the firmware's int16 moment command"),
    (GYRO + XYZ, 4000.0, 4001.0, r"a gyroscope's rate \(deg/s"),
    (GYRO[::-1] + XYZ, -4000.0, -1e30, r"a gyroscope's rate \(deg/s"),
    (RATES + XYZ, float(np.float32(W_MAX * (1 - 1e-6))), 1e4, r"a gyroscope's rate \(rad/s"),
    ([("pm.vbat", "f")] + XYZ, 4.2, -4.0, r"a battery voltage \(V\)"),
    ([("pm.vbat", "f")] + XYZ, 65.5, 3e38, r"a battery voltage \(V\)"),
    ([("pm.vbatMV", "f")] + XYZ, 4200.0, 70000.0, r"a battery voltage \(mV\)"),
])
def test_usd_commands_rates_and_voltages_beyond_the_firmware_are_refused(tmp_path, variables,
                                                                         edge, bad, expected):
    """Were read as numbers (cmd_thrust 1e30 -> thrust_command 1.5e25, a gyro of 1e30 deg/s,
    a battery of -4 V); at the firmware's own limits they are read."""
    good = [0.0] * len(variables)
    ok = read_log(_one_bad(tmp_path / "ok.bin", variables, good, edge))
    assert ok.raw[variables[0][0]][2] == np.float32(edge)
    p = _one_bad(tmp_path / "bad.bin", variables, good, bad)
    name = variables[0][0]
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(p))}: variable "
                                             rf"'{re.escape(name)}' of event 'fixedFrequency' "
                                             rf"is {re.escape(repr(float(np.float32(bad))))} in "
                                             rf"record 2 \(t = 0.02 s\); expected {expected}"):
        read_log(p)


def _signals_log(**signals):
    n = 5
    return FlightLog("memory", "csv", np.arange(n) * 0.01,
                     {k: np.broadcast_to(v, (n,) + np.shape(v)) for k, v in signals.items()},
                     {}, {})


@pytest.mark.parametrize("signals, variable", [
    (dict(thrust_command=1.0001), "controller.cmd_thrust"),
    (dict(thrust_command=-0.1), "controller.cmd_thrust"),
    (dict(moment_command=[0.3, 0.0, 0.0]), "controller.cmd_roll"),
    (dict(moment_command=[0.0, 0.0, -0.6]), "controller.cmd_yaw"),
    (dict(body_rates=[0.0, -W_MAX * 1.001, 0.0]), "controller.r_pitch"),
])
def test_usd_writer_refuses_what_its_reader_refuses(tmp_path, signals, variable):
    """What write_log writes as a uSD log, read_log reads (were written, then refused on
    reading); the limits themselves are written and read back."""
    for name, value in signals.items():
        edge = {"thrust_command": 1.0, "moment_command": [0.25, -0.25, 0.5],
                "body_rates": [W_MAX * 0.999, 0.0, 0.0]}[name]
        back = read_log(write_log(_signals_log(**{name: edge}), tmp_path / "ok.bin",
                                  "crazyflie-usd"))
        assert np.allclose(back.signal(name)[0], edge, rtol=1e-6)
    with pytest.raises(LogSignalError, match=rf"{re.escape(variable)} is .* at sample 0; a "
                                             r"Crazyflie log holds"):
        write_log(_signals_log(**signals), tmp_path / "bad.bin", "crazyflie-usd")


def test_usd_signalling_nan_is_refused_without_a_numpy_warning(tmp_path):
    """A float32 signalling NaN (0x7fa00000) warned 'invalid value encountered in cast'
    before the reader refused it."""
    p = _usd(tmp_path / "s.bin", XYZ, [[0.0, 0.0, 0.0]] * 3)
    data = bytearray(p.read_bytes())
    at = data.index(struct.pack("<HQ", 0xFFFF, 10_000)) + 10       # record 1, its x
    data[at:at + 4] = struct.pack("<I", 0x7FA00000)
    body = bytes(data[:-4])
    p.write_bytes(body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF))
    with pytest.raises(LogFormatError, match=r"'stateEstimate.x' .* is nan in record 1"):
        read_log(p)


# -- ULog ------------------------------------------------------------------------------------
LP = "vehicle_local_position:uint64_t timestamp;float x;float y;float z;"
ATT = "vehicle_attitude:uint64_t timestamp;float[4] q;"
AM = "actuator_motors:uint64_t timestamp;float[4] control;"


def _attitude_ulog(path, q_of):
    return _ulog(path, [LP, ATT], [("vehicle_local_position", "<Qfff",
                                    lambda k: (0.0, 0.0, -1.0)),
                                   ("vehicle_attitude", "<Q4f", q_of)])


def test_ulog_nan_quaternion_is_named_as_logged_and_the_attitude_left_out(tmp_path):
    """Was 'vehicle_attitude.q is not a unit quaternion (norm nan after interpolation)': the
    whole log refused in terms of the resampled signal. Now, as for every estimate PX4 logs
    NaN before it is valid, the attitude signals are left out and the logged sample is named:
    its field, index and time stamp."""
    p = _attitude_ulog(tmp_path / "q.ulg",
                       lambda k: (1.0, float("nan") if k == 7 else 0.0, 0.0, 0.0))
    log = read_log(p)
    assert log.has("position") and not any(log.has(n) for n in ("roll", "pitch", "yaw"))
    assert log.meta["signals_dropped"] == (
        "roll, pitch, yaw (vehicle_attitude.q[1] is nan in its sample 7, time stamp 1070000 "
        "us: 1 of 20 samples not finite)")
    with pytest.raises(LogSignalError, match=r"left out roll, pitch, yaw \(vehicle_attitude"
                                             r"\.q\[1\] is nan in its sample 7"):
        log.signal("pitch")
    ok = read_log(_attitude_ulog(tmp_path / "ok.ulg", lambda k: (1.0, 0.0, 0.0, 0.0)))
    assert np.allclose(ok.signal("roll"), 0.0) and "signals_dropped" not in ok.meta


def _motor_ulog(path, params):
    return _ulog(path, [LP, AM], [("vehicle_local_position", "<Qfff",
                                   lambda k: (0.0, 0.0, -1.0)),
                                  ("actuator_motors", "<Q4f", lambda k: (0.1, 0.2, 0.3, 0.4))],
                 params=params)


ROTORS = [("float", f"CA_ROTOR{i}_{k}", struct.pack("<f", v))
          for i, (x, y) in enumerate([(1, 1), (-1, -1), (1, -1), (-1, 1)])
          for k, v in (("PX", 0.1 * x), ("PY", 0.1 * y), ("KM", 0.05 * (-1) ** i))]


@pytest.mark.parametrize("count, note", [
    (("float", struct.pack("<f", float("nan"))), "CA_ROTOR_COUNT is nan, not a rotor count"),
    (("float", struct.pack("<f", 4.5)), "CA_ROTOR_COUNT is 4.5, not a rotor count"),
    (("int32_t", struct.pack("<i", 6)), "CA_ROTOR_COUNT = 6: not a quadrotor"),
    (("int32_t", struct.pack("<i", 0)), "CA_ROTOR_COUNT = 0: not a quadrotor"),
])
def test_ulog_rotor_count_that_is_not_four_leaves_the_rotor_order_unknown(tmp_path, count,
                                                                          note):
    """A logged CA_ROTOR_COUNT that is NaN or another airframe's fell back to PX4's quad X
    numbering, taking control[0..3] as quadcog's rotors. PX4's quad X is assumed only where
    the count is not logged; with a count of 4 the CA_ROTOR positions order the motors."""
    ctype, packed = count
    log = read_log(_motor_ulog(tmp_path / "c.ulg", ROTORS + [(ctype, "CA_ROTOR_COUNT",
                                                              packed)]))
    assert log.meta["rotor_order"] == f"{note}: rotor order unknown (motor outputs not read)"
    assert not log.has("motor_command") and log.has("position")
    absent = read_log(_motor_ulog(tmp_path / "a.ulg", ROTORS))
    assert absent.meta["rotor_order"].startswith("assumed PX4 quad X")
    assert np.allclose(absent.signal("motor_command"), [0.1, 0.4, 0.2, 0.3])
    four = read_log(_motor_ulog(tmp_path / "4.ulg", ROTORS + [
        ("int32_t", "CA_ROTOR_COUNT", struct.pack("<i", 4))]))
    assert four.meta["rotor_order"] == "from CA_ROTOR{i}_PX/PY"


@pytest.mark.parametrize("key", ["CA_ROTOR0_PX", "CA_ROTOR2_PY", "CA_ROTOR3_KM"])
def test_ulog_rotor_parameters_of_a_damaged_type_leave_the_order_unknown(tmp_path, key):
    """A parameter whose type a damaged byte turned into text (pyulog gives str, or bytes for
    a type it does not know) raised ValueError ('could not convert string to float') or
    TypeError (the unary minus of a str)."""
    params = [(("char[4]" if name == key else ctype), name, packed)
              for ctype, name, packed in ROTORS]
    params += [("int32_t", "CA_ROTOR_COUNT", struct.pack("<i", 4))]
    log = read_log(_motor_ulog(tmp_path / "d.ulg", params))
    assert log.meta["rotor_order"].startswith(f"CA_ROTOR parameters not numbers ({key} is '")
    assert not log.has("motor_command")


def test_ulog_output_function_of_a_damaged_type_assigns_no_motor(tmp_path):
    """PWM_MAIN_FUNC1 of type char raised ValueError; like a NaN function it assigns no motor
    (the channels' own order is kept)."""
    ao = "actuator_outputs:uint64_t timestamp;float[4] output;"
    p = _ulog(tmp_path / "f.ulg", [LP, ao],
              [("vehicle_local_position", "<Qfff", lambda k: (0.0, 0.0, -1.0)),
               ("actuator_outputs", "<Q4f", lambda k: (1500.0,) * 4)],
              params=[("char[4]", "PWM_MAIN_FUNC1", b"e\0\0\0")])
    assert np.allclose(read_log(p).signal("motor_pwm"), 0.5)


class _Deadline(Exception):
    pass


def _raise_deadline(signum, frame):
    raise _Deadline()


def test_ulog_message_pyulog_takes_for_damage_is_refused_before_pyulog_loops(tmp_path):
    """The flag-bits message's type byte set to 0: pyulog takes the message for damage,
    rescans from the next byte, reads a header whose size runs past the end and seeks back
    before it: for ever (the reader never returned). Refused first, naming the byte."""
    log = FlightLog("x", "csv", np.arange(6) * 0.01, {"position": np.zeros((6, 3))}, {}, {})
    p = write_log(log, tmp_path / "x.ulg", "ulog")
    data = bytearray(p.read_bytes())
    assert data[18] == ord("B")
    data[18] = 0
    p.write_bytes(bytes(data))
    old = signal.signal(signal.SIGALRM, _raise_deadline)
    signal.alarm(60)
    try:
        with pytest.raises(LogFormatError, match=r"damaged ULog: the message at byte 16 of the "
                                                 r"definitions section has type 0x00 and 40 "
                                                 r"bytes"):
            read_log(p)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@pytest.mark.parametrize("kind, size", [(0, 4), (ord("X"), 0), (ord("X"), 10_001)])
def test_ulog_data_section_message_pyulog_takes_for_damage_is_refused(tmp_path, kind, size):
    """In the data section pyulog flags the same messages as damage (and the reader refused
    the file after pyulog rescanned it byte by byte); refused at once, by byte. A message of
    a type pyulog does not know, of a sane size, is skipped as the format says."""
    p = _ulog(tmp_path / "ok.ulg")
    skipped = p.read_bytes() + struct.pack("<HB", 4, ord("X")) + bytes(4)
    p.write_bytes(skipped)
    assert read_log(p).n_samples == 20
    data = _ulog(tmp_path / "d.ulg").read_bytes()
    at = len(data)
    p.write_bytes(data + struct.pack("<HB", size, kind) + bytes(size))
    with pytest.raises(LogFormatError, match=rf"the message at byte {at} of the data section "
                                             rf"has type 0x{kind:02x} and {size} bytes"):
        read_log(p)


def test_ulog_signalling_nan_is_dropped_without_a_numpy_warning(tmp_path):
    """A float32 signalling NaN in a topic warned 'invalid value encountered in cast' when
    interpolated; it is dropped and counted like any NaN."""
    p = _ulog(tmp_path / "s.ulg", topics=(("vehicle_local_position", "<Qfff",
                                           lambda k: (123.0 if k == 3 else 0.0, 0.0, -1.0)),))
    data = bytearray(p.read_bytes())            # the marker 123.0 -> the signalling bits
    at = data.index(struct.pack("<f", 123.0))
    data[at:at + 4] = struct.pack("<I", 0x7FA00000)
    p.write_bytes(bytes(data))
    log = read_log(p)
    assert not log.has("position")
    assert log.meta["signals_dropped"].startswith("position (")


# -- tables: one check of the cells for every source -----------------------------------------
pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")


def _parquet(path, columns, names=None):
    t = pa.Table.from_arrays([pa.array(c) for c in columns],
                             names=names or ["t_s"] + [f"c{i}" for i in range(len(columns) - 1)])
    pq.write_table(t, path)
    return path


T = np.arange(5) * 0.01


@pytest.mark.parametrize("column, shown, dtype", [
    (np.array([0, 1e-310, 0, 0, 0]), "1e-310", "float64"),
    (np.array([0, -5e-324, 0, 0, 0]), "-5e-324", "float64"),
    (np.array([0, 1e-40, 0, 0, 0], np.float32), repr(float(np.float32(1e-40))), "float32"),
    (np.array([0, 1e-6, 0, 0, 0], np.float16), repr(float(np.float16(1e-6))), "float16"),
])
def test_parquet_subnormal_cells_are_refused_as_csv_cells_are(tmp_path, column, shown, dtype):
    """A CSV cell below the float range was refused; the same value in a Parquet file was
    read with its digits lost. Checked in the type the file holds: a float32 subnormal is
    one too, though float64 would hold it."""
    p = _parquet(tmp_path / "s.parquet", [T, column], ["t_s", "roll_rad"])
    with pytest.raises(LogFormatError, match=rf"column 'roll_rad', data row 2: "
                                             rf"{re.escape(shown)} is below the range of a "
                                             rf"{dtype} \(a subnormal"):
        read_log(p)
    ok = _parquet(tmp_path / "ok.parquet", [T, column * 0 + np.finfo(column.dtype).tiny],
                  ["t_s", "roll_rad"])
    assert read_log(ok).signal("roll")[1] == float(np.finfo(column.dtype).tiny)


@pytest.mark.parametrize("column", [np.array([0, 2 ** 53 + 1, 0, 0, 0], np.int64),
                                    np.array([0, 2 ** 64 - 1, 0, 0, 0], np.uint64),
                                    np.array([0, -2 ** 63, 0, 0, 0], np.int64)])
def test_parquet_integers_a_float_cannot_hold_are_refused(tmp_path, column):
    """An integer cell beyond 2^53 was read with its last digits changed (2^53 + 1 as 2^53)."""
    p = _parquet(tmp_path / "i.parquet", [T, column], ["t_s", "roll_rad"])
    with pytest.raises(LogFormatError, match=rf"column 'roll_rad', data row 2: the integer "
                                             rf"{int(column[1])} is beyond 2\^53"):
        read_log(p)
    ok = _parquet(tmp_path / "ok.parquet", [T, np.array([0, 2 ** 53, 0, 0, 0])],
                  ["t_s", "roll_rad"])
    assert read_log(ok).signal("roll")[1] == 2.0 ** 53


def test_parquet_repeated_column_names_are_refused_in_one_line(tmp_path):
    """pyarrow reads the table, then cannot tell its columns apart: its message ran over
    several lines. Refused by name, as a CSV header's repeated names are."""
    p = _parquet(tmp_path / "r.parquet", [T, np.zeros(5), np.ones(5)],
                 ["t_s", "roll_rad", "roll_rad"])
    with pytest.raises(LogFormatError) as e:
        read_log(p)
    assert str(e.value) == (f"{p}: repeated column names ['roll_rad']; expected each column "
                            "once")


# -- FlightLog: numbers are numbers ----------------------------------------------------------
@pytest.mark.parametrize("what, value, message", [
    ("text", ["0", "1"], r"x: time\[0\]: expected a real number, got '0'"),
    ("bools", np.array([False, True]), "x: time: expected a numeric array of real numbers, "
                                       "not booleans"),
    ("complex", np.array([0, 1 + 1j]), "not complex numbers"),
    ("dates", np.array(["2020-01-01", "2020-01-02"], "datetime64[D]"), "not dtype datetime64"),
    ("durations", np.array([0, 1], "timedelta64[s]"), "not dtype timedelta64"),
    ("masked", np.ma.masked_array([0.0, 1.0, 2.0], mask=[0, 1, 0]), "1 masked entries"),
    ("span past the float range", [-1e308, 1e308], r"time runs from -1e\+308 s to 1e\+308 s, "
                                                    "a span beyond the range of a float"),
])
def test_flightlog_time_is_real_numbers(what, value, message):
    """Text and bools were taken as numbers, the imaginary part dropped (numpy's
    ComplexWarning), dates read as days, a masked entry's data used, steps of inf passed."""
    with pytest.raises(LogFormatError, match=message):
        FlightLog("x", "csv", value, {}, {}, {})


@pytest.mark.parametrize("value, message", [
    (np.ones(3, bool), "not booleans"), (np.ones(3) * 1j, "not complex numbers"),
    (["1", "2", "3"], r"signal 'roll'\[0\]: expected a real number, got '1'")])
def test_flightlog_signals_are_real_numbers(value, message):
    with pytest.raises(LogFormatError, match=message):
        FlightLog("x", "csv", [0.0, 0.1, 0.2], {"roll": value}, {}, {})


@pytest.mark.parametrize("source", [None, b"log.csv", 3, ["log.csv"]])
def test_flightlog_source_is_a_name(source):
    """None became the source 'None', bytes "b'log.csv'"."""
    with pytest.raises(InputError, match=r"^FlightLog: source: expected the log's file or name"):
        FlightLog(source, "csv", [0.0, 0.1], {}, {}, {})


def test_flightlog_names_of_raw_and_meta_are_strings():
    """Keys 1 and '1' became the one name '1', the second value silently kept."""
    t = [0.0, 0.1]
    with pytest.raises(InputError, match=r"^x: raw key: expected a name \(a str\), got 1$"):
        FlightLog("x", "csv", t, {}, {1: t, "1": [5.0, 6.0]}, {})
    with pytest.raises(InputError, match=r"^x: meta key: expected a name \(a str\), got 1$"):
        FlightLog("x", "csv", t, {}, {}, {1: "a", "1": "b"})
    from pathlib import Path
    log = FlightLog(Path("dir/log.csv"), "csv", t, {}, {"a": t}, {"k": 1})
    assert log.source == str(Path("dir/log.csv")) and log.meta["k"] == "1"


def test_parquet_written_by_quadcog_carries_page_checksums_the_reader_checks(tmp_path):
    """A Parquet file has no checksum unless its writer adds one: a byte changed in a data
    page was read as another value. write_log writes each page's CRC-32 and read_log checks
    it (a file without them is read as before)."""
    n = 5
    log = FlightLog("x", "csv", np.arange(n) * 0.01, {"roll": np.full(n, 1234.5678)}, {}, {})
    p = write_log(log, tmp_path / "c.parquet", "parquet")
    assert np.allclose(read_log(p).signal("roll"), 1234.5678)
    data = bytearray(p.read_bytes())
    at = data.index(struct.pack("<d", 1234.5678))       # its first copy: the data page
    data[at] ^= 1
    p.write_bytes(bytes(data))
    with pytest.raises(LogFormatError, match=r"not a readable Parquet file \(could not verify "
                                             r"page integrity, CRC checksum verification "
                                             r"failed"):
        read_log(p)


def test_parquet_schema_name_that_is_not_utf8_is_a_format_error(tmp_path):
    """pyarrow decodes the column names as UTF-8 and raised a raw UnicodeDecodeError."""
    p = _parquet(tmp_path / "n.parquet", [T, np.zeros(5)], ["t_s", "zzzz"])
    p.write_bytes(p.read_bytes().replace(b"zzzz", b"\xff\xfe\xfd\xfc"))
    with pytest.raises(LogFormatError, match=r"not a readable Parquet file \(a name in its "
                                             r"schema is not UTF-8 text"):
        read_log(p)


def test_table_writers_refuse_a_subnormal_time(tmp_path):
    """Written as 0 it repeated the time before, so the reader refused the file it wrote;
    a subnormal signal value is written as 0 by both table writers."""
    log = FlightLog("x", "csv", [0.0, 5e-324, 1.0], {"roll": [0.0, 1e-310, 0.5]}, {}, {})
    for fmt in ("csv", "parquet"):
        with pytest.raises(LogSignalError, match=r"time t = 5e-324 s at sample 1 is below the "
                                                 r"range of a float"):
            write_log(log, tmp_path / f"t.{fmt}", fmt)
        ok = FlightLog("x", "csv", [0.0, 0.5, 1.0], {"roll": [0.0, 1e-310, 0.5]}, {}, {})
        assert read_log(write_log(ok, tmp_path / f"ok.{fmt}", fmt)).signal("roll")[1] == 0.0


# -- the helpers of quadcog.logs.checks check their arguments ---------------------------------
_T = np.arange(0, 12, 0.01)
_LOG = FlightLog("hop", "csv", _T, {"position": np.column_stack(
    [np.zeros((_T.size, 2)), np.clip(np.minimum(_T - 1, 11 - _T), 0, 0.5)])}, {}, {})


@pytest.mark.parametrize("call, message", [
    (lambda: checks.lowpass("abc"), r"^lowpass: y: expected an array of shape \(N,\) or \(N, k\)"),
    (lambda: checks.lowpass(np.zeros(5)), r"^lowpass: y: expected .* N > 9 samples \(filtfilt's "
                                          r"padding\), got shape \(5,\)$"),
    (lambda: checks.lowpass(np.full(100, np.nan)), r"^lowpass: y\[0\]: expected a finite number"),
    (lambda: checks.lowpass(np.ones(100) * 1j), r"^lowpass: y: .*not complex numbers"),
    (lambda: checks.lowpass(np.ones((100, 2, 2))), r"^lowpass: y: .*got shape \(100, 2, 2\)$"),
    (lambda: checks.bandpass([]), r"^bandpass: y: expected .* N > 15 samples"),
    (lambda: checks.fit_gain(np.ones(10), np.arange(10.0)), r"^fit_gain: x: expected samples "
                                                            r"that vary"),
    (lambda: checks.fit_gain(np.arange(10.0), np.ones(10)), r"^fit_gain: y: expected samples "
                                                            r"that vary"),
    (lambda: checks.fit_gain(np.arange(10.0), np.ones(5)), r"^fit_gain: y: .*got shape \(5,\)"),
    (lambda: checks.fit_gain([], []), r"^fit_gain: x: .*N >= 2"),
    (lambda: checks.fit_gain([np.nan, 1, 2], [1, 2, 3]), r"^fit_gain: x\[0\]: expected a finite"),
    (lambda: checks.airborne_segments(None), r"^airborne_segments: log: expected a "
                                             r"quadcog.logs.FlightLog, got None$"),
    (lambda: checks.airborne_segments(_LOG, float("nan")), r"^airborne_segments: zmin: "
                                                           r"expected a finite real number"),
    (lambda: checks.airborne_segments(_LOG, "a"), r"^airborne_segments: zmin:"),
    (lambda: checks.airborne_segments(_LOG, 0.4, -1.0), r"^airborne_segments: trim: expected "
                                                        r"a number >= 0 \(s\), got -1.0$"),
])
def test_log_check_helpers_refuse_what_they_cannot_filter_or_fit(call, message):
    """Were raw ValueError (scipy's padlen, 'abc'), IndexError (None), AttributeError, numpy's
    ComplexWarning, and NaN answers: a NaN series filtered to NaN, a constant x gave a gain
    of nan (0 / 0) with a RuntimeWarning, a NaN zmin found no flight."""
    with pytest.raises(InputError, match=message):
        call()


def test_fit_gain_of_large_numbers_does_not_overflow():
    """Products of 1e300 overflowed to inf and the gain was nan (inf / inf)."""
    x = np.array([0.0, 1e300, 5e299])
    assert checks.fit_gain(x, 3 * x) == pytest.approx((3.0, 1.0))
    assert checks.fit_gain(np.arange(10.0), 2 * np.arange(10.0) + 1) == pytest.approx((2.0, 1.0))
    assert len(checks.airborne_segments(_LOG, 0.4)) == 1
    assert checks.lowpass(np.ones((100, 2))).shape == (100, 2)


# -- every public function of the format modules checks its arguments -------------------------
_GOOD = FlightLog("g", "csv", [0.0, 0.01, 0.02], {"position": np.zeros((3, 3))}, {}, {})
NOT_A_PATH = {"None": None, "True": True, "int 1": 1, "float": 1.5, "bytes": b"log.csv",
              "empty": "", "list": ["log.csv"], "array": np.zeros(2)}


@pytest.mark.parametrize("reader", [crazyflie.parse_usd, crazyflie.read_usd, ulog.read_ulog,
                                    lambda p: table.read_table(p, "csv"),
                                    lambda p: table.read_table(p, "parquet")],
                         ids=["parse_usd", "read_usd", "read_ulog", "read_table csv",
                              "read_table parquet"])
@pytest.mark.parametrize("value", list(NOT_A_PATH.values()), ids=list(NOT_A_PATH))
def test_format_readers_take_only_paths(reader, value, capsys):
    """Each format's reader took any value: str(None) 'None' was opened (FileNotFoundError),
    '' read the working folder (IsADirectoryError), and read_table(True, 'csv') opened file
    descriptor 1, the standard output, read it and closed it."""
    with pytest.raises(LogError, match=r": path: expected the path of a flight log file "
                                       r"\(str or os.PathLike\), got "):
        reader(value)
    print("stdout still open")
    assert "stdout still open" in capsys.readouterr().out


@pytest.mark.parametrize("reader", [crazyflie.read_usd, ulog.read_ulog,
                                    lambda p: table.read_table(p, "csv")],
                         ids=["read_usd", "read_ulog", "read_table"])
def test_format_readers_name_a_missing_file_or_a_folder(tmp_path, reader):
    with pytest.raises(LogError, match=rf"{re.escape(str(tmp_path / 'no.log'))}: cannot open "
                                       r"the flight log \(No such file or directory\)"):
        reader(tmp_path / "no.log")
    with pytest.raises(LogError, match=r"is a folder; expected a flight log file"):
        reader(tmp_path)


@pytest.mark.parametrize("fmt", [None, "CSV", "ulog", 1, b"csv"])
def test_table_reader_and_writer_take_only_their_formats(tmp_path, fmt):
    """read_table read anything but 'csv' as Parquet, write_table wrote anything but
    'parquet' as CSV (write_table(log, path, None) wrote a CSV)."""
    p = write_log(_GOOD, tmp_path / "g.csv", "csv")
    with pytest.raises(LogError, match=r"^read_table: fmt: expected one of 'csv', 'parquet'"):
        table.read_table(p, fmt)
    with pytest.raises(LogError, match=r"^write_table: fmt: expected one of 'csv', 'parquet'"):
        table.write_table(_GOOD, tmp_path / "w.csv", fmt)
    assert not (tmp_path / "w.csv").exists()


@pytest.mark.parametrize("writer", [crazyflie.write_usd, ulog.write_ulog,
                                    lambda log, p: table.write_table(log, p, "csv")],
                         ids=["write_usd", "write_ulog", "write_table"])
def test_format_writers_check_the_log_and_the_file(tmp_path, writer):
    """A log that is no FlightLog raised AttributeError ('NoneType' has no 'signals'); a
    path of None raised TypeError; a folder was not named."""
    with pytest.raises(LogError, match=r": log: expected a quadcog.logs.FlightLog, got None"):
        writer(None, tmp_path / "x")
    with pytest.raises(LogError, match=r"path: expected a file name"):
        writer(_GOOD, None)
    with pytest.raises(LogError, match=r"is a folder"):
        writer(_GOOD, tmp_path)


@pytest.mark.parametrize("call, message", [
    (lambda: ulog.px4_to_quadcog_quaternion("abc"), r"^px4_to_quadcog_quaternion: q: expected "
                                                    r"quaternions"),
    (lambda: ulog.px4_to_quadcog_quaternion(np.zeros(3)), r"got shape \(3,\)$"),
    (lambda: ulog.px4_to_quadcog_quaternion([1.0, np.nan, 0.0, 0.0]), r"q\[1\]: expected a "
                                                                      r"finite number"),
    (lambda: ulog.quaternion_to_euler(None), r"^quaternion_to_euler: q: expected quaternions"),
    (lambda: ulog.quaternion_to_euler(np.zeros(4)), r"^quaternion_to_euler: q: expected unit "
                                                    r"quaternions .* of norm 0$"),
    (lambda: ulog.quaternion_to_euler([[1.0, 0, 0, 0], [2.0, 0, 0, 0]]), r"of norm 2 at \(1,\)"),
    (lambda: ulog.euler_to_quaternion(None, 0, 0), r"^euler_to_quaternion: roll: expected"),
    (lambda: ulog.euler_to_quaternion(0, np.inf, 0), r"^euler_to_quaternion: pitch: expected "
                                                     r"a finite number"),
    (lambda: ulog.euler_to_quaternion(np.zeros(2), 0, np.zeros(3)), r"shapes that broadcast"),
    (lambda: signals.signal_columns("rol"), r"^signal_columns: name: expected a name of "
                                            r"quadcog.logs.SIGNALS"),
    (lambda: signals.signal_columns(None), r"^signal_columns: name: expected"),
    (lambda: signals.table_columns("roll"), r"^table_columns: names: expected None or an "
                                            r"iterable"),
    (lambda: signals.table_columns(["roll", "rol"]), r"^table_columns: names\[1\]: expected a "
                                                     r"name of quadcog.logs.SIGNALS"),
    (lambda: signals.table_columns(5), r"^table_columns: names: expected"),
    (lambda: signals.unit_token(None), r"^unit_token: unit: expected a unit"),
    (lambda: limits.microsecond_ticks(None, 0, "x"), r"^microsecond_ticks: log: expected a "
                                                     r"quadcog.logs.FlightLog"),
    (lambda: limits.microsecond_ticks(_GOOD, -1, "x"), r"^microsecond_ticks: start_us: "
                                                       r"expected an integer in \[0, "),
    (lambda: limits.microsecond_ticks(_GOOD, 1.5, "x"), r"^microsecond_ticks: start_us:"),
    (lambda: limits.check_range(_GOOD, "x", "abc", "f"), r"^check_range: values: expected"),
    (lambda: limits.check_range(_GOOD, "x", np.nan, "f"), r"^check_range: values: expected an "
                                                          r"array of one row per sample"),
    (lambda: limits.check_range(_GOOD, "x", [0.0], "f", lo=np.nan), r"^check_range: lo:"),
    (lambda: limits.check_unit_signals("log", "x"), r"^check_unit_signals: log: expected"),
    (lambda: samples.resolve_log_argument(None), r"^log: expected a log file's path or "
                                                 r"sample:NAME \(a str or os.PathLike\), got "
                                                 r"None$"),
    (lambda: samples.resolve_log_argument(b"a.csv"), r"^log: expected"),
])
def test_format_helpers_refuse_arguments_of_another_kind(call, message):
    """Were raw ValueError, TypeError, AxisError, KeyError, AttributeError and IndexError,
    or an answer: table_columns('roll') read the str as letters and gave ('t_s',), an unknown
    name was left out silently, quaternion_to_euler of a zero quaternion gave angles, a NaN
    quaternion converted to NaN, resolve_log_argument(None) the path 'None'."""
    with pytest.raises(InputError, match=message):
        call()


def test_format_helpers_still_answer():
    assert signals.table_columns(["roll"]) == ("t_s", "roll_rad")
    assert signals.table_columns(np.array(["roll"])) == ("t_s", "roll_rad")
    roll, pitch, yaw = ulog.quaternion_to_euler(ulog.euler_to_quaternion(0.1, -0.2, 0.3) * 1.05)
    assert np.allclose([roll, pitch, yaw], [0.1, -0.2, 0.3])
    assert samples.resolve_log_argument("x.csv") == [samples.Path("x.csv")]


def test_usd_records_are_gathered_in_memory_linear_in_the_file(tmp_path):
    """Each record's bytes were gathered through an index array of one int64 per byte: the
    parse took about 10 times the file in memory (a 76 MB log, 850 MB). Through a window
    view of the file: the file and one copy of its records, under 4 times the file."""
    import tracemalloc
    n = 30_000
    t = np.arange(n) * 0.001
    log = FlightLog("x", "csv", t, {"position": np.zeros((n, 3)), "velocity": np.zeros((n, 3)),
                                    "body_rates": np.zeros((n, 3)),
                                    "motor_pwm": np.full((n, 4), 0.5)}, {}, {})
    p = write_log(log, tmp_path / "m.bin", "crazyflie-usd")
    tracemalloc.start()
    try:
        version, events = crazyflie.parse_usd(p)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert events["fixedFrequency"][0].size == n
    assert peak < 4 * p.stat().st_size, peak / p.stat().st_size

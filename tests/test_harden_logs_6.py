"""Sixth hostile pass on quadcog.logs: values no firmware logs, read as numbers before.

- Crazyflie uSD: a motor output beyond the firmware's 16 bits (``motor.m*``, ``pwm.m*_pwm``
  of type ``I`` up to 2^32 - 1, or negative) or a motor request beyond an int32; a roll or
  pitch beyond 180 deg, a yaw beyond ``YAW_MAX_DEG``: refused with variable, value, record
  and time (were motor commands of 65537 x full scale and a yaw of 3e38 deg wrapped); the
  writer refuses the attitudes its reader would;
- ULog: a file format version PX4 never wrote (was read as version 1), a time stamp not
  declared ``uint64_t`` (int8 wrapped, negative int64 read), PWM range parameters beyond
  PX4's pulse widths or with the minimum not below the maximum (were used, or replaced by the
  defaults in silence), a ``THR_MDL_FAC`` that is not a factor in 0..1 (was copied to meta as
  'nan'); pyulog no longer opens the file (it left it open when it raised);
- CSV: a nonzero cell below the float range (``1e-400`` read as 0.0, ``2e-310`` as a
  subnormal) is refused like one beyond it; the writer writes subnormals as 0.
"""
import gc
import re
import struct
import warnings
import zlib

import numpy as np
import pytest

from quadcog.errors import LogFormatError, LogSignalError
from quadcog.logs import FlightLog, read_log, write_log
from quadcog.logs.crazyflie import ROLL_PITCH_MAX_DEG, YAW_MAX_DEG
from quadcog.logs.table import FLOAT_TINY
from quadcog.logs.ulog import PWM_RANGE_US, ULOG_MAGIC, ULOG_VERSIONS


@pytest.fixture(autouse=True)
def _no_runtime_warnings():
    """Every hostile input here must give a typed error, never a numpy warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


# -- Crazyflie uSD -------------------------------------------------------------------------
_PACK = {"B": "B", "b": "b", "H": "H", "h": "h", "I": "I", "i": "i", "f": "f", "e": "e"}


def _usd(path, variables, rows):
    """A uSD log (version 2) of one fixed-frequency event: ``variables`` [(name, T)],
    ``rows`` the values of each record, 10 ms apart; CRC-32 appended."""
    out = bytearray(struct.pack("<BHH", 0xBC, 2, 1))
    out += struct.pack("<H", 0xFFFF) + b"fixedFrequency\0" + struct.pack("<H", len(variables))
    out += b"".join(f"{v}({t})".encode() + b"\0" for v, t in variables)
    layout = "<" + "".join(_PACK[t] for _, t in variables)
    for k, values in enumerate(rows):
        out += struct.pack("<HQ", 0xFFFF, 10_000 * k) + struct.pack(layout, *values)
    path.write_bytes(bytes(out) + struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF))
    return path


def _one_bad(path, variables, good, bad, at=2, n=5):
    """``n`` records of ``good`` values, record ``at`` holding ``bad`` in the first variable."""
    rows = [list(good) for _ in range(n)]
    rows[at][0] = bad
    return _usd(path, variables, rows)


MOTORS = [(f"motor.m{k}", "I") for k in range(1, 5)]
PWM = [(f"pwm.m{k}_pwm", "I") for k in range(1, 5)]
REQUESTS = [(f"motor.m{k}req", "i") for k in range(1, 5)]


@pytest.mark.parametrize("variables, edge, bad", [
    (MOTORS, 65535, 65536), (MOTORS, 0, 2 ** 32 - 1), (PWM + MOTORS, 65535, 100_000),
    ([("motor.m1", "i")] + MOTORS[1:], 0, -1), ([("motor.m1", "f")] + MOTORS[1:], 65535.0,
                                                65535.5),
    ([("motor.m1", "f")] + MOTORS[1:], 0.0, -0.5), ([("pwm.m1_pwm", "h")] + PWM[1:], 0, -3),
    ([("motor.m1req", "f")] + REQUESTS[1:], -70000.0, 2.0 ** 31),
    ([("motor.m1req", "I")] + REQUESTS[1:], 70000, 2 ** 32 - 1)])
def test_usd_motor_outputs_beyond_the_firmwares_full_scale_are_refused(tmp_path, variables,
                                                                       edge, bad):
    """The firmware's motor outputs are 16-bit (0..65535), whatever type the header declares
    them in; its uncapped requests are int32. Anything beyond is refused with its variable,
    value, record and time; the full scale itself (a request beyond it) is read."""
    good = [1000] * len(variables)
    ok = read_log(_one_bad(tmp_path / "ok.bin", variables, good, edge))
    assert ok.raw[variables[0][0]][2] == edge
    assert any(np.isin(edge / 65535, ok.signals[m][:, 0]) for m in ("motor_command", "motor_pwm")
               if ok.has(m))
    p = _one_bad(tmp_path / "bad.bin", variables, good, bad)
    name = variables[0][0]
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(p))}: variable '{re.escape(name)}"
                                             rf"' of event 'fixedFrequency' is "
                                             rf"{re.escape(repr(float(bad)))} in record 2 "
                                             rf"\(t = 0.02 s\); expected the firmware's"):
        read_log(p)


@pytest.mark.parametrize("angle, typ, bad", [
    ("yaw", "f", 3e38), ("yaw", "f", -3e38), ("yaw", "f", YAW_MAX_DEG * 1.01),
    ("roll", "e", 200.0), ("roll", "f", 181.0), ("roll", "e", -65504.0), ("pitch", "f", -200.0),
    ("pitch", "f", 1e30)])
def test_usd_attitudes_beyond_any_orientation_are_refused(tmp_path, angle, typ, bad):
    """A roll or pitch beyond 180 deg (the estimators' atan2/asin range) or a yaw beyond
    YAW_MAX_DEG is no attitude: refused by name (a yaw of 3e38 deg was wrapped to an angle of
    rounding noise). At the limits, and a yaw of several turns, the angles are read."""
    variables = [(f"stateEstimate.{angle}", typ), ("stateEstimate.x", "f")]
    limit = ROLL_PITCH_MAX_DEG if angle != "yaw" else 720.0
    ok = read_log(_one_bad(tmp_path / "ok.bin", variables, [10.0, 0.0], limit))
    expected = {"roll": np.pi, "pitch": -np.pi, "yaw": 0.0}[angle]
    assert abs(abs(ok.signal(angle)[2]) - abs(expected)) < 1e-6
    p = _one_bad(tmp_path / "bad.bin", variables, [10.0, 0.0], bad)
    shown = float(np.float16(bad)) if typ == "e" else float(np.float32(bad))
    with pytest.raises(LogFormatError, match=rf"variable 'stateEstimate.{angle}' of event "
                                             rf"'fixedFrequency' is {re.escape(repr(shown))} in "
                                             rf"record 2 \(t = 0.02 s\); expected a {angle}"):
        read_log(p)


def _attitude_log(roll=0.0, pitch=0.0, yaw=0.0):
    n = 5
    return FlightLog("memory", "csv", np.arange(n) * 0.01,
                     {"roll": np.full(n, roll), "pitch": np.full(n, pitch),
                      "yaw": np.full(n, yaw)}, {}, {})


@pytest.mark.parametrize("angle, value", [("roll", 3.2), ("pitch", -3.5), ("roll", 1e30),
                                          ("yaw", np.radians(YAW_MAX_DEG) * 1.001),
                                          ("yaw", -1e30)])
def test_usd_writer_refuses_attitudes_its_reader_refuses(tmp_path, angle, value):
    """What write_log writes as a uSD log, read_log reads: a roll or pitch beyond 180 deg or
    a yaw beyond YAW_MAX_DEG is refused before writing (was written, and read back wrapped
    or not at all). An unwrapped yaw of many turns is written and read back wrapped."""
    p = tmp_path / "a.bin"
    back = read_log(write_log(_attitude_log(roll=np.pi, yaw=100.0), p, "crazyflie-usd"))
    assert np.allclose(back.signal("roll"), np.pi, atol=1e-6)
    assert np.allclose(back.signal("yaw"), np.angle(np.exp(100j)), atol=1e-4)
    with pytest.raises(LogSignalError, match=rf"stateEstimate.{angle} is .* at sample 0; a "
                                             r"Crazyflie log holds -\d+\.\.\d+ \(deg\)"):
        write_log(_attitude_log(**{angle: value}), p, "crazyflie-usd")


# -- ULog ----------------------------------------------------------------------------------
def _message(kind, payload):
    return struct.pack("<HB", len(payload), ord(kind)) + payload


LP = "vehicle_local_position:uint64_t timestamp;float x;float y;float z;"
AO = "actuator_outputs:uint64_t timestamp;float[16] output;"


def _ulog(path, formats=(LP,), topics=(("vehicle_local_position", "<Qfff",
                                         lambda k: (0.01 * k, 0.0, -1.0)),),
          params=(), version=1, flags=bytes(40), stamps=None, n=20):
    """A ULog: ``topics`` [(name, pack, values of sample k)] subscribed in order, data
    ``struct.pack(pack, stamp, *values(k))``; ``params`` (ctype, name, packed value);
    ``stamps`` the time stamps (default 1 s + 10 ms k)."""
    out = bytearray(ULOG_MAGIC + bytes([version]) + struct.pack("<Q", 0)) + _message("B", flags)
    for ctype, name, packed in params:
        key = f"{ctype} {name}".encode()
        out += _message("P", bytes([len(key)]) + key + packed)
    for text in formats:
        out += _message("F", text.encode())
    for msg_id, (name, _, _) in enumerate(topics):
        out += _message("A", bytes([0]) + struct.pack("<H", msg_id) + name.encode())
    stamps = stamps or [1_000_000 + 10_000 * k for k in range(n)]
    for k, stamp in enumerate(stamps):
        for msg_id, (_, pack, values) in enumerate(topics):
            out += _message("D", struct.pack("<H", msg_id)
                            + struct.pack(pack, stamp, *values(k)))
    path.write_bytes(bytes(out))
    return path


@pytest.mark.parametrize("version", [2, 3, 99, 255])
def test_ulog_file_format_versions_pyulog_does_not_know_are_refused(tmp_path, version):
    """pyulog reads any version as version 1 (printing a warning the reader hid); a version
    PX4 has not written is refused by number. Versions 0 and 1 are read."""
    for good in ULOG_VERSIONS:
        assert read_log(_ulog(tmp_path / "ok.ulg", version=good)).n_samples == 20
    p = _ulog(tmp_path / "v.ulg", version=version)
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(p))}: ULog file format version "
                                             rf"{version} \(header byte 7\); expected 0 or 1"):
        read_log(p)


@pytest.mark.parametrize("ctype, pack, stamps", [
    ("int8_t", "b", list(range(20))), ("int8_t", "b", list(range(-10, 10))),
    ("int64_t", "q", [-10 ** 18 + 10_000 * k for k in range(20)]),
    ("int64_t", "q", [1_000_000 + 10_000 * k for k in range(20)]),
    ("uint32_t", "I", [1_000_000 + 10_000 * k for k in range(20)]),
    ("int16_t", "h", list(range(20)))])
def test_ulog_time_stamps_not_uint64_are_refused(tmp_path, ctype, pack, stamps):
    """The ULog time stamp is ``uint64_t timestamp`` (us since boot); a narrower type wraps
    within minutes and a signed one can go negative: refused by type, whatever the values
    (int8 and negative int64 stamps were read)."""
    fmt = LP.replace("uint64_t timestamp", f"{ctype} timestamp")
    p = _ulog(tmp_path / "t.ulg", [fmt], [("vehicle_local_position", f"<{pack}fff",
                                           lambda k: (0.0, 0.0, -1.0))], stamps=stamps)
    with pytest.raises(LogFormatError, match=rf"topic vehicle_local_position has a 'timestamp' "
                                             rf"of type {np.dtype(ctype[:-2])}; expected the ULog "
                                             r"time stamp 'uint64_t timestamp' \(us\)"):
        read_log(p)


def _pwm_log(path, lo, hi):
    params = [("int32_t" if isinstance(v, int) else "float", k,
               struct.pack("<i" if isinstance(v, int) else "<f", v))
              for k, v in (("PWM_MAIN_MIN1", lo), ("PWM_MAIN_MAX1", hi)) if v is not None]
    topics = [("vehicle_local_position", "<Qfff", lambda k: (0.01 * k, 0.0, -1.0)),
              ("actuator_outputs", "<Q16f", lambda k: [1500.0] * 16)]
    return _ulog(path, [LP, AO], topics, params)


@pytest.mark.parametrize("lo, hi, message", [
    (1000, 2_000_000_000, r"PWM_MAIN_MAX1 is 2000000000 us; expected a PWM within 0..2500 us"),
    (-5, 2000, r"PWM_MAIN_MIN1 is -5 us; expected a PWM within 0..2500 us"),
    (1000, 3000, r"PWM_MAIN_MAX1 is 3000 us"), (1000.0, 2600.5, r"PWM_MAIN_MAX1 is 2600.5 us"),
    (2000, 1000, r"PWM_MAIN_MIN1 = 2000 us and PWM_MAIN_MAX1 = 1000 us; expected the minimum "
                 r"below the maximum"),
    (1500, 1500, r"PWM_MAIN_MIN1 = 1500 us and PWM_MAIN_MAX1 = 1500 us")])
def test_ulog_pwm_ranges_px4_cannot_output_are_refused(tmp_path, lo, hi, message):
    """A motor's PWM range must be pulse widths PX4 outputs (PWM_RANGE_US), the minimum
    below the maximum: otherwise refused by name (2e9 us gave a motor_pwm of almost 0; a
    swapped range was replaced by the defaults in silence). A range within them is used;
    PX4's old "not set" (-1) reads as the defaults."""
    assert PWM_RANGE_US == (0.0, 2500.0)
    log = read_log(_pwm_log(tmp_path / "ok.ulg", 1100, 1900))
    assert np.allclose(log.signal("motor_pwm"), 0.5) and "PWM_MAIN_MIN" in log.meta["pwm_range"]
    log = read_log(_pwm_log(tmp_path / "unset.ulg", -1, -1))
    assert np.allclose(log.signal("motor_pwm"), 0.5) and "defaults" in log.meta["pwm_range"]
    p = _pwm_log(tmp_path / "bad.ulg", lo, hi)
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(p))}: parameters? {message}.*"
                                             r"channel 1 \(actuator_outputs.output\[0\]\)"):
        read_log(p)


@pytest.mark.parametrize("value", [float("nan"), float("inf"), float("-inf"), 1.5, -0.25])
def test_ulog_thr_mdl_fac_that_is_no_factor_is_refused(tmp_path, value):
    """THR_MDL_FAC goes from meta to the thrust curve: one outside PX4's 0..1 (or not finite)
    is refused with the log's name (was copied to meta as 'nan' or 'inf'). A factor in range
    is carried; the parameters nothing computes with are copied as logged."""
    good = [("float", "THR_MDL_FAC", struct.pack("<f", 0.25)),
            ("float", "MPC_THR_HOVER", struct.pack("<f", 0.5))]
    log = read_log(_ulog(tmp_path / "ok.ulg", params=good))
    assert log.meta["param.THR_MDL_FAC"] == "0.25" and log.meta["param.MPC_THR_HOVER"] == "0.5"
    p = _ulog(tmp_path / "bad.ulg", params=[("float", "THR_MDL_FAC", struct.pack("<f", value))])
    with pytest.raises(LogFormatError, match=rf"{re.escape(str(p))}: parameter THR_MDL_FAC is "
                                             rf"{re.escape(repr(value))}; expected PX4's thrust "
                                             r"model factor, a number within 0..1"):
        read_log(p)


@pytest.mark.parametrize("flags", [
    bytes(8) + bytes([0xFE]) + bytes(31),              # an unknown incompat bit
    bytes(9) + bytes([1]) + bytes(30),                 # a bit of a later incompat byte
    bytes(15) + bytes([0x80]) + bytes(24)])
def test_ulog_pyulog_leaves_no_file_open_when_it_raises(tmp_path, flags):
    """pyulog opened the file itself and left it open when it raised (a ResourceWarning at
    garbage collection); the reader hands it the bytes it has checked, so no file is left
    open on any path, the refusal still typed."""
    p = _ulog(tmp_path / "f.ulg", flags=flags)
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        with pytest.raises(LogFormatError, match=r"pyulog cannot read the ULog \(Unknown "
                                                 r"incompatible flag"):
            read_log(p)
        assert read_log(_ulog(tmp_path / "ok.ulg")).n_samples == 20
        gc.collect()
    leaks = [str(w.message) for w in seen if issubclass(w.category, ResourceWarning)]
    assert not leaks


# -- CSV -----------------------------------------------------------------------------------
@pytest.mark.parametrize("cell", ["1e-400", "-1e-400", "2e-310", "-4.9e-324", "1E-0000400",
                                  "123e-330", "0." + "0" * 400 + "1", "+.00001e-305",
                                  "1" + "0" * 30 + "e-360"])
def test_csv_nonzero_cells_below_the_float_range_are_refused(tmp_path, cell):
    """A nonzero cell that would read as 0.0 or a subnormal (digits lost) is refused with
    its line, column and text, as a cell beyond the float range is, in a file of plain
    numbers (numpy's fast parser) or not; zeros written any way, and the smallest normal
    float, are read."""
    p = tmp_path / "a.csv"
    p.write_text("t_s,x\n0,0e-400\n1,-0.000e-999\n2,2.3e-308\n3,0." + "0" * 400 + "\n")
    assert read_log(p).raw["x"].tolist() == [0.0, 0.0, 2.3e-308, 0.0]
    for rest in ("", "\n9,abc"):                   # plain text, and text read cell by cell
        p.write_text(f"t_s,x\n0,1\n1,2\n2,{cell}\n3,4{rest}\n")
        shown = re.escape(repr(cell)) if len(cell) <= 40 else \
            re.escape(repr(cell[:40])) + r"\.\.\. \(\d+ characters\)"
        with pytest.raises(LogFormatError, match=rf"line 4, column 'x': {shown} is below the "
                                                 rf"range of a float \(a nonzero magnitude at "
                                                 rf"least {FLOAT_TINY:.4g}\)"):
            read_log(p)


def test_csv_writer_writes_subnormals_as_zero(tmp_path):
    """What write_log writes as CSV, read_log reads: a subnormal value (which the reader
    refuses) is written as a zero of its sign; the other values as they are."""
    n = 4
    x = np.array([5e-324, -1e-310, FLOAT_TINY, 1.0])
    log = FlightLog("memory", "csv", np.arange(n) * 0.01,
                    {"battery_voltage": x}, {}, {})
    back = read_log(write_log(log, tmp_path / "a.csv", "csv"))
    v = back.signal("battery_voltage")
    assert v.tolist() == [0.0, 0.0, FLOAT_TINY, 1.0] and np.signbit(v[1])

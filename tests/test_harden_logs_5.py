"""Fifth hostile pass on quadcog.logs: inputs of the kinds the pass found, other than its
examples.

- ULog formats that contain themselves (directly or through others), nest too deep or expand
  beyond a data message: a LogFormatError naming the format (was a raw RecursionError);
- ULog fields declared ``char`` or ``bool`` where numbers are read, attitude quaternions far
  from unit norm, non-finite PWM range parameters: refused by name (were read as numbers,
  normalised silently, or a NaN signal and a RuntimeWarning naming nothing);
- the ULog writer's rotor positions (meta) that float32 or the reader's quadrant assignment
  cannot carry: a LogError before any byte is written (was a raw OverflowError, or motors
  silently reordered on reading back);
- CSV cells that are not plain ASCII decimal numbers (``#``, ``1_000``, other scripts'
  digits, ...): refused with line, column and cell (were read as other numbers, or rows
  dropped); a cell beyond the float range is shown as written (was "inf");
- Crazyflie uSD logs: the time base is the event of id 0xFFFF, an event name declared twice is
  refused, a non-finite variable is named as logged (was the event found by name, and "signal
  'yaw' is nan" for an inf yaw, with RuntimeWarnings).
"""
import re
import struct
import warnings
import zlib

import numpy as np
import pytest

from quadcog.errors import LogError, LogFormatError
from quadcog.logs import FlightLog, read_log, write_log
from quadcog.logs.ulog import MAX_FORMAT_BYTES, MAX_NESTING, QUATERNION_NORM_TOLERANCE, ULOG_MAGIC


@pytest.fixture(autouse=True)
def _no_runtime_warnings():
    """Every hostile input here must give a typed error, never a numpy warning."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


# -- ULog files, byte by byte from the format's spec ----------------------------------------
def _message(kind, payload):
    return struct.pack("<HB", len(payload), ord(kind)) + payload


def _ulog(path, formats, topics, params=(), n=20):
    """A ULog: ``formats`` the text of its format messages; ``topics`` ``[(name, pack, values
    of sample k)]`` subscribed in order, whose data are ``struct.pack(pack, stamp,
    *values(k))``; ``params`` ``(ctype, name, packed value)``."""
    out = bytearray(ULOG_MAGIC + bytes([1]) + struct.pack("<Q", 0)) + _message("B", bytes(40))
    for ctype, name, packed in params:
        key = f"{ctype} {name}".encode()
        out += _message("P", bytes([len(key)]) + key + packed)
    for text in formats:
        out += _message("F", text.encode())
    for msg_id, (name, _, _) in enumerate(topics):
        out += _message("A", bytes([0]) + struct.pack("<H", msg_id) + name.encode())
    for k in range(n):
        for msg_id, (_, pack, values) in enumerate(topics):
            out += _message("D", struct.pack("<H", msg_id)
                            + struct.pack(pack, 1_000_000 + 10_000 * k, *values(k)))
    path.write_bytes(bytes(out))
    return path


LP = "vehicle_local_position:uint64_t timestamp;float x;float y;float z;"
LP_TOPIC = ("vehicle_local_position", "<Qfff", lambda k: (0.01 * k, 0.0, -1.0))


@pytest.mark.parametrize("formats, name", [
    (["foo:foo b;"], "foo"),                                    # itself
    (["foo:uint8_t a;foo[2] b;"], "foo"),                       # itself, in an array
    (["foo:bar b;", "bar:foo c;"], "foo"),                      # through another
    (["a:b x;", "b:c x;", "c:d x;", "d:b x;"], "b"),            # a loop further down
    ([f"f{k}:f{k + 1} x;" for k in range(3000)] + ["f3000:float y;"], "f0"),   # too deep
])
def test_ulog_formats_that_nest_without_end_are_refused_by_name(tmp_path, formats, name):
    """pyulog expands a format by recursion: a cycle, or a chain deeper than Python's stack,
    must be found before it parses, whether the format is subscribed or not."""
    p = _ulog(tmp_path / "nest.ulg", [LP] + formats, [LP_TOPIC])
    with pytest.raises(LogFormatError, match=rf"{p}: ULog format '{name}' (contains itself|"
                                             rf"nests formats more than {MAX_NESTING} deep)"):
        read_log(p)


def test_ulog_formats_larger_than_a_data_message_are_refused(tmp_path):
    """A format that expands (arrays of nested formats) beyond what a data message holds
    cannot be logged; refused before pyulog expands it field by field. Nested formats within
    the bounds are read."""
    formats = [LP, "pair:float a;float b;", "esc_status:uint64_t timestamp;pair[2] esc;",
               f"wide:uint64_t timestamp;uint8_t[{MAX_FORMAT_BYTES - 8}] v;"]
    topics = [LP_TOPIC, ("esc_status", "<Q4f", lambda k: (1.0, 2.0, 3.0, 4.0))]
    log = read_log(_ulog(tmp_path / "ok.ulg", formats, topics))
    assert np.allclose(log.signal("position")[:, 0], 0.01 * np.arange(20))
    big = MAX_FORMAT_BYTES // 4 + 1
    for formats in ([f"huge:float[{big}] v;"],
                    ["pair:float a;float b;", f"huge:pair[{big // 2 + 1}] p;"]):
        p = _ulog(tmp_path / "big.ulg", [LP] + formats, [LP_TOPIC])
        with pytest.raises(LogFormatError, match=rf"ULog format 'huge' takes more than "
                                                 rf"{MAX_FORMAT_BYTES:,} bytes"):
            read_log(p)


@pytest.mark.parametrize("ctype, field", [("char", "x"), ("bool", "x"), ("char", "z"),
                                          ("char", "timestamp")])
def test_ulog_text_or_bool_fields_read_as_numbers_are_refused(tmp_path, ctype, field):
    """A char ('a') or bool field where the reader expects a number is refused by name,
    not read as its byte code."""
    fields = {"timestamp": "uint64_t", "x": "float", "y": "float", "z": "float"}
    fields[field] = ctype
    fmt = "vehicle_local_position:" + "".join(f"{t} {f};" for f, t in fields.items())
    pack = "<" + "".join({"uint64_t": "Q", "float": "f", "char": "B", "bool": "?"}[t]
                         for t in fields.values())

    def values(k):
        return [{"char": 97, "bool": True, "float": 0.5}[t] for f, t in fields.items()
                if f != "timestamp"]

    out = _ulog(tmp_path / "t.ulg", [fmt], [("vehicle_local_position", "<Q" + pack[2:],
                                             values)])
    if field == "timestamp":            # the stamp itself as a char: rewrite the file
        out = _ulog(tmp_path / "t.ulg", [fmt], [])
        body = b"".join(_message("D", struct.pack("<H", 0) + struct.pack(pack, k, 0.5, 0.5, 0.5))
                        for k in range(20))
        out.write_bytes(out.read_bytes() + _message("A", bytes([0]) + struct.pack("<H", 0)
                                                    + b"vehicle_local_position") + body)
    with pytest.raises(LogFormatError, match=rf"vehicle_local_position: field {field} has "
                                             rf"type '{ctype}'; expected a number"):
        read_log(out)


ATT = "vehicle_attitude:uint64_t timestamp;float[4] q;"


@pytest.mark.parametrize("q", [(1000.0, 0, 0, 0), (0.5, 0, 0, 0), (0, 0, 0, 0),
                               (1.0, 0.5, 0.0, 0.0), (0.7, 0.0, 0.0, 0.0),
                               (float("inf"), 0, 0, 0), (3e38, 3e38, 0, 0)])
def test_ulog_quaternions_far_from_unit_norm_are_refused(tmp_path, q):
    """Normalising would hide the damage: any sample with |q| outside 1 +- the tolerance is
    refused with its sample, time stamp and norm; the other samples are unit. Within the
    tolerance (float32 rounding, a filter's drift) q is normalised and read."""
    scale = 1.0 + 0.5 * QUATERNION_NORM_TOLERANCE
    c, s = np.cos(0.1), np.sin(0.1)                 # roll 0.2 rad
    ok = read_log(_ulog(tmp_path / "ok.ulg", [ATT],
                        [("vehicle_attitude", "<Q4f", lambda k: (scale * c, scale * s, 0, 0))]))
    assert np.allclose(ok.signal("roll"), 0.2, atol=1e-6)
    bad_at = 7

    def values(k):
        return q if k == bad_at else (1.0, 0.0, 0.0, 0.0)

    p = _ulog(tmp_path / "q.ulg", [ATT], [("vehicle_attitude", "<Q4f", values)])
    norm = float(np.linalg.norm(np.asarray(q, dtype=np.float32).astype(float)))
    with pytest.raises(LogFormatError, match=rf"vehicle_attitude.q of sample {bad_at} \(time "
                                             rf"stamp {1_000_000 + 10_000 * bad_at} us\) .* "
                                             rf"of norm {re.escape(f'{norm:.6g}')}; expected a "
                                             "unit quaternion"):
        read_log(p)


AO = "actuator_outputs:uint64_t timestamp;float[16] output;"
AO_TOPIC = ("actuator_outputs", "<Q16f", lambda k: [1500.0] * 16)


@pytest.mark.parametrize("key, ctype, value", [
    ("PWM_MAIN_MIN1", "float", float("-inf")), ("PWM_MAIN_MAX1", "float", float("inf")),
    ("PWM_MAIN_MIN1", "float", float("nan")), ("PWM_MAIN_MAX1", "float", float("nan")),
    ("PWM_MAIN_MIN1", "char[4]", b"1000")])
def test_ulog_pwm_range_parameters_not_finite_numbers_are_refused(tmp_path, key, ctype, value):
    """The motor output's range is read from its parameters: one that is not a finite number
    is refused by name (was a NaN signal dropped, with a warning, or defaults in silence)."""
    other = "PWM_MAIN_MAX1" if key == "PWM_MAIN_MIN1" else "PWM_MAIN_MIN1"
    params = [("float", other, struct.pack("<f", 2000.0 if "MAX" in other else 1000.0)),
              (ctype, key, value if isinstance(value, bytes) else struct.pack("<f", value))]
    p = _ulog(tmp_path / "pwm.ulg", [LP, AO], [LP_TOPIC, AO_TOPIC], params)
    with pytest.raises(LogFormatError, match=rf"parameter {key} is .*expected a finite PWM"):
        read_log(p)


# -- the ULog writer: what it narrows to float32 -----------------------------------------
def _log(meta):
    n = 10
    return FlightLog("memory", "csv", np.arange(n) * 0.01,
                     {"position": np.zeros((n, 3)),
                      "motor_command": np.tile([0.1, 0.2, 0.3, 0.4], (n, 1))}, {}, meta)


@pytest.mark.parametrize("positions", [
    "1e39 0.1; -0.1 -0.1; -0.1 0.1; 0.1 0.1",          # beyond float32
    "0.1 -1e300; -0.1 -0.1; -0.1 0.1; 0.1 0.1",
    "inf -0.1; -0.1 -0.1; -0.1 0.1; 0.1 0.1", "nan -0.1; -0.1 -0.1; -0.1 0.1; 0.1 0.1",
    "0.1 0.1; -0.1 -0.1; -0.1 0.1; 0.1 -0.1",          # rotors 1 and 4 swapped
    "1e-50 -0.1; -0.1 -0.1; -0.1 0.1; 0.1 0.1",        # 0 in float32: no quadrant
    "0.1 -0.1; -0.1 -0.1", "x y z", "0.1 -0.1 0; -0.1 -0.1 0; -0.1 0.1 0; 0.1 0.1 0"])
def test_ulog_writer_refuses_rotor_positions_it_cannot_carry(tmp_path, positions):
    """Rotor positions the float32 parameters cannot hold, or that the reader would assign
    to other motors, are refused before a byte is written; an existing file is kept."""
    p = tmp_path / "out.ulg"
    p.write_bytes(b"before")
    with pytest.raises(LogError, match=r"meta\['rotor_positions_m'\]"):
        write_log(_log({"rotor_positions_m": positions}), p, "ulog")
    assert p.read_bytes() == b"before"
    assert [q.name for q in tmp_path.iterdir()] == ["out.ulg"]
    # positions that fit are carried: read back (float32) with the motors in their order
    good = "0.12 -0.1; -0.1 -0.3; -0.1 0.1; 0.1 0.1"
    back = read_log(write_log(_log({"rotor_positions_m": good}), p, "ulog"))
    read = np.array([[float(v) for v in pair.split()]
                     for pair in back.meta["rotor_positions_m"].split(";")])
    expected = np.array([[0.12, -0.1], [-0.1, -0.3], [-0.1, 0.1], [0.1, 0.1]])
    assert np.allclose(read, expected, rtol=1e-6)
    assert np.allclose(back.signal("motor_command")[0], [0.1, 0.2, 0.3, 0.4], rtol=1e-6)


# -- CSV cells -----------------------------------------------------------------------------
# forms float() or numpy's parser would read as another number, or read in part
SILENTLY_READ = ["1#5", "2 # note", "1_000", "\uff11", "\u0661", "\u00a01", "1\u3000",
                 "\u0967.5"]


@pytest.mark.parametrize("cell", SILENTLY_READ)
def test_csv_cells_that_are_not_plain_decimal_numbers_are_refused(tmp_path, cell):
    """Only an ASCII decimal number is a cell: what float() or numpy would also take (other
    scripts' digits, underscores, "#" comments, Unicode blanks) is refused with line, column
    and cell, in any column."""
    p = tmp_path / "a.csv"
    for row in (f"0.5,3,{cell}", f"0.5,{cell},3"):
        p.write_text(f"t_s,x,y\n0,1,2\n{row}\n1,2,4\n", encoding="utf-8")
        column = "y" if row.endswith(cell) else "x"
        with pytest.raises(LogFormatError, match=rf"line 3, column '{column}': "
                                                 rf"{re.escape(repr(cell))} is not a number"):
            read_log(p)


def test_csv_reads_plain_numbers_and_refuses_every_other_cell(tmp_path):
    """The rule as a whole: plain forms are read as they are written, anything else (those
    numpy refused before, and those it read as something else) is refused."""
    p = tmp_path / "a.csv"
    p.write_text('t_s,x\n0,-1.5e-3\n1,+.5\n2,5.\n3,"2"\n4, 3 \n5,1E2\n6,007\n',
                 encoding="utf-8")
    assert read_log(p).raw["x"].tolist() == [-1.5e-3, 0.5, 5.0, 2.0, 3.0, 100.0, 7.0]
    for cell in SILENTLY_READ + ["0x1p3", "1e5e5", "1..2", "--1", "1e", "\u00b2", "1;5", "1 5",
                                 "", "abc"]:
        p.write_text(f"t_s,x\n0,1\n1,{cell}\n", encoding="utf-8")
        with pytest.raises(LogFormatError, match=rf"line 3, column 'x': "
                                                 rf"{re.escape(repr(cell.strip(' ')))} is not"):
            read_log(p)


def test_csv_a_row_that_starts_with_a_hash_is_not_dropped(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("t_s,x\n0,1\n#0.5,7\n1,2\n")
    with pytest.raises(LogFormatError, match=r"line 3, column 't_s': '#0.5' is not a number"):
        read_log(p)


def test_csv_a_row_of_empty_cells_is_refused_not_skipped(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("t_s,x\n0,1\n,\n1,2\n")
    with pytest.raises(LogFormatError, match=r"line 3, column 't_s': '' is not a number"):
        read_log(p)


@pytest.mark.parametrize("cell", ["9" * 400, "-" + "1" * 310, "1e400", "-2.5E+999"])
def test_csv_cells_beyond_the_float_range_are_shown_as_written(tmp_path, cell):
    p = tmp_path / "a.csv"
    p.write_text(f"t_s,x\n0,{cell}\n1,2\n")
    with pytest.raises(LogFormatError, match=rf"line 2, column 'x': '{re.escape(cell[:40])}'.* is "
                                             r"beyond the range of a float") as e:
        read_log(p)
    assert "inf" not in str(e.value)


# -- Crazyflie uSD ---------------------------------------------------------------------------
def _usd(events, records):
    """A uSD log (version 2): ``events`` [(id, name, [(var, T)])], ``records`` [(id, tick us,
    values)], CRC-32 appended."""
    out = bytearray(struct.pack("<BHH", 0xBC, 2, len(events)))
    layout = {}
    for eid, name, variables in events:
        out += struct.pack("<H", eid) + name.encode() + b"\0" + struct.pack("<H", len(variables))
        out += b"".join(f"{v}({t})".encode() + b"\0" for v, t in variables)
        layout[eid] = "<" + "".join(t for _, t in variables)
    for eid, tick, values in records:
        out += struct.pack("<HQ", eid, tick) + struct.pack(layout[eid], *values)
    return bytes(out) + struct.pack("<I", zlib.crc32(bytes(out)) & 0xFFFFFFFF)


X = [("stateEstimate.x", "f")]


@pytest.mark.parametrize("other_id", [1, 0, 0xFFFE])
def test_usd_an_event_name_declared_twice_is_refused(tmp_path, other_id):
    p = tmp_path / "a.bin"
    p.write_bytes(_usd([(0xFFFF, "fixedFrequency", X), (other_id, "fixedFrequency", X)],
                       [(0xFFFF, 0, [1.0]), (0xFFFF, 10_000, [2.0]), (other_id, 5, [9.0])]))
    with pytest.raises(LogFormatError, match=r"event name 'fixedFrequency' declared twice"):
        read_log(p)


def test_usd_the_time_base_is_the_event_of_id_0xffff_whatever_the_names(tmp_path):
    """The event of id 0xFFFF is the fixed-frequency log; another event named
    'fixedFrequency' is not the time base."""
    p = tmp_path / "a.bin"
    p.write_bytes(_usd([(3, "fixedFrequency", X), (0xFFFF, "fixedRate", X)],
                       [(3, 5, [9.0]), (3, 7, [9.0]), (3, 9, [9.0])]
                       + [(0xFFFF, 10_000 * k, [float(k)]) for k in range(4)]))
    log = read_log(p)
    assert log.n_samples == 4 and log.raw["stateEstimate.x"].tolist() == [0.0, 1.0, 2.0, 3.0]
    assert "fixedFrequency: 3 records" in log.meta["events"]


@pytest.mark.parametrize("variable, typ", [("stateEstimate.yaw", "e"), ("stateEstimate.yaw", "f"),
                                           ("stateEstimate.roll", "e"), ("gyro.x", "f"),
                                           ("stateEstimate.x", "e")])
@pytest.mark.parametrize("value", [float("inf"), float("-inf"), float("nan")])
def test_usd_variables_not_finite_are_named_as_logged(tmp_path, variable, typ, value):
    """Named with the value the file holds (inf is not reported as nan), before any
    conversion warns."""
    p = tmp_path / "a.bin"
    variables = [(variable, typ), ("gyro.y", "f"), ("gyro.z", "f")] if variable == "gyro.x" \
        else [(variable, typ)]
    fill = [0.0] * (len(variables) - 1)
    p.write_bytes(_usd([(0xFFFF, "fixedFrequency", variables)],
                       [(0xFFFF, 0, [1.0] + fill), (0xFFFF, 10_000, [value] + fill),
                        (0xFFFF, 20_000, [1.0] + fill)]))
    with pytest.raises(LogFormatError, match=rf"variable '{variable}' of event 'fixedFrequency' "
                                             rf"is {value!r} in record 1 \(t = 0.01 s\)"):
        read_log(p)

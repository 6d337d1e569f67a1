"""quadcog.logs, whatever the format: the signal table and column names, FlightLog's checks,
format detection, CSV and Parquet round trips and their damaged files."""
import builtins
import dataclasses

import numpy as np
import pytest

from quadcog.errors import InputError, LogError, LogFormatError, LogSignalError, MissingDependencyError
from quadcog.logs import (
    LOG_FORMATS,
    SIGNALS,
    FlightLog,
    detect_format,
    read_log,
    signal_columns,
    table_columns,
    write_log,
)

N = 50


def synthetic(n=N, signals=None):
    """A log with every standard signal, values of every sign and size (seeded)."""
    rng = np.random.default_rng(7)
    t = np.cumsum(rng.uniform(0.005, 0.015, n))
    t -= t[0]
    if signals is None:
        signals = {name: rng.uniform(-3, 3, (n,) + spec.shape) for name, spec in SIGNALS.items()}
        signals["yaw"] = rng.uniform(-np.pi + 1e-3, np.pi, n)
        for name in ("motor_command", "motor_pwm"):
            signals[name] = rng.uniform(0, 1, (n, 4))
        signals["battery_voltage"] = rng.uniform(3.0, 4.2, n)
        signals["thrust_command"] = rng.uniform(0, 1, n)
        signals["moment_command"] = rng.uniform(-0.1, 0.1, (n, 3))
    return FlightLog("synthetic", "csv", t, signals, {}, {"vehicle": "test"})


def test_column_names_follow_quadcog_columns():
    """One convention: <signal>_<component>_<unit>, '/' as '_', no '^', no unit when
    dimensionless (the style of quadcog.model.columns: ref_ax_m_s2)."""
    assert signal_columns("position") == ("position_x_m", "position_y_m", "position_z_m")
    assert signal_columns("acceleration")[2] == "acceleration_z_m_s2"
    assert signal_columns("body_rates") == ("body_rates_p_rad_s", "body_rates_q_rad_s",
                                            "body_rates_r_rad_s")
    assert signal_columns("roll") == ("roll_rad",)
    assert signal_columns("battery_voltage") == ("battery_voltage_V",)
    assert signal_columns("motor_command") == tuple(f"motor_command_m{k}" for k in range(1, 5))
    cols = table_columns()
    assert cols[0] == "t_s" and len(cols) == len(set(cols))
    assert len(cols) == 1 + sum(int(np.prod(s.shape)) for s in SIGNALS.values())


def test_signal_table_shapes_match_components():
    for name, spec in SIGNALS.items():
        assert len(spec.components) == (spec.shape[0] if spec.shape else 0), name
        assert spec.unit and spec.meaning, name


def test_flightlog_is_frozen_and_copies():
    t = np.linspace(0, 1, N)
    pos = np.zeros((N, 3))
    log = FlightLog("x", "csv", t, {"position": pos}, {"a": np.ones(N)}, {"k": 1})
    pos[0, 0] = 5.0
    assert log.signal("position")[0, 0] == 0.0            # a copy, not a view
    with pytest.raises(ValueError):
        log.signal("position")[0, 0] = 1.0               # read-only
    with pytest.raises(TypeError):
        log.signals["roll"] = t                         # read-only mapping
    with pytest.raises(dataclasses.FrozenInstanceError):
        log.t = t
    assert log.meta["k"] == "1" and log.has("position") and not log.has("roll")


@pytest.mark.parametrize("t, signals, match", [
    ([0.0, 0.1, 0.1], {}, "not strictly increasing"),
    ([0.0, np.nan, 0.2], {}, "not finite"),
    ([0.0], {}, "N >= 2"),
    ([0.0, 0.1, 0.2], {"position": np.zeros((3, 2))}, r"shape \(3, 2\), expected \(3, 3\)"),
    ([0.0, 0.1, 0.2], {"roll": [0.0, np.nan, 0.0]}, r"signal 'roll' is nan at sample 1"),
    ([0.0, 0.1, 0.2], {"roll": ["a", "b", "c"]}, r"signal 'roll'\[0\]: expected a real number, got 'a'"),
])
def test_flightlog_refuses_bad_content(t, signals, match):
    with pytest.raises(LogFormatError, match=match):
        FlightLog("bad.csv", "csv", t, signals, {}, {})


def test_flightlog_refuses_unknown_names():
    with pytest.raises(InputError, match="'rol' is not a standard signal"):
        FlightLog("x", "csv", [0.0, 1.0], {"rol": [0.0, 0.0]}, {}, {})
    with pytest.raises(InputError, match="format 'bag'"):
        FlightLog("x", "bag", [0.0, 1.0], {}, {}, {})


def test_missing_signal_names_signal_log_and_what_it_has():
    log = synthetic(signals={"position": np.zeros((N, 3)), "roll": np.zeros(N)})
    with pytest.raises(LogSignalError) as e:
        log.signal("pitch")
    msg = str(e.value)
    assert "'pitch'" in msg and "synthetic" in msg and "position, roll" in msg
    assert e.value.signal == "pitch" and e.value.available == ("position", "roll")
    with pytest.raises(LogSignalError, match="not a standard signal"):
        log.signal("pich")


def test_window_keeps_the_time_origin():
    log = synthetic()
    w = log.window(0.1, 0.3)
    keep = (log.t >= 0.1) & (log.t <= 0.3)
    assert np.array_equal(w.t, log.t[keep])
    assert np.array_equal(w.signal("position"), log.signal("position")[keep])
    with pytest.raises(InputError, match="window"):
        log.window(0.3, 0.1)
    with pytest.raises(InputError, match="at least 2 samples"):
        log.window(100.0, 101.0)
    with pytest.raises(InputError, match="t0"):
        log.window(float("nan"), 1.0)


@pytest.mark.parametrize("fmt", ["csv", "parquet"])
def test_table_round_trip_is_exact(tmp_path, fmt):
    log = synthetic()
    path = write_log(log, tmp_path / f"log.{fmt}", fmt)
    back = read_log(path)
    assert back.format == fmt and detect_format(path) == fmt
    assert np.array_equal(back.t, log.t)
    assert set(back.signals) == set(SIGNALS)
    for name in SIGNALS:
        assert np.array_equal(back.signal(name), log.signal(name)), name
    assert set(back.raw) == set(table_columns()[1:])


def test_csv_written_by_hand_reads_with_offset_time_and_extra_columns(tmp_path):
    """A user's CSV: time not starting at 0, columns in any order, an unknown column kept
    raw, spaces around cells."""
    p = tmp_path / "mine.csv"
    p.write_text("roll_rad, t_s ,notes_x\n0.1, 10.0, 3\n-0.2 ,10.5,4\n0.3,11.0,5\n")
    log = read_log(p)
    assert np.allclose(log.t, [0.0, 0.5, 1.0]) and log.meta["time_offset_s"] == "10.0"
    assert np.allclose(log.signal("roll"), [0.1, -0.2, 0.3])
    assert np.allclose(log.raw["notes_x"], [3, 4, 5]) and set(log.signals) == {"roll"}


@pytest.mark.parametrize("text, match", [
    ("", "empty file"),
    ("roll_rad\n0.1\n0.2\n", "no time column 't_s'"),
    ("t_s,roll_rad\n0,0.1\n0.1,abc\n", r"line 3, column 'roll_rad': 'abc' is not a number"),
    ("t_s,roll_rad\n0,0.1\n0.1,\n", r"line 3, column 'roll_rad': '' is not a number"),
    ("t_s,roll_rad\n0,0.1\n0.1,nan\n", r"column 'roll_rad', data row 2: nan"),
    ("t_s,roll_rad\n0,0.1\n0.1,inf\n", r"column 'roll_rad', data row 2: inf"),
    ("t_s,roll_rad\n0,0.1\n0,0.2\n", "not strictly increasing: data row 2"),
    ("t_s,roll_rad\n0,0.1\n0.1\n", "line 3 has 1 cells"),
    ("t_s,t_s\n0,0\n1,1\n", "repeated column"),
    ("t_s,position_x_m,position_y_m\n0,1,2\n1,1,2\n", r"lacks \['position_z_m'\]"),
    ("t_s,roll_rad\n0,0.1\n", "1 data rows"),
])
def test_damaged_csv_gets_a_typed_error(tmp_path, text, match):
    p = tmp_path / "bad.csv"
    p.write_text(text)
    with pytest.raises(LogFormatError, match=match) as e:
        read_log(p)
    assert str(p) in str(e.value)


def test_binary_garbage_named_csv(tmp_path):
    p = tmp_path / "bad.csv"
    p.write_bytes(b"t_s,roll_rad\n\xff\xfe\x00\x01")
    with pytest.raises(LogFormatError, match="not a text"):
        read_log(p)


def test_damaged_parquet(tmp_path):
    import pyarrow as pa
    import pyarrow.parquet as pq
    p = tmp_path / "bad.parquet"
    p.write_bytes(b"PAR1 this is not parquet PAR1")
    with pytest.raises(LogFormatError, match="not a readable Parquet"):
        read_log(p)
    pq.write_table(pa.table({"t_s": [0.0, 1.0], "roll_rad": [0.1, None]}), p)
    with pytest.raises(LogFormatError, match=r"'roll_rad', data row 2 is empty"):
        read_log(p)
    pq.write_table(pa.table({"t_s": [0.0, 1.0], "roll_rad": ["a", "b"]}), p)
    with pytest.raises(LogFormatError, match="has type string"):
        read_log(p)


def test_parquet_without_pyarrow_says_how_to_install(tmp_path, monkeypatch):
    log = synthetic()
    path = write_log(log, tmp_path / "log.parquet", "parquet")
    real_import = builtins.__import__

    def no_pyarrow(name, *args, **kwargs):
        if name.split(".")[0] == "pyarrow":
            raise ImportError("No module named 'pyarrow'")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pyarrow)
    for call in (lambda: read_log(path), lambda: write_log(log, tmp_path / "b.parquet",
                                                            "parquet")):
        with pytest.raises(MissingDependencyError, match="pip install pyarrow"):
            call()


def test_detection_by_content_then_extension(tmp_path):
    cases = {"a.bin": b"\xbc\x02\x00", "b.ulg": b"ULog\x01\x12\x35\x01", "noext": b"\xbc",
             "c.dat": b"ULog\x01\x12\x35\x01", "d.parquet": b"PAR1", "e.csv": b"t_s\n"}
    expected = {"a.bin": "crazyflie-usd", "b.ulg": "ulog", "noext": "crazyflie-usd",
                "c.dat": "ulog", "d.parquet": "parquet", "e.csv": "csv"}
    for name, head in cases.items():
        (tmp_path / name).write_bytes(head)
        assert detect_format(tmp_path / name) == expected[name], name
    (tmp_path / "f.txt").write_bytes(b"hello")
    with pytest.raises(LogFormatError, match="unknown log format"):
        read_log(tmp_path / "f.txt")
    (tmp_path / "empty.csv").write_bytes(b"")
    with pytest.raises(LogFormatError, match="empty file"):
        read_log(tmp_path / "empty.csv")
    with pytest.raises(LogError, match="cannot open"):
        read_log(tmp_path / "missing.csv")
    with pytest.raises(InputError, match="format 'px4'"):
        read_log(tmp_path / "e.csv", format="px4")


def test_write_log_refuses_what_is_not_a_log(tmp_path):
    with pytest.raises(InputError, match="FlightLog"):
        write_log({"t": [0, 1]}, tmp_path / "x.csv", "csv")
    with pytest.raises(InputError, match="format 'xls'"):
        write_log(synthetic(), tmp_path / "x.xls", "xls")
    assert set(LOG_FORMATS) == {"crazyflie-usd", "ulog", "csv", "parquet"}


def test_docs_table_lists_every_signal_with_its_unit():
    """docs/logs.md's table of signals is SIGNALS (names, shapes and units)."""
    from pathlib import Path
    import re
    doc = (Path(__file__).resolve().parent.parent / "docs" / "logs.md").read_text()
    rows = dict(re.findall(r"^\| `(\w+)` \| \(N,(?: \d)?\) \| ([^|]+) \|", doc, flags=re.M))
    assert set(rows) == set(SIGNALS)
    for name, spec in SIGNALS.items():
        assert rows[name].strip() == spec.unit, name
        assert f"(N,{' ' + str(spec.shape[0]) if spec.shape else ''})" in \
            re.search(rf"^\| `{name}` \|[^|]+\|", doc, flags=re.M).group(0), name


def test_flightlog_refuses_a_non_mapping():
    with pytest.raises(InputError, match="signals must be a mapping"):
        FlightLog("x", "csv", [0.0, 1.0], [("roll", [0.0, 0.0])], {}, {})

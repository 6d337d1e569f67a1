"""Issue 33: identification that refuses impossible logs, log readers and writers that
refuse what they cannot hold, writers that leave no damage, and the tests that catch the
mutations the earlier tests missed (the Crazyflie gyro in deg/s, the sign of mass_change, the
compiled projection of payload_adaptive from outside the consistency cone). Oracles are
written here: the firmware's units (deg/s, V), the thrust balance m = sum f / g, the cone
m r^T Sigma_O^-1 r <= 1 - margin with Sigma_O = tr(I_O)/2 - I_O (Wensing et al. 2017)."""
import os
from pathlib import Path
import stat
import struct
import tempfile
import zlib

import casadi as ca
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
import numpy as np
import pytest

import quadcog
from quadcog.controllers.payload_adaptive import PayloadAdaptive
from quadcog.errors import IdentificationError, InputError, LogError, QuadcogError
from quadcog.identification import identify
from quadcog.identification.identified import identified_cog
from quadcog.logs import FlightLog, read_log, write_log
from quadcog.sim.prepare import as_payload_profile, check_payload_events
from quadcog.sim.timeline import PayloadProfile
from quadcog.trajectories.waypoints import MinimumSnap
from quadcog.vehicles.rotor_model import CRAZYFLIE_FIRMWARE_COMMAND
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD

set_hypothesis_home_dir(tempfile.mkdtemp(prefix="quadcog-hypothesis-"))
SETTINGS = dict(derandomize=True, database=None, deadline=None, max_examples=40,
                suppress_health_check=list(HealthCheck))
HOSTILE = st.one_of(st.none(), st.booleans(), st.integers(), st.just(10 ** 400), st.floats(),
                    st.complex_numbers(), st.binary(max_size=4), st.text(max_size=4),
                    st.lists(st.floats(), max_size=4), st.just({"a": 1}), st.just(object()),
                    st.just([[1.0, 2.0], [3.0]]))
G = CRAZYFLIE.g


def hover_log(mass=CRAZYFLIE.m, r=(0.002, -0.001), dt=0.01, T=20.0, time_scale=1.0,
              motors=None, a_z=None, full=False, rates=None, meta=None, fmt="csv", roll=None):
    """A take-off, 0.5 m hover and landing whose rotor thrusts balance ``mass`` with the CoG
    at ``r``: the moment balance [U2, U3] = m g [y_G, -x_G] through the mixer."""
    t = np.arange(0, T, dt)
    n = len(t)
    z = np.clip(np.minimum(t - 1, T - 1 - t), 0, 0.5)
    U = np.column_stack([np.full(n, mass * G), np.full(n, mass * G * r[1]),
                         np.full(n, -mass * G * r[0]), np.zeros(n)])
    f = U @ np.linalg.inv(CRAZYFLIE.mixer()).T
    u = CRAZYFLIE_FIRMWARE_COMMAND.command(f) if motors is None else np.broadcast_to(
        motors, (n, 4))
    s = {"position": np.column_stack([np.zeros((n, 2)), z]), "motor_command": u}
    if a_z is not None:
        s["acceleration"] = np.column_stack([np.zeros((n, 2)), np.full(n, a_z)])
    if full or rates is not None:
        s.update(velocity=np.zeros((n, 3)), roll=np.zeros(n) if roll is None else roll(t),
                 pitch=np.zeros(n),
                 yaw=np.zeros(n), body_rates=np.zeros((n, 3)) if rates is None else rates(t))
    return FlightLog("hover.csv", fmt, t * time_scale, s, {}, meta or {})


def test_the_hover_log_is_identified():
    res = identify(hover_log())
    assert np.allclose(res.r_G[:2], (0.002, -0.001), atol=1e-9)
    assert res.mass == pytest.approx(CRAZYFLIE.m, rel=1e-6)


# -- answers from impossible data: refused in the log's terms -----------------------------
IMPOSSIBLE = [
    ("motors off (all zero)", dict(motors=0.0), r"0 % of the weight.*motors are off"),
    ("motors negative", dict(motors=-0.1), r"'motor_command_m1' is -0.1.*0..1"),
    ("motor outputs in percent", dict(motors=40.0), r"'motor_command_m1' is 40"),
    ("a vehicle of a tenth of the weight", dict(mass=CRAZYFLIE.m / 10), r"10 % of the weight"),
    ("acceleration with gravity removed twice", dict(a_z=-G), r"averages -9.81 m/s\^2"),
    ("acceleration with gravity in it", dict(a_z=G), r"averages 9.81 m/s\^2"),
    ("time in milliseconds", dict(time_scale=1e3), r"'t_s'.*milliseconds"),
    ("time in microseconds", dict(time_scale=1e6), r"'t_s'.*microseconds"),
    ("rates beyond a gyroscope", dict(rates=lambda t: np.full((len(t), 3), 1e200)),
     r"'body_rates_p_rad_s' is 1e\+200"),
    ("rates in deg/s", dict(rates=lambda t: np.column_stack(
        [np.degrees(1.0 * np.sin(2 * np.pi * 2 * t)), np.zeros(len(t)), np.zeros(len(t))])),
     r"'body_rates_p_rad_s'.*deg/s"),
    # a 0.6 deg roll wobble at 1 Hz, its rate logged in deg/s: the rates turn 57 times too far
    ("small rates in deg/s", dict(roll=lambda t: 0.01 * np.sin(2 * np.pi * t),
                                  rates=lambda t: np.column_stack(
                                      [np.degrees(0.01 * 2 * np.pi * np.cos(2 * np.pi * t)),
                                       np.zeros(len(t)), np.zeros(len(t))])),
     r"'body_rates_p_rad_s'.*more in roll.*deg/s"),
]


@pytest.mark.parametrize("what, kw, message", IMPOSSIBLE, ids=[c[0] for c in IMPOSSIBLE])
@pytest.mark.parametrize("method", ["static", "auto"])
def test_impossible_logs_are_refused_naming_the_log_and_the_column(what, kw, message, method):
    log = hover_log(**kw)
    if method == "auto" and "rates" not in kw:
        log = hover_log(full=True, **kw)
    with pytest.raises(IdentificationError, match=message) as e:
        identify(log, method=method)
    assert "hover.csv" in str(e.value)


@settings(**SETTINGS)
@given(scale=st.sampled_from([1e-9, 1e-6, 1e-3, 1e3, 1e6, 1e9]),
       field=st.sampled_from(["velocity", "position", "acceleration", "body_rates"]))
def test_property_values_in_other_units_never_give_an_answer(scale, field):
    """A signal scaled by a unit's factor gives a refusal or a finite answer, never inf, NaN
    or a traceback; velocity and rates beyond a quadrotor's reach are refused."""
    log = hover_log(full=True, a_z=0.0)
    s = dict(log.signals)
    s[field] = s[field] + 1e-3 * scale      # an offset in the other unit
    bad = FlightLog("hover.csv", "csv", log.t, s, {}, {})
    try:
        res = identify(bad)
    except IdentificationError:
        return
    j = res.as_json()
    assert np.isfinite([j["mass"], j["mass_ci95"], *j["r_G"]]).all() and j["mass"] > 0


def test_a_baseline_of_another_vehicle_type_is_refused():
    cf = hover_log(meta={"vehicle": "Crazyflie"})
    px4 = hover_log(meta={"vehicle": "x500"})
    with pytest.raises(IdentificationError, match="same vehicle type"):
        identify(cf, baseline=px4)
    ulog = FlightLog("b.ulg", "ulog", cf.t, dict(cf.signals), {}, {"sys_name": "PX4"})
    with pytest.raises(IdentificationError, match="'px4'.*'crazyflie'|same vehicle type"):
        identify(cf, baseline=ulog)
    with pytest.raises(IdentificationError, match="identified as 'AscTec Hummingbird'"):
        identify(cf, vehicle="hummingbird")


def test_mass_change_is_the_payload_mass_with_its_sign():
    """Flown 3 g heavier than the baseline: mass_change = +3 g (the thrust balance m = sum f /
    g of each), and -3 g the other way round; the CoG shift is the difference of the two."""
    heavy = hover_log(mass=CRAZYFLIE.m + 0.003, r=(0.003, 0.0))
    base = hover_log(mass=CRAZYFLIE.m, r=(0.001, 0.0))
    up = identify(heavy, baseline=base, method="static")
    assert up.mass_change == pytest.approx(+0.003, rel=1e-6)
    assert up.r_G[0] == pytest.approx(0.002, abs=1e-9)
    down = identify(base, baseline=heavy, method="static")
    assert down.mass_change == pytest.approx(-0.003, rel=1e-6)


# -- raw exceptions: every entry point refuses wrong types with a typed error --------------
@settings(**SETTINGS)
@given(value=HOSTILE)
def test_property_entry_points_refuse_hostile_arguments(value):
    log = hover_log()
    calls = [lambda: identify(value), lambda: identify(log, vehicle=value),
             lambda: identify(log, method=value), lambda: read_log(value),
             lambda: identified_cog(value), lambda: log.signal(value),
             lambda: write_log(log, value, "csv"), lambda: write_log(value, "x.csv", "csv"),
             lambda: write_log(log, "x.csv", value), lambda: CRAZYFLIE.rotor_speeds(value),
             lambda: MinimumSnap(value), lambda: MinimumSnap([[0, 0, 0], [1, 1, 1]],
                                                              max_speed=value)]
    if value is not None:
        calls += [lambda: identify(log, baseline=value), lambda: identify(log, rotor_model=value)]
    here = os.getcwd()
    os.chdir(tempfile.mkdtemp(prefix="quadcog-hostile-"))   # a str value is a file name
    try:
        for call in calls:
            try:
                call()
            except QuadcogError:
                pass
    finally:
        os.chdir(here)
    with pytest.raises(QuadcogError):
        log.has(value) if not isinstance(value, str) else log.signal(value + "?")


@pytest.mark.parametrize("bad", [[np.nan] * 4, [np.inf] * 4, "abcd", [[1, 2], [3]], [1j] * 4])
def test_rotor_speeds_refuse_what_is_not_a_thrust(bad):
    with pytest.raises(InputError, match="f"):
        CRAZYFLIE.rotor_speeds(bad)


def test_a_fifo_or_a_device_is_never_read_as_a_log_or_a_json(tmp_path):
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)                       # opening it to read would block for ever
    for path in (fifo, Path("/dev/zero")):
        with pytest.raises(LogError, match="not a regular file"):
            read_log(path)
        with pytest.raises(IdentificationError, match="not a regular file"):
            identified_cog(path)


def test_identified_json_of_absurd_shape_is_refused(tmp_path):
    cases = {"digits": '{"r_G": [' + "1" * 401 + ", 0, 0]}",
             "deep": "[" * 200_000 + "]" * 200_000, "nan": '{"r_G": [NaN, 0, 0]}',
             "far": '{"r_G": [1e9, 0, 0]}', "text": '{"r_G": ["1", 0, 0]}'}
    for name, text in cases.items():
        p = tmp_path / f"{name}.json"
        p.write_text(text)
        with pytest.raises(IdentificationError, match=str(p)):
            identified_cog(p)


@pytest.mark.parametrize("name", ["_id", "_tick"])
def test_a_crazyflie_variable_with_a_reserved_name_is_refused(tmp_path, name):
    p = _usd(tmp_path, [(name, "f")], [[0.5], [0.5], [0.5]])
    with pytest.raises(LogError, match=f"'{name}'"):
        read_log(p)


def test_csv_cells_and_columns_beyond_reason_are_refused(tmp_path):
    p = tmp_path / "a.csv"
    for text, message in [("t_s,x\n0," + "a" * 200_000 + "\n1,2\n", "line 2"),
                          ("t_s," + "a" * 200_000 + "\n0,1\n1,2\n", "the header"),
                          ("t_s,x\n0," + "9" * 400 + "\n1,2\n", "not a finite number")]:
        p.write_text(text)
        with pytest.raises(LogError, match=message):
            read_log(p)
    n = 5000                                     # many columns: read (linear in the columns)
    p.write_text("t_s," + ",".join(f"c{k}" for k in range(n)) + "\n"
                 + "\n".join(",".join(["%d" % i] + ["1"] * n) for i in range(3)) + "\n")
    assert len(read_log(p).raw) == n


# -- silent NaN ---------------------------------------------------------------------------
@pytest.mark.parametrize("entry, value", [(9, 1e308), (6, 1e200), (3, 1e160)])
def test_the_model_at_extreme_inputs_raises_rather_than_returns_nan(entry, value):
    m = quadcog.load()
    x = np.zeros(12)
    x[entry] = value
    for call in (m.dynamics, m.linearization):
        try:
            out = call(x, HUMMINGBIRD.hover_input(), HUMMINGBIRD.parameters())
        except InputError as e:
            assert "not finite" in str(e)
            continue
        arrays = out if isinstance(out, tuple) else (out,)
        assert all(np.isfinite(a).all() for a in arrays)


# -- damage left behind -------------------------------------------------------------------
def _targets(tmp_path):
    real = tmp_path / "real.csv"
    real.write_text("keep")
    link = tmp_path / "link.csv"
    link.symlink_to(real)
    fifo = tmp_path / "fifo.csv"
    os.mkfifo(fifo)
    out = {"symlink": link, "fifo": fifo, "folder": tmp_path}
    dev = tmp_path / "dev.csv"
    try:
        os.mknod(dev, stat.S_IFCHR | 0o666, os.makedev(1, 3))      # as /dev/null
        out["device"] = dev
    except (OSError, AttributeError):
        pass
    return out, real


@pytest.mark.parametrize("fmt", ["csv", "crazyflie-usd", "ulog", "parquet"])
def test_writers_never_replace_what_is_not_a_regular_file(tmp_path, fmt):
    pytest.importorskip("pyarrow") if fmt == "parquet" else None
    log = hover_log(T=3.0)
    targets, real = _targets(tmp_path)
    for kind, target in targets.items():
        mode = os.lstat(target).st_mode
        with pytest.raises(LogError, match="regular file|folder"):
            write_log(log, target, fmt)
        assert os.lstat(target).st_mode == mode, kind
    assert real.read_text() == "keep"
    with pytest.raises(LogError, match="does not exist"):
        write_log(log, tmp_path / "missing" / "x", fmt)
    assert not [p for p in tmp_path.iterdir() if "part" in p.name]


def test_a_failed_write_leaves_the_old_file_and_no_part(tmp_path):
    target = tmp_path / "x.bin"
    target.write_bytes(b"old")
    n = 5
    far = FlightLog("far", "csv", 1e14 + np.arange(n), {"position": np.zeros((n, 3))}, {}, {})
    for fmt in ("crazyflie-usd", "ulog"):
        with pytest.raises(LogError, match="uint64"):
            write_log(far, target, fmt)
        assert target.read_bytes() == b"old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.bin"]


@pytest.mark.parametrize("fmt", ["crazyflie-usd", "ulog"])
@pytest.mark.parametrize("signal, value, message", [
    ("position", 1e39, "float32"), ("motor_pwm", 1.5, "0.."), ("motor_pwm", -0.5, "0.."),
    ("motor_command", 2.0, "0..")])
def test_binary_writers_refuse_what_their_readers_refuse(tmp_path, fmt, signal, value, message):
    n = 20
    shape = (n,) + quadcog.logs.SIGNALS[signal].shape
    s = {"position": np.zeros((n, 3)), signal: np.full(shape, value)}
    log = FlightLog("w", "csv", np.arange(n) * 0.01, s, {}, {})
    with pytest.raises(LogError, match=message):
        write_log(log, tmp_path / "w", fmt)
    assert not list(tmp_path.iterdir())


def test_identify_json_never_overwrites_a_log_a_link_or_a_fifo(tmp_path, capsys):
    from quadcog.cli import main
    log = write_log(hover_log(), tmp_path / "log.csv", "csv")
    before = log.read_bytes()
    targets, real = _targets(tmp_path)
    for target in [log] + list(targets.values()):
        mode = os.lstat(target).st_mode
        assert main(["identify", str(log), "--json", str(target)]) != 0
        assert os.lstat(target).st_mode == mode
    assert log.read_bytes() == before and real.read_text() == "keep"
    assert "Traceback" not in capsys.readouterr().err


# -- payloads: said, and linear -----------------------------------------------------------
def test_a_payload_event_after_the_end_or_far_away_is_refused():
    from quadcog import simulate
    from quadcog.controllers.registry import make_controller
    late = [{"t": 5.0, "action": "attach", "name": "a", "mass": 0.05, "position": [0, 0, 0]}]
    with pytest.raises(InputError, match="after the end of the run"):
        simulate(make_controller("adaptive"), "hover", duration=1.0,
                 payloads=late)
    far = [{"t": 0.1, "action": "attach", "name": "a", "mass": 0.05, "position": [1e5, 0, 0]}]
    with pytest.raises(InputError, match="arm lengths"):
        check_payload_events(HUMMINGBIRD, as_payload_profile(far, HUMMINGBIRD), 1.0)
    with pytest.raises(InputError, match="arm lengths"):
        HUMMINGBIRD.with_payload({"mass": 0.05, "position": [1e5, 0, 0]})


def test_payload_events_are_checked_in_one_pass(monkeypatch):
    """The check walks the events once: it never rebuilds every payload's track per event
    (PayloadProfile._tracks), which made it quadratic; and it still refuses what it must."""
    def no_tracks(self, t):
        raise AssertionError("_tracks called by the check")
    n = 400
    ev = [{"t": 0.01 * k, "action": "attach", "name": f"p{k}", "mass": 1e-4,
           "position": [0.01, 0, 0]} for k in range(n)]
    ev += [{"t": 10 + 0.01 * k, "action": "move", "name": f"p{k}", "position": [0, 0.01, 0],
            "ramp": 0.001} for k in range(n)]
    loads = as_payload_profile(ev, HUMMINGBIRD)
    monkeypatch.setattr(PayloadProfile, "_tracks", no_tracks)
    check_payload_events(HUMMINGBIRD, loads)


# -- the three mutations the tests missed ---------------------------------------------------
def _usd(tmp_path, variables, rows):
    """A Crazyflie uSD log (version 2) written here from the format (crazyflie-firmware
    usddeck.c): magic, version, one fixed-frequency event, records of (id, tick us, values)."""
    hdr = bytearray(struct.pack("<BHH", 0xBC, 2, 1)) + struct.pack("<H", 0xFFFF)
    hdr += b"fixedFrequency\x00" + struct.pack("<H", len(variables))
    for name, typ in variables:
        hdr += f"{name}({typ})".encode() + b"\x00"
    body = bytes(hdr)
    for k, row in enumerate(rows):
        body += struct.pack("<HQ", 0xFFFF, 10_000 * k)
        body += b"".join(struct.pack(f"<{typ}", v) for (_, typ), v in zip(variables, row))
    p = tmp_path / "gyro.bin"
    p.write_bytes(body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF))
    return p


def test_crazyflie_gyro_is_read_in_deg_per_s_and_vbat_in_volts(tmp_path):
    """The firmware logs gyro.x, y, z in deg/s (body frame, x forward, y left, z up, as
    quadcog's) and pm.vbat in V: 90 deg/s is pi/2 rad/s, 3.7 V is 3.7 V."""
    rows = [[90.0, -45.0, 180.0, 3.7], [30.0, 0.0, -60.0, 3.6], [0.0, 10.0, 0.0, 3.5]]
    p = _usd(tmp_path, [("gyro.x", "f"), ("gyro.y", "f"), ("gyro.z", "f"), ("pm.vbat", "f")],
             rows)
    log = read_log(p)
    deg = np.array(rows)[:, :3]
    assert np.allclose(log.signal("body_rates"), deg * np.pi / 180, rtol=1e-6)
    assert np.allclose(log.signal("battery_voltage"), np.array(rows)[:, 3], rtol=1e-6)
    assert np.allclose(log.t, [0.0, 0.01, 0.02])


def test_compiled_projection_brings_a_state_outside_the_cone_onto_it():
    """From states beyond the rim (m r^T Sigma_O^-1 r up to 50 times 1 - margin) and beyond
    the mass bounds, the compiled project() gives the point of the cone along the same r
    direction and the mass clipped, as project_numpy does: the cone is written here."""
    law = PayloadAdaptive(HUMMINGBIRD)
    I_O = np.diag([HUMMINGBIRD.Ixx, HUMMINGBIRD.Iyy, HUMMINGBIRD.Izz])
    sigma_inv = np.linalg.inv(0.5 * np.trace(I_O) * np.eye(3) - I_O)
    keep = 1.0 - law.consistency_margin
    lo, hi = law.mass_bounds * HUMMINGBIRD.m
    c_sym = ca.SX.sym("c", law.n_state)
    project = ca.Function("project", [c_sym], [law.project(c_sym)])
    rng = np.random.default_rng(3)
    for k in range(40):
        c = law.initial_state()
        c[3] = HUMMINGBIRD.m * rng.uniform(0.2, 4.5)        # both bounds exercised
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        m = min(max(c[3], lo), hi)
        rim = np.sqrt(keep / (m * d @ sigma_inv @ d))
        c[0:3] = d * rim * rng.uniform(1.01, 7.0)          # outside the cone
        out = np.array(project(c)).ravel()
        assert out[3] == pytest.approx(m)
        q = out[3] * out[0:3] @ sigma_inv @ out[0:3]
        assert q == pytest.approx(keep, rel=1e-9), k      # on the rim, not beyond
        assert np.allclose(out[0:3] / np.linalg.norm(out[0:3]), d)
        assert np.allclose(out, law.project_numpy(c.copy()))
        assert np.array_equal(out[4:], c[4:])


def test_rates_that_agree_with_the_angles_are_accepted():
    """The control of the deg/s case: the same wobble with its rate in rad/s (p = d roll/dt
    at zero pitch, the ZYX kinematics) is identified."""
    res = identify(hover_log(roll=lambda t: 0.01 * np.sin(2 * np.pi * t),
                             rates=lambda t: np.column_stack(
                                 [0.01 * 2 * np.pi * np.cos(2 * np.pi * t),
                                  np.zeros(len(t)), np.zeros(len(t))])), method="static")
    assert res.mass == pytest.approx(CRAZYFLIE.m, rel=1e-3)


@settings(**SETTINGS)
@given(seed=st.integers(0, 2 ** 32 - 1))
def test_property_payload_sample_in_one_pass_equals_the_tracks(seed):
    """PayloadProfile.sample (one pass over the events, linear) against the sum over every
    payload's track sampled at each time (the earlier payloads x samples form), for random
    attach, move (instant or sliding) and drop events at distinct times."""
    from quadcog.vehicles.payload import Payload
    rng = np.random.default_rng(seed)
    carried = (Payload(0.01, (0.01, 0.0, 0.0), (0.01, 0.02, 0.0), "c"),)
    ev, on, busy, t0 = [], ["c"], {}, 0.0
    for k in range(int(rng.integers(1, 12))):
        t0 += float(rng.uniform(0.01, 0.5))
        action = rng.choice(["attach", "move", "drop"]) if on else "attach"
        if action == "attach":
            ev.append(dict(t=t0, action="attach", name=f"p{k}", mass=float(rng.uniform(1e-3, 0.1)),
                           position=rng.uniform(-0.1, 0.1, 3).tolist(),
                           size=rng.uniform(0, 0.05, 3).tolist()))
            on.append(f"p{k}")
            continue
        name = on[int(rng.integers(len(on)))]
        if busy.get(name, -1.0) > t0:
            continue
        if action == "drop":
            on.remove(name)
            ev.append(dict(t=t0, action="drop", name=name))
        else:
            ramp = float(rng.choice([0.0, rng.uniform(0, 0.4)]))
            ev.append(dict(t=t0, action="move", name=name,
                           position=rng.uniform(-0.1, 0.1, 3).tolist(), ramp=ramp))
            busy[name] = t0 + ramp
    profile = PayloadProfile(ev, carried)
    t = np.sort(np.concatenate([rng.uniform(-0.1, t0 + 1, 50), [e["t"] for e in ev],
                                [e["t"] + e.get("ramp", 0.0) for e in ev]]))
    tracks = np.zeros((t.size, 10))
    for p, r, mask in profile._tracks(t):
        tracks[mask] += p.inertial_parameters(r[mask])
    assert np.allclose(profile.sample(t), tracks, rtol=1e-12, atol=1e-15)


def test_a_run_folder_never_replaces_a_link_with_a_file(tmp_path):
    from quadcog.files import RunFiles
    real = tmp_path / "real.json"
    real.write_text("keep")
    (tmp_path / "metrics.json").symlink_to(real)
    with pytest.raises(QuadcogError, match="symbolic link"):
        with RunFiles(tmp_path) as files:
            files.path("metrics.json").write_text("{}")
    assert (tmp_path / "metrics.json").is_symlink() and real.read_text() == "keep"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json", "real.json"]


# -- the second hostile pass: the same kinds of input, wider ---------------------------------
def _with(log, **signals):
    """``log`` with some signals replaced (a CSV log, as a user's would be)."""
    s = {k: np.array(v) for k, v in log.signals.items()}
    s.update(signals)
    return FlightLog(log.source, log.format, log.t, s, {}, dict(log.meta))


def _impossible_second_pass():
    full = hover_log(full=True)
    n, s = full.n_samples, full.signals
    noise = np.random.default_rng(0).normal(0.0, 0.01, (n, 3))
    both = np.column_stack([s["motor_command"][:, 0] * 2, np.zeros(n),
                            s["motor_command"][:, 2] * 2, np.zeros(n)])
    return [
        ("position in mm", _with(full, position=s["position"] * 1e3),
         r"'position_z_m' changes at 1000 m/s.*mm or cm"),
        ("velocity in mm/s", _with(full, velocity=noise * 1e3),
         r"'velocity_.*' integrated over 1 s.*mm/s"),
        ("velocity against the position", _with(full, velocity=np.tile([5.0, 0, 0], (n, 1))),
         r"'velocity_x_m_s' integrated over 1 s moves the vehicle 5 m"),
        ("upside down (roll = pi)", _with(full, roll=np.full(n, np.pi)),
         r"tilt the vehicle 180 deg.*upside down"),
        ("tilted 80 deg throughout", _with(full, roll=np.full(n, np.radians(80.0))),
         r"tilt the vehicle 80 deg"),
        ("acceleration in g with gravity", _with(full, acceleration=np.column_stack(
            [np.zeros((n, 2)), np.ones(n)])), r"averages 1 m/s\^2.*changes at 0 m/s\^2.*in g"),
        ("motors saturated", _with(full, motor_command=np.ones((n, 4))),
         r"'motor_command_m1' is at full scale"),
        ("motors just below full scale", _with(full, motor_command=np.full((n, 4), 0.999)),
         r"'motor_command_m1' is at full scale"),
        ("two diagonal rotors carry it", _with(full, motor_command=both), r"in yaw at"),
    ]


@pytest.mark.parametrize("method", ["static", "regression"])
def test_second_pass_impossible_logs_are_refused_in_their_terms(method):
    for what, log, message in _impossible_second_pass():
        with pytest.raises(IdentificationError, match=message) as e:
            identify(log, method=method)
        assert "hover.csv" in str(e.value), what


@pytest.mark.parametrize("method", ["static", "regression"])
def test_a_gap_in_the_time_stamps_splits_the_hover(method):
    """A log with an hour's gap in its hover (two flights in one file, a logging pause) gives
    the estimate of the same log without it (it raised LinAlgError: empty blocks, NaN)."""
    log = hover_log(full=True, T=30.0)
    t = log.t.copy()
    t[len(t) // 2:] += 3600.0
    gapped = FlightLog(log.source, log.format, t, dict(log.signals), {}, {})
    a, b = identify(log, method=method), identify(gapped, method=method)
    assert np.allclose(a.r_G, b.r_G, atol=1e-9) and b.mass == pytest.approx(a.mass, rel=1e-9)
    assert all(h is None or np.isfinite(h) for h in b.r_G_ci95)


def test_pooled_intervals_stay_finite_for_tiny_or_zero_half_widths():
    """Inverse-variance pooling of two logs: 1 / h^2 overflowed to inf for h = 1e-200 (r_G
    NaN, reported 'not a number'); the oracle is the textbook weighted mean with the weights
    scaled by the narrowest interval."""
    from dataclasses import replace

    from quadcog.identification.core import pooled_estimate
    e = identify(hover_log(full=True), method="regression").flights[0]
    for h1 in (1e-200, 0.0, 1e-3):
        a = replace(e, r_G_ci95=np.array([h1, h1, np.nan]))
        b = replace(e, r_G_ci95=np.array([3 * h1, 3 * h1, np.nan]), r_G=e.r_G + 1e-3)
        r, half, *_ = pooled_estimate([a, b])
        w = np.array([1.0, 1.0]) if h1 == 0 else np.array([1.0, 1 / 9])
        expected = (w[0] * e.r_G[:2] + w[1] * (e.r_G[:2] + 1e-3)) / w.sum()
        assert np.allclose(r[:2], expected, rtol=0, atol=1e-15)
        assert np.allclose(half[:2], h1 / np.sqrt(w.sum()), rtol=1e-12, atol=0)


def test_identify_out_onto_a_file_is_refused_before_the_work(tmp_path, capsys):
    from quadcog.cli import main
    log = write_log(hover_log(), tmp_path / "log.csv", "csv")
    afile = tmp_path / "afile"
    afile.write_text("keep")
    assert main(["identify", str(log), "--out", str(afile)]) != 0
    captured = capsys.readouterr()
    assert "not a folder" in captured.err and "mass:" not in captured.out
    assert afile.read_text() == "keep"


# trajectories: the times they are sampled at, the waypoints' cost
HOSTILE_TIMES = [True, 1 + 2j, np.array([1 + 0j, 2]), np.array([True]), "1", None, b"1",
                 [[1.0, 2.0], [3.0]], np.zeros((2, 2)), np.inf, [0.0, np.nan], 10 ** 400]


@pytest.mark.parametrize("t", HOSTILE_TIMES, ids=[repr(v)[:20] for v in HOSTILE_TIMES])
def test_trajectories_sampled_at_what_is_not_a_time_say_so(t):
    from quadcog.trajectories.analytic import Helix
    for traj in (Helix(), MinimumSnap([[0, 0, 0], [1, 0, 0]])):
        with pytest.raises(InputError, match=r"^t"):
            traj.sample(t)


@pytest.mark.parametrize("points", [None, 5, [[0, 0, 0]], [[0, 0], [1, 1]], [[0, 0, 0], [1]],
                                    "ab", np.zeros((2, 3), complex)])
def test_allocate_times_refuses_what_is_not_waypoints(points):
    from quadcog.trajectories.waypoints import allocate_times
    with pytest.raises(InputError, match="points"):
        allocate_times(points)
    with pytest.raises(InputError, match="max_speed"):
        allocate_times([[0, 0, 0], [1, 0, 0]], max_speed="1")


def test_minimum_snap_solves_the_dense_system_and_grows_linearly():
    """The sparse solve gives the coefficients of the dense system built here (the same
    constraints: ends at rest, positions at the waypoints, derivatives 1..6 continuous), and
    1,500 waypoints build in seconds (the dense 12,000 x 12,000 solve took minutes and 1 GB)."""
    import time

    from quadcog.trajectories.waypoints import N_COEF, _derivative_row
    pts = np.random.default_rng(3).normal(size=(9, 3))
    traj = MinimumSnap(pts)
    n, T = len(pts) - 1, np.diff(traj.times)
    A, b, row = np.zeros((N_COEF * n, N_COEF * n)), np.zeros((N_COEF * n, 3)), 0

    def put(seg, tau, order, value=None, sign=1.0):
        A[row, N_COEF * seg:N_COEF * (seg + 1)] += sign * _derivative_row(tau, order)
        if value is not None:
            b[row] = value
    for i in range(n):
        put(i, 0.0, 0, pts[i])
        row += 1
        put(i, T[i], 0, pts[i + 1])
        row += 1
    for order in (1, 2, 3):
        put(0, 0.0, order, 0.0)
        row += 1
        put(n - 1, T[-1], order, 0.0)
        row += 1
    for i in range(n - 1):
        for order in range(1, 7):
            put(i, T[i], order)
            put(i + 1, 0.0, order, 0.0, sign=-1.0)
            row += 1
    assert np.allclose(traj.coefficients, np.linalg.solve(A, b).reshape(n, N_COEF, 3),
                       rtol=0, atol=1e-10)
    many = np.column_stack([np.arange(1501.0), np.sin(np.arange(1501.0)), np.ones(1501)])
    start = time.perf_counter()
    MinimumSnap(many)
    assert time.perf_counter() - start < 20.0


# payloads: what is not carried, what never happens
def test_a_payload_box_beyond_reach_or_dropped_as_it_is_attached_is_refused():
    box = [{"t": 0.1, "action": "attach", "name": "a", "mass": 0.05, "position": [0.1, 0, 0],
            "size": [100.0, 100.0, 100.0]}]
    with pytest.raises(InputError, match=r"box of size \[100.0, 100.0, 100.0\].*arm lengths"):
        check_payload_events(HUMMINGBIRD, as_payload_profile(box, HUMMINGBIRD), 1.0)
    with pytest.raises(InputError, match="box of size.*arm lengths"):
        HUMMINGBIRD.with_payload({"mass": 0.05, "position": [0.1, 0, 0],
                                  "size": [100.0, 100.0, 100.0]})
    at_once = [{"t": 0.5, "action": "attach", "name": "a", "mass": 0.05,
                "position": [0.1, 0, 0]}, {"t": 0.5, "action": "drop", "name": "a"}]
    with pytest.raises(InputError, match="never carried"):
        check_payload_events(HUMMINGBIRD, as_payload_profile(at_once, HUMMINGBIRD), 1.0)


def test_a_sweep_range_wider_than_the_float_range_is_refused():
    from quadcog.errors import SweepError
    from quadcog.sweeps.spec import from_dict
    spec = {"name": "x", "scenario": "fig6", "mode": "grid", "set": {"duration": 1.0},
            "dimension": [{"key": "vehicle.m",
                           "range": {"start": -1e308, "stop": 1e308, "num": 3}}]}
    with pytest.raises(SweepError, match="stop - start overflows"):
        from_dict(spec)


@pytest.mark.parametrize("fmt", ["crazyflie-usd", "ulog"])
def test_binary_writers_refuse_times_their_stamps_would_change(tmp_path, fmt):
    """An integer-us stamp of a negative time wrapped around a uint64 (read back 0.0117 s
    steps for 0.01 s); one of t = 1e12 s was rounded to 128 us (steps of 0.0099 s). The
    oracle: what is written reads back with the same steps, or nothing is written."""
    t = np.arange(5) * 0.01
    for shift, message in ((-100.0, "before the first"), (1e12, "rounded")):
        log = FlightLog("x", "csv", t + shift, {"position": np.zeros((5, 3))}, {}, {})
        target = tmp_path / f"out{shift:g}.bin"
        with pytest.raises(LogError, match=message):
            write_log(log, target, fmt)
        assert not target.exists() and not list(tmp_path.glob("*.part"))
    back = read_log(write_log(FlightLog("x", "csv", t + 5.0, {"position": np.zeros((5, 3))},
                                        {}, {}), tmp_path / "ok.bin", fmt), format=fmt)
    assert np.allclose(np.diff(back.t), 0.01, rtol=0, atol=1e-6)


def test_ulog_writer_refuses_a_log_its_reader_refuses(tmp_path):
    log = FlightLog("x", "csv", np.arange(5) * 0.01, {"battery_voltage": np.full(5, 3.7)},
                    {}, {})
    with pytest.raises(LogError, match="time base"):
        write_log(log, tmp_path / "v.ulg", "ulog")
    assert not (tmp_path / "v.ulg").exists()


@pytest.mark.parametrize("bad", [None, 5, "hummingbird", [1.0], {"m": 1}])
def test_payload_api_refuses_what_is_not_a_vehicle_or_a_duration(bad):
    ok = [{"t": 0.5, "action": "attach", "name": "a", "mass": 0.05, "position": [0.1, 0, 0]}]
    with pytest.raises(InputError, match="vehicle"):
        as_payload_profile(ok, bad)
    with pytest.raises(InputError, match="vehicle"):
        check_payload_events(bad, as_payload_profile(ok, HUMMINGBIRD), 1.0)
    if not isinstance(bad, int) and bad is not None:      # 5 s is a duration
        with pytest.raises(InputError, match="duration"):
            check_payload_events(HUMMINGBIRD, as_payload_profile(ok, HUMMINGBIRD), bad)
    with pytest.raises(InputError, match="duration"):
        check_payload_events(HUMMINGBIRD, as_payload_profile(ok, HUMMINGBIRD), float("nan"))


def test_a_csv_log_with_a_byte_that_is_not_utf8_in_its_rows_is_a_log_error(tmp_path):
    """The cell-by-cell second reading (after numpy's parser refused a row) decoded the file
    again without the first reading's guard: a raw UnicodeDecodeError."""
    p = write_log(hover_log(T=3.0), tmp_path / "log.csv", "csv")
    data = bytearray(p.read_bytes())
    at = data.index(b"\n", len(data) // 2) + 1
    data[at:at] = b"1.0,\xe9x\n"
    p.write_bytes(bytes(data))
    with pytest.raises(LogError, match="not a text"):
        read_log(p)


def test_a_cog_change_or_a_disturbance_after_the_end_is_said():
    """Like a payload event after the end, it never happens; said as a QuadcogWarning (not
    refused: shipped scenarios are flown shorter with --set duration=..., and fig6 with its
    CoG step at 100 s flew 2 s and reported a 0.00 cm error without a word)."""
    import warnings

    from quadcog import simulate
    from quadcog.controllers.registry import make_controller
    from quadcog.errors import QuadcogWarning
    from quadcog.sim.timeline import Disturbance
    law = make_controller("adaptive")
    with pytest.warns(QuadcogWarning, match=r"cog\[0\].*after the end of the run"):
        simulate(law, "hover", duration=0.2, cog=[(5.0, [0.01, 0.0, 0.0], 0.0)])
    with pytest.warns(QuadcogWarning, match=r"disturbance\[0\].*after the end of the run"):
        simulate(law, "hover", duration=0.2,
                 disturbances=[Disturbance(t=5.0, duration=0.1, force=(1.0, 0.0, 0.0))])
    with warnings.catch_warnings():
        warnings.simplefilter("error", QuadcogWarning)
        simulate(law, "hover", duration=0.2, cog=[(0.1, [0.01, 0.0, 0.0], 0.0)])

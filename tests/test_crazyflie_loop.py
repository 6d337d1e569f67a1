"""The Crazyflie firmware in quadcog's loop: units and signs at the boundary (hand-derived
oracles), isolation of flights, the out-of-tree API, bad input."""
from pathlib import Path
import shutil
import stat

import numpy as np
import pytest

from quadcog.errors import InputError, StackError
from quadcog.sim.plant import TruthOptions
from quadcog.vehicles.vehicle import CRAZYFLIE_21

INSTALL = ("no Crazyflie firmware tree: set QUADCOG_CRAZYFLIE_FIRMWARE to a `git clone "
           "--recursive https://github.com/bitcraze/crazyflie-firmware` or put "
           "crazyflie-firmware.tar.xz in the vendor folder ($QUADCOG_VENDOR_DIR)")
OOT = Path(__file__).parent / "data" / "crazyflie_oot"


@pytest.fixture(scope="module")
def tree():
    from quadcog.crazyflie.firmware import firmware_tree
    try:
        return firmware_tree()
    except StackError as e:
        if "no Crazyflie firmware tree" in str(e):
            pytest.skip(INSTALL)
        raise


def _fly(*args, **kw):
    from quadcog.crazyflie import simulate
    return simulate(*args, **kw)


def test_pid_hover_with_cog_offset_matches_the_legacy_mixer(tree):
    """Steady cmd_roll / cmd_pitch of the firmware PID derived by hand. In a level hover
    the rotors must give U2 = m g y_G, U3 = -m g x_G about O. The legacy mixer
    (power_distribution_quadrotor.c) sets m1..m4 = T -+ r -+ p ... with r = cmd_roll / 2,
    p = cmd_pitch / 2; battery compensation makes rotor i give m_i THRUST_MAX / 65535 N; with
    M1 (h, -h), M2 (-h, -h), M3 (-h, h), M4 (h, h), h = ARM_LENGTH / sqrt(2):
    U2 = h k (-m1 - m2 + m3 + m4) = 2 h k cmd_roll, U3 = -h k (m1 - m2 - m3 + m4)
    = -2 h k cmd_pitch, k = THRUST_MAX / 65535, and 4 k cmd_thrust = m g. With motor lag:
    without it the PID's rate loop chatters between its limits once it must hold a torque."""
    x_G, y_G = 0.002, -0.003
    vehicle = CRAZYFLIE_21.with_cog([x_G, y_G, 0.0])
    res = _fly("pid", "hover", 12.0, vehicle=vehicle, truth=TruthOptions(motor_lag=True))
    assert not res.diverged
    log = {k: v[-500:].mean() for k, v in res.info["log"].items()}
    m, g, h, k = vehicle.m, vehicle.g, 0.046 / np.sqrt(2), 0.12 / 65535
    assert log["controller.cmd_roll"] == pytest.approx(m * g * y_G / (2 * h * k), abs=3)
    assert log["controller.cmd_pitch"] == pytest.approx(m * g * x_G / (2 * h * k), abs=3)
    assert log["controller.cmd_thrust"] == pytest.approx(m * g / (4 * k), rel=2e-4)
    assert np.abs(res.x[-1, :3] - [0, 0, 1]).max() < 5e-3       # hovering at the setpoint
    # the motor PWMs: the legacy mixer's thrusts through the firmware's battery compensation,
    # i.e. the inverse of the 2.1+ cubic at 4 V (quadcog's rotor model), to a few PWM counts
    T, r, p, y = (log[f"controller.cmd_{a}"] for a in ("thrust", "roll", "pitch", "yaw"))
    r, p = r / 2, p / 2
    mixed = np.array([T - r + p + y, T - r - p - y, T + r - p + y, T + r + p - y])
    pwm = 65535 * CRAZYFLIE_21.rotor_model.command(mixed * k, 4.0)
    assert np.abs(np.array([log[f"motor.m{i}"] for i in range(1, 5)]) - pwm).max() < 5


def test_flights_do_not_share_the_firmware_state(tree):
    # the PID's integrators are C statics: a flight after a very different one must be the
    # flight of a fresh process, bit for bit
    first = _fly("pid", "hover", 2.0)
    _fly("pid", "hover", 2.0, vehicle=CRAZYFLIE_21.with_cog([0.01, 0.01, 0]))
    again = _fly("pid", "hover", 2.0)
    assert np.array_equal(first.x, again.x)


@pytest.mark.parametrize("controller", ["pid", "mellinger", "indi", "lee"])
def test_each_controller_holds_a_step(tree, controller):
    res = _fly(controller, "hover", 6.0, cog=[(1.0, (0.003, 0.0, 0.0), 0.0)],
               truth=TruthOptions(motor_lag=True))
    assert not res.diverged and np.abs(res.x[-1, :3] - [0, 0, 1]).max() < 0.05


def test_out_of_tree_controller_flies_force_torque(tree):
    res = _fly(OOT, "hover", 4.0, log=("motor.m1", "motor.m3"))
    assert not res.diverged and np.abs(res.x[-1, :3] - [0, 0, 1]).max() < 0.01
    assert res.controller == "crazyflie out-of-tree crazyflie_oot"


def test_firmware_parameters_and_logs_by_name(tree):
    res = _fly("pid", "hover", 1.0, params={"posCtlPid.zKp": 0.0, "posCtlPid.zKi": 0.0,
                                            "velCtlPid.vzKp": 0.0, "velCtlPid.vzKi": 0.0},
               log=("posCtl.targetVZ",))
    assert np.all(res.info["log"]["posCtl.targetVZ"] == 0.0)
    with pytest.raises(InputError, match="no log variable 'controller.nothing'"):
        _fly("pid", "hover", 0.1, log=("controller.nothing",))
    with pytest.raises(InputError, match="no parameter 'pid_rate.nothing'"):
        _fly("pid", "hover", 0.1, params={"pid_rate.nothing": 1.0})
    with pytest.raises(InputError, match="controller"):
        _fly("pidd", "hover", 0.1)
    with pytest.raises(InputError, match="'X' frame"):
        from quadcog.vehicles.vehicle import HUMMINGBIRD
        _fly("pid", "hover", 0.1, vehicle=HUMMINGBIRD)


def _mutated(monkeypatch, old, new):
    from quadcog.crazyflie import firmware
    text = firmware.loop_source()
    assert old.encode() in text
    monkeypatch.setattr(firmware, "loop_source", lambda: text.replace(old.encode(), new.encode()))


@pytest.mark.slow
def test_a_pitch_sign_mutation_fails(tree, monkeypatch):
    _mutated(monkeypatch, "state->attitude.pitch = (float)-qc_deg(eul[1]);",
             "state->attitude.pitch = (float)qc_deg(eul[1]);")
    res = _fly("pid", "hover", 3.0, vehicle=CRAZYFLIE_21.with_cog([0.002, 0, 0]),
               truth=TruthOptions(motor_lag=True))
    assert res.diverged or np.abs(res.x[-1, :3] - [0, 0, 1]).max() > 0.05


@pytest.mark.slow
def test_a_quaternion_order_mutation_fails(tree, monkeypatch):
    # w stored in x and x in w (the order w, x, y, z instead of the firmware's x, y, z, w):
    # Lee reads a level vehicle as rolled over
    from quadcog.crazyflie import firmware
    text = firmware.loop_source()
    for old, new in ((b"attitudeQuaternion.w =", b"attitudeQuaternion.TMP ="),
                     (b"attitudeQuaternion.x =", b"attitudeQuaternion.w ="),
                     (b"attitudeQuaternion.TMP =", b"attitudeQuaternion.x =")):
        assert old in text
        text = text.replace(old, new)
    monkeypatch.setattr(firmware, "loop_source", lambda: text)
    res = _fly("lee", "hover", 2.0)
    assert res.diverged or np.abs(res.x[-1, :3] - [0, 0, 1]).max() > 0.05


def test_not_a_firmware_tree(tmp_path):
    with pytest.raises(StackError, match="is not a Crazyflie firmware tree: it has no "
                                         "src/modules/interface/stabilizer_types.h"):
        _fly("pid", "hover", 0.1, firmware=tmp_path)
    with pytest.raises(StackError, match="is not a folder"):
        _fly("pid", "hover", 0.1, firmware=tmp_path / "nothing")


def _snapshot(root):
    return {str(p.relative_to(root)): (p.stat().st_size, p.stat().st_mtime_ns)
            for p in root.rglob("*")}


def _copy(tree, tmp_path):
    copy = tmp_path / "fw"
    shutil.copytree(tree, copy, ignore=shutil.ignore_patterns("vendor", "examples", "test*"))
    # only the headers quadcog includes from vendor/
    shutil.copytree(tree / "vendor/CMSIS/CMSIS/DSP/Include", copy / "vendor/CMSIS/CMSIS/DSP/Include")
    shutil.copytree(tree / "vendor/CMSIS/CMSIS/Core/Include", copy / "vendor/CMSIS/CMSIS/Core/Include")
    return copy


def _read_only(root):
    for p in [root, *root.rglob("*")]:
        p.chmod(p.stat().st_mode & ~(stat.S_IWUSR | stat.S_IWGRP | stat.S_IWOTH))


def _writable(root):
    for p in [root, *root.rglob("*")]:
        p.chmod(p.stat().st_mode | stat.S_IWUSR)


@pytest.mark.slow
def test_a_read_only_tree_is_built_elsewhere_and_left_unchanged(tree, tmp_path):
    copy = _copy(tree, tmp_path)
    _read_only(copy)
    try:
        before = _snapshot(copy)
        res = _fly("pid", "hover", 0.5, firmware=copy)
        assert res.info["firmware"] == str(copy.resolve())
        assert _snapshot(copy) == before
    finally:
        _writable(copy)


def test_structs_that_differ_and_a_compile_error(tree, tmp_path):
    copy = _copy(tree, tmp_path)
    types = copy / "src/modules/interface/stabilizer_types.h"
    types.write_text(types.read_text().replace("attitudeQuaternion;", "attitudeQ;"))
    with pytest.raises(StackError, match="state_t has no field `attitudeQuaternion`"):
        _fly("pid", "hover", 0.1, firmware=copy)
    types.write_text(types.read_text().replace("attitudeQ;", "attitudeQuaternion;"))
    pid = copy / "src/modules/src/controller/controller_pid.c"
    pid.write_text(pid.read_text() + "\nthis is not C;\n")
    with pytest.raises(StackError, match=r"controller_pid\.c:\d+:\d+: error"):
        _fly("pid", "hover", 0.1, firmware=copy)


def test_no_compiler(tree, monkeypatch):
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.raises(StackError, match="no C compiler found"):
        _fly("pid", "hover", 0.1)


def test_quadcog_run_with_the_stack(tree, tmp_path, capsys):
    import json

    from quadcog.cli import main
    main(["run", "parcel-crazyflie", "--stack", "crazyflie", "--controller", "pid",
          "--set", "duration=3", "--set", "payload=[]", "--out", str(tmp_path), "--quiet", "--no-plot"])
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["controller"] == "crazyflie pid" and not metrics["diverged"]
    assert "tail RMS" in capsys.readouterr().out


def test_a_stack_scenario_without_the_stacks_layer_is_refused(tmp_path):
    from quadcog.errors import ScenarioError
    from quadcog.scenarios.scenario import run_file
    with pytest.raises(ScenarioError, match="key 'stack'"):
        run_file("parcel-crazyflie", tmp_path, progress=False,
                 overrides=['stack.name="crazyflie"'], plot=False)
    with pytest.raises(ScenarioError, match="stack.name"):
        run_file("parcel-crazyflie", tmp_path, progress=False,
                 overrides=['stack.name="px5"'], plot=False)


@pytest.mark.slow
def test_a_sweep_of_firmware_flights(tree, tmp_path):
    pytest.importorskip("pyarrow")
    import quadcog.crazyflie  # noqa: F401  (registers the stack)
    from quadcog.sweeps.runner import sweep
    spec = {"name": "cf", "scenario": "parcel-crazyflie", "mode": "grid", "threshold": 0.5,
            "set": {"duration": 2.0, "stack": {"name": "crazyflie"}, "payload": [],
                    "cog": [{"t": 0.5, "r": [0.0, 0.0, 0.0], "ramp": 0.0}],
                    "trajectory": {"kind": "hover"}},
            "dimension": [{"key": "stack.controller", "values": ["pid", "lee"]},
                          {"key": "cog[0].r[0]", "values": [0.0, 0.003]}]}
    res = sweep(spec, out=tmp_path, workers=1, progress=False)
    cols = res.columns
    assert list(cols["controller"]) == ["crazyflie pid"] * 2 + ["crazyflie lee"] * 2
    assert not cols["diverged"].any()
    # the same flight flown alone
    from quadcog.crazyflie.scenario import run_scenario
    from quadcog.scenarios.scenario import load_scenario
    alone = run_scenario(load_scenario("parcel-crazyflie", [
        "duration=2.0", 'stack={name="crazyflie", controller="lee"}', "payload=[]",
        "cog=[{t=0.5, r=[0.003, 0.0, 0.0], ramp=0.0}]", 'trajectory={kind="hover"}']))
    assert cols["rms_position_error"][3] == alone.metrics.rms_position_error


def test_brescianini_is_not_finite_at_an_exactly_level_hover(tree):
    # issue 30: Brescianini returns NaN torques at an exactly level attitude with zero lateral
    # error. Confirmed: in a level hover at the setpoint its control_t is NaN on some 100 Hz
    # periods, and the firmware's power distribution turns that into all motors off; with the
    # least sensing noise the attitude is never exactly level and it never happens
    from quadcog.sim.sensing import Sensing
    level = _fly("brescianini", "hover", 3.0, log=("motor.m1", "motor.m2", "motor.m3", "motor.m4"))
    assert level.info["nonfinite_control_ticks"] > 0
    pwm = np.array([level.info["log"][f"motor.m{i}"] for i in range(1, 5)])
    assert (pwm[:, 100:] == 0).all(axis=0).any()          # motors off after the start
    noisy = _fly("brescianini", "hover", 3.0, sensing=Sensing(delay=False, seed=1))
    assert noisy.info["nonfinite_control_ticks"] == 0
    assert _fly("lee", "hover", 1.0).info["nonfinite_control_ticks"] == 0

"""quadcog's laws in the firmware loop: the app's float32 C (``write_crazyflie_app``) flown as
the firmware's out-of-tree controller through its power distribution, against
``quadcog.simulate`` of the same law on the same vehicle, trajectory and CoG event.

What differs between the two loops, and what it costs (measured on this circle, 5 s, CoG ramp
of (4, -3, 0) mm from 1 s over 0.5 s, Crazyflie 2.1 with motor lag, in both):

- the firmware's first tick (stabilizerStep 1) is not a 500 Hz tick: ``control_t`` is still
  zero, the motors are off for 1 ms, the lagged rotors lose 8 % of their thrust and the
  vehicle sags; both laws recover, the positions part by at most 4.4 mm (composite, at
  0.25 s; 2.5 mm payload_adaptive) and come back together within 1 s;
- the law runs at 500 Hz (its state integrated by Euler steps of 2 ms, the command held for
  two ticks) against 1 kHz in quadcog.simulate, in float32 from the firmware's units (degrees,
  the pitch negated, the quaternion x y z w) against double;
- the command reaches the rotors through ``powerDistributionForceTorque`` (the firmware's
  ARM_LENGTH and THRUST2TORQUE, which the Crazyflie 2.1 preset is built from), the uint16 PWM
  and battery compensation (the inverse of the thrust cubic in float32), then the cubic.

After the start and the CoG event (t >= 2 s) the positions agree to 4.7e-5 m and the rotor
input U to 1.4e-5 of its scale (thrust) and 1.2e-4 (torque, one scale for its three
components), for both laws; the tolerances below are 4 to 7 times those (and 1.8 times the
start's sag). A sign error at the boundary (the pitch read from state_t, the pitch torque
written to control_t) makes the law fly another vehicle: it tilts over 85 deg within 1 s. A
setpoint without the high-level commander's jerk (which the laws feed forward) parts the
settled positions by 2.2 mm.
"""
from pathlib import Path
import shutil

import numpy as np
import pytest
from test_crazyflie_loop import INSTALL

from quadcog import simulate
from quadcog.controllers.registry import make_controller
from quadcog.errors import StackError
from quadcog.sim.plant import TruthOptions
from quadcog.vehicles.vehicle import CRAZYFLIE_21

DURATION, SETTLED = 5.0, 2.0                # s; the comparison after the start and the CoG event
COG = [(1.0, (0.004, -0.003, 0.0), 0.5)]
START_TOL = 0.008                           # m, whole flight (the 1 ms without motors)
POSITION_TOL = 2e-4                         # m, settled
U_TOL = {"thrust": 1e-4, "torque": 5e-4}    # of the largest |U| (settled)


@pytest.fixture(scope="module")
def tree():
    from quadcog.crazyflie.firmware import firmware_tree
    try:
        return firmware_tree()
    except StackError as e:
        if "no Crazyflie firmware tree" in str(e):
            pytest.skip(INSTALL)
        raise


def _loop(name):
    from quadcog.crazyflie import simulate as in_the_loop
    return in_the_loop(name, "circle", DURATION, vehicle=CRAZYFLIE_21, cog=COG)


def _quadcog(name):
    from quadcog.crazyflie.law import law_model
    return simulate(make_controller(name, vehicle=law_model(CRAZYFLIE_21)), "circle", DURATION,
                    dt=0.001, vehicle=CRAZYFLIE_21, cog=COG, truth=TruthOptions(motor_lag=True))


def _differences(a, b):
    k = int(SETTLED / 0.001)
    whole = np.linalg.norm(a.x[:, :3] - b.x[:, :3], axis=1)
    rel = lambda u, v: float(np.abs(u - v).max() / np.abs(v).max())
    Ua, Ub = a.U[k:-1], b.U[k:-1]
    return {"whole": float(whole.max()), "settled": float(whole[k:].max()),
            "thrust": rel(Ua[:, 0], Ub[:, 0]), "torque": rel(Ua[:, 1:], Ub[:, 1:])}


def _agrees(d):
    return (d["whole"] < START_TOL and d["settled"] < POSITION_TOL
            and d["thrust"] < U_TOL["thrust"] and d["torque"] < U_TOL["torque"])


@pytest.fixture(scope="module")
def reference():
    return {name: _quadcog(name) for name in ("composite", "payload_adaptive")}


@pytest.mark.parametrize("name", ["composite", "payload_adaptive"])
def test_the_app_in_the_loop_agrees_with_quadcog(tree, reference, name):
    res = _loop(name)
    assert res.controller == f"crazyflie quadcog {name}" and not res.diverged
    assert res.t.shape == reference[name].t.shape
    d = _differences(res, reference[name])
    assert _agrees(d), d
    # the firmware's own path: motor PWMs near hover (0.285 N / 4 of 0.12 N a motor, through
    # the 2.1+ cubic at 4 V), not a zero or saturated command
    pwm = np.array([res.info["log"][f"motor.m{i}"][-1] for i in range(1, 5)])
    assert np.all((pwm > 20000) & (pwm < 50000)), pwm


def _mutated_app(monkeypatch, tmp_path, old, new):
    from quadcog.crazyflie import law, loop

    def mutated(name, vehicle):
        host = tmp_path / "host"
        shutil.copytree(law.law_sources(name, vehicle), host, dirs_exist_ok=True)
        c = host / f"quadcog_cf_{name}.c"
        text = c.read_text()
        assert old in text
        c.write_text(text.replace(old, new))
        return Path(host)
    monkeypatch.setattr(loop, "law_sources", mutated)


@pytest.mark.parametrize("old, new", [
    ("x[4] = -QC_DEG_TO_RAD * state->attitude.pitch;",
     "x[4] = QC_DEG_TO_RAD * state->attitude.pitch;"),
    ("control->torqueY = U[2];", "control->torqueY = -U[2];"),
], ids=["pitch-sign", "torque-y-sign"])
def test_a_sign_error_at_the_boundary_fails_the_agreement(tree, reference, monkeypatch,
                                                          tmp_path, old, new):
    _mutated_app(monkeypatch, tmp_path, old, new)
    res = _loop("composite")
    assert res.diverged or not _agrees(_differences(res, reference["composite"]))


def test_quadcog_run_flies_a_law_on_the_stack(tree, tmp_path):
    import json

    from quadcog.cli import main
    main(["run", "parcel-crazyflie", "--stack", "crazyflie", "--controller", "payload_adaptive",
          "--set", "duration=13", "--out", str(tmp_path), "--quiet", "--no-plot"])
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["controller"] == "crazyflie quadcog payload_adaptive"
    assert not metrics["diverged"]


def test_the_setpoint_s_jerk_reaches_the_law(tree, reference, monkeypatch):
    from quadcog.crazyflie import firmware
    text = firmware.loop_source()
    jerk = b"sp->jerk.x = (float)r[9]; sp->jerk.y = (float)r[10]; sp->jerk.z = (float)r[11];"
    assert jerk in text
    monkeypatch.setattr(firmware, "loop_source", lambda: text.replace(jerk, b""))
    assert not _agrees(_differences(_loop("composite"), reference["composite"]))

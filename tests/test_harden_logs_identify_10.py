"""Tenth hostile pass on quadcog.logs and quadcog.identification: time stamps no logger
writes, thrusts of different sources compared, thrusts beyond the rotor model's fit, and the
hover window's cost on a long log of many plateaus.

- ``identify``: a log whose median step is a logger's but with samples 0.1 us after the one
  before (a stamp repeated with a jitter) was identified, or refused as "gravity counted
  twice" (the derivative of the velocity over 0.1 us); now the time column is named with
  its first short step;
- ``identify``: logs and baseline logs whose thrusts came from different rotor models or
  signals (a Crazyflie's PWM and battery voltage against the mixer's commands) were pooled
  or subtracted: a payload read as a mass that fell by 2 g (CrazyPAD E8, motor against
  controller logs), the verdict naming only the first log's source;
- ``identify``: a battery voltage in other units (37 V on a 1S Crazyflie) put every rotor
  at the largest thrust of its voltage model (beyond the fit's vertex, saturated): the
  answer was x_G = y_G = 0 +- 0 mm, "determined";
- ``hover_window`` and ``HoverWindow.blocks`` looped over the plateaus, each over every
  sample: quadratic in a long log of many plateaus (a 5 h log took 18 s, 2.5 h 3.6 s).
"""
import time

import numpy as np
import pytest

from quadcog.errors import IdentificationError
from quadcog.identification import identify
from quadcog.identification.segments import hover_window
from quadcog.logs import FlightLog
from quadcog.vehicles.rotor_model import CRAZYFLIE_BITCRAZE_VOLTAGE, CRAZYFLIE_FIRMWARE_COMMAND
from quadcog.vehicles.vehicle import CRAZYFLIE

G = CRAZYFLIE.g


def _thrusts(n, mass=CRAZYFLIE.m, r=(0.002, -0.001)):
    """Rotor thrusts (n, 4) that balance ``mass`` with the CoG at ``r`` (the mixer's moment
    balance [U2, U3] = m g [y_G, -x_G])."""
    U = np.column_stack([np.full(n, mass * G), np.full(n, mass * G * r[1]),
                         np.full(n, -mass * G * r[0]), np.zeros(n)])
    return U @ np.linalg.inv(CRAZYFLIE.mixer()).T


def _log(t=None, pwm_volts=None, source="hover.csv", noise=0.0, **extra):
    """A take-off, 0.5 m hover and landing over ``t``: motor commands, or PWM and a battery
    voltage of ``pwm_volts`` (V), with all attitude signals."""
    t = np.arange(0, 20.0, 0.01) if t is None else t
    n = len(t)
    z = np.clip(np.minimum(t - 1, t[-1] - 1 - t), 0, 0.5)
    f = _thrusts(n) * (1 + noise * np.random.default_rng(0).standard_normal((n, 4)))
    s = {"position": np.column_stack([np.zeros((n, 2)), z]),
         "velocity": np.column_stack([np.zeros((n, 2)), np.gradient(z, t)]),
         "roll": np.zeros(n), "pitch": np.zeros(n), "yaw": np.zeros(n),
         "body_rates": np.zeros((n, 3))}
    if pwm_volts is None:
        s["motor_command"] = CRAZYFLIE_FIRMWARE_COMMAND.command(f)
    else:
        s["motor_pwm"] = CRAZYFLIE_BITCRAZE_VOLTAGE.command(f, np.full(n, pwm_volts))
        s["battery_voltage"] = np.full(n, pwm_volts)
    s.update(extra)
    return FlightLog(source, "csv", t, s, {}, {})


# -- time stamps no logger writes -------------------------------------------------------------
def test_time_steps_shorter_than_any_logger_writes_are_refused_naming_the_first():
    """A third of the samples 0.1 us after the one before: the median step is 10 ms (a
    logger's), so the log was identified; the derivatives over 0.1 us are no flight's."""
    t = np.arange(0, 20.0, 0.01)
    t[1::3] = t[0::3][:len(t[1::3])] + 1e-7
    rates = 1e-2 * np.random.default_rng(1).standard_normal((len(t), 3))
    log = _log(t, noise=0.01, body_rates=rates)
    with pytest.raises(IdentificationError, match=r"hover.csv: column 't_s': sample 1 at t = "
                       r"1e-07 s follows sample 0 by 1e-07 s \(the first of 667 such step\(s\)\); "
                       r"expected steps of at least 1e-05 s"):
        identify(log, method="static")
    t = np.arange(0, 20.0, 0.01)
    t[1::3] = t[0::3][:len(t[1::3])] + 2e-5                 # 20 us: a fast logger's step
    identify(_log(t, noise=0.01), method="static")


# -- thrusts of different sources ----------------------------------------------------------------
def test_logs_and_baselines_whose_thrusts_come_from_different_sources_are_refused():
    pwm = _log(pwm_volts=3.7, source="pwm.csv")
    command = _log(source="command.csv", noise=0.01)
    with pytest.raises(IdentificationError, match=r"baseline\[0\]: expected a log whose thrust "
                       r"comes from bitcraze-voltage from motor_pwm and battery_voltage as in "
                       r"logs\[0\] \(pwm.csv\), got command.csv, whose thrust comes from "
                       r"firmware-command from motor_command"):
        identify(pwm, baseline=command, method="static")
    with pytest.raises(IdentificationError, match=r"logs\[1\]: expected a log whose thrust"):
        identify([command, pwm], method="static")
    # one source: the note on what each log lacks does not count
    other = _log(source="command2.csv", noise=0.02)
    assert identify(command, baseline=other, method="static").mass_change is not None


# -- thrusts beyond the rotor model's fit --------------------------------------------------------
def test_rotors_at_the_largest_thrust_of_their_model_are_refused():
    """PWM for 3.7 V logged with 37 V: every rotor at the voltage model's ceiling, all
    equal, which read as x_G = y_G = 0 +- 0 mm, determined."""
    log = _log(pwm_volts=3.7)
    wrong = FlightLog("volts.csv", "csv", log.t, dict(
        log.signals, battery_voltage=10 * log.signal("battery_voltage")), {}, {})
    with pytest.raises(IdentificationError, match=r"volts.csv: rotor 1 gives the largest "
                       r"thrust of rotor model 'bitcraze-voltage' \(0.1736 N\) over 100 % of "
                       r"the hover at 0.50 m.*is the battery voltage in other units\? \(column "
                       r"'battery_voltage_V' is 37 V, median\)"):
        identify(wrong, method="static")
    assert identify(log, method="static").mass == pytest.approx(CRAZYFLIE.m)


def test_the_new_helper_arguments_are_checked():
    from quadcog.identification.plausibility import hover_physics
    from quadcog.identification.segments import rotor_thrusts, thrust_source
    with pytest.raises(IdentificationError, match=r"thrust_source: description: expected a "
                       r"str, got None"):
        thrust_source(None)
    assert thrust_source("firmware-command from motor_command (the log has no motor_pwm)") \
        == "firmware-command from motor_command"
    log = _log()
    thrusts = rotor_thrusts(log, CRAZYFLIE)[0]
    with pytest.raises(IdentificationError, match=r"hover_physics: rotor_model: expected a "
                       r"RotorModel or None, got 'firmware-command'"):
        hover_physics(log, CRAZYFLIE, hover_window(log).mask, thrusts, np.zeros(len(log.t)),
                      "none", "firmware-command")


# -- cost --------------------------------------------------------------------------------------
def _plateaus(minutes):
    """``minutes`` of 5 s hovers at 0.5 m with 1 s dips to 0.2 m, at 100 Hz."""
    t = np.arange(0, 60.0 * minutes, 0.01)
    z = np.where(t % 6.0 < 5.0, 0.5, 0.2)
    return FlightLog("long.csv", "csv", t, {
        "position": np.column_stack([np.zeros((len(t), 2)), z])}, {}, {})


def _seconds(log):
    best = np.inf
    for _ in range(3):
        start = time.perf_counter()
        hover_window(log)
        best = min(best, time.perf_counter() - start)
    return best


def test_the_hover_window_of_many_plateaus_grows_linearly():
    """40 min against 160 min: a loop over the plateaus, each over every sample, took 26
    times longer for 4 times the log (0.07 s, 1.9 s); linear, about 4 times."""
    short, long = _plateaus(40), _plateaus(160)
    window = hover_window(long)
    assert len(window.segments) == 1600                 # each 5 s less 1.5 s at both ends
    blocks = window.blocks(long.t[window.mask])
    assert blocks.max() + 1 == 1600 and (blocks >= 0).all() and (np.diff(blocks) >= 0).all()
    fast, slow = _seconds(short), _seconds(long)
    assert slow < 10 * fast + 0.05, (fast, slow)


def test_the_thrust_note_names_what_the_log_lacks():
    """A PWM log without its battery voltage, thrust from the mixer's commands: the note said
    "(the log has no motor outputs)", though the log has motor_pwm."""
    from quadcog.identification.segments import rotor_thrusts
    from quadcog.vehicles.rotor_model import CRAZYFLIE_BITCRAZE_VOLTAGE as voltage_model
    n = 200
    f = _thrusts(n)
    U = f @ CRAZYFLIE.mixer().T
    log = FlightLog("pwm.csv", "csv", np.arange(n) * 0.01, {
        "motor_pwm": voltage_model.command(f, np.full(n, 3.7)),
        "thrust_command": U[:, 0], "moment_command": U[:, 1:]}, {}, {})
    _, described, _ = rotor_thrusts(log, CRAZYFLIE, voltage_model)
    assert described.endswith("(the log has no battery_voltage)"), described

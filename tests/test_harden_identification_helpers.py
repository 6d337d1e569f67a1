"""The public helpers of quadcog.identification check their own arguments.

Only ``quadcog.identify()`` checked its arguments; the helpers of its modules (segments,
estimators, plausibility, core, simulated, survey, figure) raised TypeError, IndexError,
AttributeError or numpy's errors on an argument of the wrong type or shape, or answered
silently (``missing_for(log, "x")`` read the str as a sequence of one-letter names, a negative
battery voltage was logged, an index array was read as a boolean mask). The rule tested, for
every function and argument against every hostile value: a ``quadcog.InputError`` (the
package's IdentificationError) whose one-line message starts with ``"function: argument"``
and says what was expected and what was given.
"""
import atexit
import dataclasses
import re
import shutil
import tempfile

import numpy as np
import pytest

import quadcog
from quadcog.identification import core, estimators, figure, plausibility, segments, simulated, survey
from quadcog.logs import FlightLog
from quadcog.vehicles.rotor_model import CRAZYFLIE_FIRMWARE_COMMAND
from quadcog.vehicles.vehicle import CRAZYFLIE


def _hover_log():
    """A 12 s take-off, 0.5 m hover and landing of the Crazyflie with all signals."""
    dt, T = 0.01, 12.0
    t = np.arange(0, T, dt)
    n = len(t)
    z = np.clip(np.minimum(t - 1, T - 1 - t), 0, 0.5)
    m, g = CRAZYFLIE.m, CRAZYFLIE.g
    U = np.column_stack([np.full(n, m * g), np.full(n, -m * g * 0.001),
                         np.full(n, -m * g * 0.002), np.zeros(n)])
    f = U @ np.linalg.inv(CRAZYFLIE.mixer()).T
    s = {"position": np.column_stack([np.zeros((n, 2)), z]),
         "motor_command": CRAZYFLIE_FIRMWARE_COMMAND.command(f),
         "velocity": np.zeros((n, 3)), "roll": np.zeros(n), "pitch": np.zeros(n),
         "yaw": np.zeros(n), "body_rates": np.zeros((n, 3)),
         "thrust_command": np.full(n, 0.5), "moment_command": np.zeros((n, 3))}
    return FlightLog("hover.csv", "csv", t, s, {}, {})


LOG = _hover_log()
WINDOW = segments.hover_window(LOG)
THRUSTS = segments.rotor_thrusts(LOG, CRAZYFLIE)[0]
A_Z = segments.vertical_acceleration(LOG)[0]
RESULT = quadcog.simulate(quadcog.CascadePD(CRAZYFLIE), trajectory="hover", duration=1.0)
IDENTIFIED = core.identify(LOG, method="static")
EMPTY_FOLDER = tempfile.mkdtemp(prefix="quadcog-survey-")     # no flight files
atexit.register(shutil.rmtree, EMPTY_FOLDER, True)             # made at collection: removed at exit
IDX = np.array([0, 0, 1, 1, 2, 2, -1])
VALUES = np.arange(14.0).reshape(7, 2)
BLOCKS = np.array([[1.0, 2.0], [1.5, 2.5], [0.5, 1.0], [1.2, 2.2], [0.9, 1.9]])
BLOCKS_R = np.column_stack([np.linspace(0, 1e-3, 6), np.full(6, 2e-3), np.zeros(6)])
BLOCKS_V = np.column_stack([np.r_[np.full(3, 0.5), np.full(3, -0.5)], np.zeros(6)])


class _Odd:
    """An object of no expected type."""


# -- hostile values, by what the argument is --------------------------------------------------
# a value is a factory (a generator is used up by the call that refuses it)
COMMON = {
    "None": lambda: None, "str": lambda: "position", "bytes": lambda: b"abc",
    "bool": lambda: True, "complex": lambda: 1 + 2j, "dict": lambda: {"a": 1},
    "generator": lambda: (x for x in (1.0, 2.0)), "huge int": lambda: 10 ** 400,
    "nan": lambda: float("nan"), "object": lambda: _Odd(),
}
SCALAR = {**COMMON, "inf": lambda: float("inf"), "FlightLog": lambda: LOG,
          "array": lambda: np.zeros(3), "negative": lambda: -1.0}
OBJECT = {**COMMON, "array": lambda: np.zeros(3), "int": lambda: 5}


def _arrays(valid):
    """Hostile arrays made from a valid one: other dtypes, masked, empty, NaN, inf inside."""
    valid = np.asarray(valid)

    def masked():
        m = np.zeros(valid.shape, bool)
        m.flat[0] = True
        return np.ma.masked_array(valid, mask=m)

    def with_value(x):
        def make():
            a = valid.astype(float)
            a.flat[1] = x
            return a
        return make
    return {**COMMON, "FlightLog": lambda: LOG,
            "object dtype": lambda: valid.astype(object),
            "complex dtype": lambda: valid.astype(complex),
            "bool dtype": lambda: np.ones(valid.shape, bool),
            "datetime64 dtype": lambda: np.zeros(valid.shape, "datetime64[s]"),
            "masked": masked, "empty": lambda: np.empty((0,) + valid.shape[1:]),
            "nan inside": with_value(np.nan), "inf inside": with_value(np.inf),
            "scalar": lambda: np.float64(1.0)}


def _without(table, *names):
    return {k: v for k, v in table.items() if k not in names}


def _sequence(valid_item):
    """Hostile sequences: not a list or tuple (a str, a generator), or a bad item."""
    return {**_without(COMMON, "None"), "FlightLog": lambda: LOG, "array": lambda: np.zeros(2),
            "item None": lambda: [valid_item, None], "item int": lambda: [valid_item, 3],
            "item bytes": lambda: [valid_item, b"x"]}


PATH = {**_without(COMMON, "str"), "empty str": lambda: "", "FlightLog": lambda: LOG,
        "int": lambda: 5, "array": lambda: np.zeros(2)}
TEXT = {**_without(COMMON, "str"), "FlightLog": lambda: LOG, "int": lambda: 5}
LOG_HOSTILE = {**OBJECT, "Vehicle": lambda: CRAZYFLIE}
VEHICLE_HOSTILE = {**OBJECT, "FlightLog": lambda: LOG, "preset name": lambda: "crazyflie"}
ROTOR_MODEL = {**_without(OBJECT, "None", "str"), "FlightLog": lambda: LOG}

# (function name, argument, call with the hostile value in that argument's place, hostile)
CASES = [
    ("block_means", "index", lambda v: segments.block_means(v, VALUES),
     {**_without(_arrays(IDX), "empty"), "floats": lambda: IDX.astype(float),
      "below -1": lambda: IDX - 2, "beyond the samples": lambda: IDX * 5,
      "2-D": lambda: IDX[:, None]}),
    ("block_means", "values", lambda v: segments.block_means(IDX, v),
     {**_arrays(VALUES), "one row short": lambda: VALUES[:-1]}),
    ("block_mean_ci95", "blocks", segments.block_mean_ci95,
     {**_arrays(BLOCKS), "one block": lambda: BLOCKS[:1]}),
    ("ar1_inflation", "blocks", segments.ar1_inflation, _arrays(BLOCKS)),
    ("speed_corrected", "blocks_r", lambda v: segments.speed_corrected(v, BLOCKS_V),
     {**_arrays(BLOCKS_R), "two columns": lambda: BLOCKS_R[:, :2],
      "one block": lambda: BLOCKS_R[:1]}),
    ("speed_corrected", "blocks_v", lambda v: segments.speed_corrected(BLOCKS_R, v),
     {**_without(_arrays(BLOCKS_V), "scalar"), "one row short": lambda: BLOCKS_V[:-1],
      "one column": lambda: BLOCKS_V[:, :1]}),
    ("speed_corrected", "spread", lambda v: segments.speed_corrected(BLOCKS_R, BLOCKS_V, v),
     SCALAR),
    ("body_velocity", "log", segments.body_velocity, LOG_HOSTILE),
    ("vertical_acceleration", "log", segments.vertical_acceleration, LOG_HOSTILE),
    ("commands_from_mixer", "log", lambda v: segments.commands_from_mixer(v, CRAZYFLIE),
     LOG_HOSTILE),
    ("commands_from_mixer", "vehicle", lambda v: segments.commands_from_mixer(LOG, v),
     VEHICLE_HOSTILE),
    ("rotor_thrusts", "rotor_model", lambda v: segments.rotor_thrusts(LOG, CRAZYFLIE, v),
     ROTOR_MODEL),
    ("check_arguments", "where", lambda v: segments.check_arguments(v, LOG), TEXT),
    ("HoverWindow.blocks", "t", WINDOW.blocks,
     {**_without(_arrays(LOG.t[WINDOW.mask]), "empty"), "2-D": lambda: LOG.t[:, None]}),
    ("HoverWindow.blocks", "seconds", lambda v: WINDOW.blocks(LOG.t[WINDOW.mask], v),
     {**SCALAR, "zero": lambda: 0.0}),
    ("missing_for", "log", lambda v: estimators.missing_for(v, ["position"]), LOG_HOSTILE),
    ("missing_for", "names", lambda v: estimators.missing_for(LOG, v),
     {**_sequence("position"), "unknown name": lambda: ["positon"]}),
    ("static_balance", "window", lambda v: estimators.static_balance(LOG, CRAZYFLIE, window=v),
     {**_without(OBJECT, "None"), "FlightLog": lambda: LOG,
      "another log's window": lambda: dataclasses.replace(WINDOW, mask=WINDOW.mask[:-5]),
      "empty mask": lambda: dataclasses.replace(WINDOW, mask=np.zeros_like(WINDOW.mask))}),
    ("static_balance", "rotor_model",
     lambda v: estimators.static_balance(LOG, CRAZYFLIE, rotor_model=v), ROTOR_MODEL),
    ("regression", "window", lambda v: estimators.regression(LOG, CRAZYFLIE, window=v),
     {**_without(OBJECT, "None"), "FlightLog": lambda: LOG,
      "another log's window": lambda: dataclasses.replace(WINDOW, mask=WINDOW.mask[:-5])}),
    ("regression", "rotor_model",
     lambda v: estimators.regression(LOG, CRAZYFLIE, rotor_model=v), ROTOR_MODEL),
    ("check_log", "log", plausibility.check_log, LOG_HOSTILE),
    ("hover_physics", "log",
     lambda v: plausibility.hover_physics(v, CRAZYFLIE, WINDOW.mask, THRUSTS, A_Z, "x"),
     LOG_HOSTILE),
    ("hover_physics", "vehicle",
     lambda v: plausibility.hover_physics(LOG, v, WINDOW.mask, THRUSTS, A_Z, "x"),
     VEHICLE_HOSTILE),
    ("hover_physics", "mask",
     lambda v: plausibility.hover_physics(LOG, CRAZYFLIE, v, THRUSTS, A_Z, "x"),
     {**_without(_arrays(WINDOW.mask), "bool dtype"),
      "indices": lambda: np.flatnonzero(WINDOW.mask), "one short": lambda: WINDOW.mask[:-1],
      "selects nothing": lambda: np.zeros(LOG.n_samples, bool)}),
    ("hover_physics", "thrusts",
     lambda v: plausibility.hover_physics(LOG, CRAZYFLIE, WINDOW.mask, v, A_Z, "x"),
     {**_arrays(THRUSTS), "three rotors": lambda: THRUSTS[:, :3]}),
    ("hover_physics", "a_z",
     lambda v: plausibility.hover_physics(LOG, CRAZYFLIE, WINDOW.mask, THRUSTS, v, "x"),
     {**_arrays(A_Z), "one short": lambda: A_Z[:-1]}),
    ("hover_physics", "a_from",
     lambda v: plausibility.hover_physics(LOG, CRAZYFLIE, WINDOW.mask, THRUSTS, A_Z, v), TEXT),
    ("column_name", "signal", lambda v: plausibility.column_name(LOG, v),
     {"array": lambda: np.zeros(3), "array of names": lambda: np.array(["position", "t"])}),
    ("check_types", "logs[1]", lambda v: plausibility.check_types([LOG, v], []),
     _without(LOG_HOSTILE, "generator")),
    ("check_types", "baseline[0]", lambda v: plausibility.check_types([LOG], [v]),
     _without(LOG_HOSTILE, "generator")),
    ("pooled_estimate", "estimates", core.pooled_estimate,
     {**_sequence(IDENTIFIED.flights[0]), "empty": lambda: [],
      "mixed methods": lambda: [IDENTIFIED.flights[0],
                                dataclasses.replace(IDENTIFIED.flights[0], method="regression")]}),
    ("as_logs", "what", lambda v: core.as_logs(LOG, v), TEXT),
    ("simulated_log", "result", lambda v: simulated.simulated_log(v, CRAZYFLIE),
     {**OBJECT, "FlightLog": lambda: LOG}),
    ("simulated_log", "vehicle", lambda v: simulated.simulated_log(RESULT, v), VEHICLE_HOSTILE),
    ("simulated_log", "sensing", lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, v),
     {**_without(OBJECT, "None"), "FlightLog": lambda: LOG}),
    ("simulated_log", "rate", lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, rate=v),
     {**SCALAR, "zero": lambda: 0.0}),
    ("simulated_log", "voltage",
     lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, voltage=v),
     {**COMMON, "FlightLog": lambda: LOG, "one": lambda: (4.1,), "negative": lambda: (4.1, -1.0),
      "nan": lambda: (float("nan"), 3.7), "bools": lambda: (True, False),
      "complex": lambda: (1 + 2j, 3.7), "strings": lambda: ("4.1", "3.7")}),
    ("simulated_log", "rotor_model",
     lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, rotor_model=v),
     {**_without(OBJECT, "None"), "FlightLog": lambda: LOG, "a name": lambda: "firmware-command"}),
    ("simulated_log", "seed", lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, seed=v),
     {**_without(SCALAR, "None", "huge int"), "float": lambda: 2.5}),
    ("simulated_log", "source", lambda v: simulated.simulated_log(RESULT, CRAZYFLIE, source=v),
     TEXT),
    ("flights", "root", survey.flights, PATH),
    ("survey_rows", "root", survey.survey_rows, PATH),
    ("survey_rows", "rotor_model", lambda v: survey.survey_rows(EMPTY_FOLDER, v),
     {**_without(OBJECT, "None"), "unknown name": lambda: "bogus"}),
    ("rotor_model_rows", "root", survey.rotor_model_rows, PATH),
    ("tables", "root", survey.tables, PATH),
    ("main", "argv", survey.main,
     {**_without(COMMON, "None", "generator"), "FlightLog": lambda: LOG,
      "item int": lambda: [EMPTY_FOLDER, 3], "item None": lambda: [None]}),
    ("plot_identification", "result", figure.plot_identification,
     {**OBJECT, "FlightLog": lambda: LOG,
      "no flights": lambda: dataclasses.replace(IDENTIFIED, flights=())}),
    ("plot_identification", "path", lambda v: figure.plot_identification(IDENTIFIED, v),
     _without(PATH, "None")),
    ("plot_identification", "title",
     lambda v: figure.plot_identification(IDENTIFIED, None, v), TEXT),
]

PARAMS = [pytest.param(call, where, make, id=f"{name}-{arg}-{label}")
          for name, arg, call, hostile in CASES
          for where in [f"{name}: {arg}"]
          for label, make in hostile.items()]


@pytest.mark.parametrize("call, where, make", PARAMS)
def test_a_hostile_argument_is_refused_naming_it(call, where, make, monkeypatch):
    """Every public helper, every argument, every hostile value: an InputError whose one-line
    message starts with "function: argument" and gives what was expected and what was got."""
    monkeypatch.chdir(EMPTY_FOLDER)             # a path taken as a file is written nowhere
    value = make()
    with pytest.raises(quadcog.InputError) as info:
        call(value)
    message = str(info.value)
    assert "\n" not in message
    assert re.match(rf"{re.escape(where.split('[')[0])}(\[[0-9, ]+\])?(\.\w+)?: expected .+, got ",
                    message), message


def test_a_str_is_not_a_sequence_of_signal_names():
    """missing_for(log, "position") read the str as eight one-letter names."""
    with pytest.raises(quadcog.InputError, match=r"^missing_for: names: expected a list or "
                                                 r"tuple .*, got 'position'$"):
        estimators.missing_for(LOG, "position")

"""Ninth hostile pass on quadcog.identification: results that check their own fields, the
identified JSON read as written, and the least squares that say what the data lack.

- ``Identification``, ``FlightEstimate`` and ``HoverWindow`` took any field when built
  directly (an Identification of mass -1 kg, r_G of 'abc', samples 2.5; a HoverWindow of an
  integer mask, whose entries would index samples, not mask them): now each field is checked
  in ``__post_init__``, named ``Class.field``, with the grammar of quadcog.validate;
- the identified JSON (``identified_cog``, ``--identified``, ``[vehicle] identified``): a key
  given twice was read as its last value (JSON's rule, silently); now refused by name, at any
  depth. Its other keys (``JSON_KEYS``) are held to the Identification's own checks (a
  negative half-width, ``samples`` 0 were accepted);
- ``regression``: ``min_tilt=0`` on a level hover raised numpy's LinAlgError (a singular
  regressor); a ``filter_rate`` other than the default kept the default's warm-up (the first
  0.25 s left out whatever the filter), and a rate of 1e300 was taken; the messages of an
  unknown vehicle, method or rotor model now say ``"name: expected ..., got ..."``;
- ``identify``: the same flight given twice (two files of one flight, or a log as its own
  baseline) was pooled as two, narrowing the intervals without a new sample.
"""
import dataclasses
import json
import re

import numpy as np
import pytest
from test_harden_identification_helpers import LOG, WINDOW

from quadcog.errors import IdentificationError
from quadcog.identification import identified_cog, identify
from quadcog.identification.estimators import regression
from quadcog.identification.segments import HoverWindow, rotor_thrusts
from quadcog.vehicles.vehicle import CRAZYFLIE

RESULT = identify(LOG, method="static")
ESTIMATE = RESULT.flights[0]


# -- results check their fields ----------------------------------------------------------------
@pytest.mark.parametrize("field, value, message", [
    ("r_G", "abc", r"Identification.r_G: expected 3 finite numbers \(m\), got 'abc'"),
    ("r_G", (0.0, np.nan, 0.0), r"Identification.r_G: expected 3 finite numbers"),
    ("r_G", (0.0, 0.0), r"Identification.r_G: expected 3 finite numbers \(m\), got \(0.0, 0.0\)"),
    ("r_G", (1e7, 0.0, 0.0), r"Identification.r_G: expected 3 numbers within \+-1e\+06 m"),
    ("r_G_ci95", (1e-4, -1e-4, None), r"Identification.r_G_ci95\[1\]: expected a number >= 0"),
    ("r_G_ci95", (1e-4, None), r"Identification.r_G_ci95: expected 3 half-widths"),
    ("r_G_ci95", (np.inf, None, None), r"Identification.r_G_ci95\[0\]: expected a number"),
    ("mass", -1.0, r"Identification.mass: expected a number in \(0.0, 1000000.0\] \(kg\)"),
    ("mass", True, r"Identification.mass: expected .*, got True"),
    ("mass", None, r"Identification.mass: expected .*, got None"),
    ("mass_ci95", np.nan, r"Identification.mass_ci95: expected a number >= 0"),
    ("mass_change", "1", r"Identification.mass_change: expected .*, got '1'"),
    ("samples", 2.5, r"Identification.samples: expected an integer >= 1, got 2.5"),
    ("samples", 0, r"Identification.samples: expected an integer >= 1, got 0"),
    ("identifiable", "x_G", r"Identification.identifiable: expected distinct names"),
    ("identifiable", ("x_G", "w_G"), r"Identification.identifiable\[1\]: expected one of x_G"),
    ("identifiable", ("x_G", "x_G"), r"Identification.identifiable: expected distinct names"),
    ("method", None, r"Identification.method: expected a str, got None"),
    ("verdict", b"ok", r"Identification.verdict: expected a str, got b'ok'"),
    ("flights", (LOG,), r"Identification.flights\[0\]: expected a FlightEstimate"),
    ("baseline", "abc", r"Identification.baseline: expected a list or tuple of FlightEstimate"),
    ("condition", 0.0, r"Identification.condition: expected a positive number"),
    ("condition", np.inf, r"Identification.condition: expected a positive number"),
])
def test_an_identification_checks_its_fields(field, value, message):
    """Built directly (or by dataclasses.replace) an Identification took any value: its
    summary, as_json and identified_cog then failed raw or answered nonsense."""
    with pytest.raises(IdentificationError, match=message):
        dataclasses.replace(RESULT, **{field: value})


def test_an_identification_keeps_what_identify_gives():
    same = dataclasses.replace(RESULT)
    assert same.as_json() == RESULT.as_json() and same.summary() == RESULT.summary()
    assert isinstance(same.r_G, tuple) and all(type(v) is float for v in same.r_G)
    assert identified_cog(same).tolist() == list(RESULT.r_G)


@pytest.mark.parametrize("field, value, message", [
    ("source", None, r"FlightEstimate.source: expected a str"),
    ("method", "magic", r"FlightEstimate.method: expected 'static' or 'regression'"),
    ("blocks_r", np.zeros((3, 2)), r"FlightEstimate.blocks_r: expected an array of shape "
                                   r"\(B, 3\)"),
    ("blocks_m", np.array([1.0, np.nan, 1.0]), r"FlightEstimate.blocks_m\[1\]: expected a "
                                                r"finite number"),
    ("blocks_v", np.zeros((2, 2)), r"FlightEstimate.blocks_v: expected an array of shape "
                                   r"\(B, 2\) with B = "),
    ("r_G", np.zeros(4), r"FlightEstimate.r_G: expected an array of shape \(3,\)"),
    ("r_G_ci95", np.array([1e-4, -1.0, np.nan]), r"FlightEstimate.r_G_ci95: expected 3 "
                                                  r"half-widths"),
    ("r_G_ci95", np.array([np.inf, 0.0, np.nan]), r"FlightEstimate.r_G_ci95: expected 3 "
                                                   r"half-widths"),
    ("mass", 0.0, r"FlightEstimate.mass: expected a positive number \(kg\)"),
    ("mass_ci95", -1.0, r"FlightEstimate.mass_ci95: expected a number >= 0 \(kg\)"),
    ("samples", -1, r"FlightEstimate.samples: expected an integer >= 0"),
    ("t", "abc", r"FlightEstimate.t: expected an array of shape \(B,\)"),
    ("moment", np.zeros((2, 2)), r"FlightEstimate.moment: expected an array of shape \(B, 2\)"),
    ("weight", np.zeros(1), r"FlightEstimate.weight: expected an array of shape \(B,\)"),
    ("condition", -1.0, r"FlightEstimate.condition: expected a positive number"),
    ("rotor", 5, r"FlightEstimate.rotor: expected a str, got 5"),
    ("notes", "a note", r"FlightEstimate.notes: expected a list or tuple of str"),
    ("notes", ("a", 1), r"FlightEstimate.notes\[1\]: expected a str, got 1"),
])
def test_a_flight_estimate_checks_its_fields(field, value, message):
    with pytest.raises(IdentificationError, match=message):
        dataclasses.replace(ESTIMATE, **{field: value})
    assert dataclasses.replace(ESTIMATE).r_G.tolist() == ESTIMATE.r_G.tolist()


@pytest.mark.parametrize("field, value, message", [
    ("mask", WINDOW.mask.astype(int), r"HoverWindow.mask: expected a one-dimensional bool "
                                      r"array"),
    ("mask", WINDOW.mask[:, None], r"HoverWindow.mask: expected a one-dimensional bool"),
    ("mask", list(WINDOW.mask), r"HoverWindow.mask: expected a one-dimensional bool"),
    ("segments", ((3.0, 2.0),), r"HoverWindow.segments\[0\]: expected start <= end"),
    ("segments", ((1.0, 2.0), (1.5, 3.0)), r"HoverWindow.segments\[1\]: expected start <= "
                                           r"end, after the segment before"),
    ("segments", ((0.0, np.nan),), r"HoverWindow.segments\[0\]\[1\]: expected a finite"),
    ("segments", "abc", r"HoverWindow.segments: expected a list or tuple"),
    ("height", np.inf, r"HoverWindow.height: expected a finite real number \(m\)"),
])
def test_a_hover_window_checks_its_fields(field, value, message):
    """An integer mask (sample indices) was taken for a window; an integer array indexes a
    log's samples where a bool mask selects them, so the estimators read other samples."""
    with pytest.raises(IdentificationError, match=message):
        dataclasses.replace(WINDOW, **{field: value})
    assert isinstance(dataclasses.replace(WINDOW), HoverWindow)


# -- the identified JSON, as written -----------------------------------------------------------
GOOD = {"r_G": [0.002, -0.001, 0.0], "r_G_ci95": [1e-4, 1e-4, None], "mass": 0.03,
        "mass_ci95": 1e-4, "mass_change": None, "samples": 100, "identifiable": ["x_G", "y_G"]}


@pytest.mark.parametrize("text, key", [
    ('{"r_G": [0.002, 0, 0], "r_G": [0.5, 0, 0]}', "r_G"),
    ('{"r_G": [0.002, 0, 0], "mass": 0.03, "mass": 30}', "mass"),
    ('{"r_G": [0.002, 0, 0], "note": {"by": "a", "by": "b"}}', "by"),
    ('{"r_G": [0.002, 0, 0], "r\\u005fG": [0.5, 0, 0]}', "r_G"),
])
def test_identified_json_with_a_key_given_twice_is_refused(tmp_path, text, key):
    """json.loads keeps a repeated key's last value: {"r_G": a, "r_G": b} was read as b,
    whichever the user meant; the key is named, at any depth, however it is escaped."""
    p = tmp_path / "id.json"
    p.write_text(text)
    with pytest.raises(IdentificationError, match=rf"^{re.escape(str(p))}: key '{key}': "
                                                  r"expected once in the identification .*, "
                                                  r"got it twice"):
        identified_cog(p)


@pytest.mark.parametrize("key, value, message", [
    ("r_G_ci95", [1e-4, -1e-4, None], r"key 'r_G_ci95'\[1\]: expected a number >= 0"),
    ("r_G_ci95", "wide", r"key 'r_G_ci95': expected 3 half-widths"),
    ("samples", 0, r"key 'samples': expected an integer >= 1, got 0"),
    ("samples", 10.5, r"key 'samples': expected an integer >= 1, got 10.5"),
    ("identifiable", ["w_G"], r"key 'identifiable'\[0\]: expected one of x_G, y_G, z_G"),
    ("mass_change", 1e300, r"key 'mass_change': expected a number in"),
    ("mass_ci95", -1, r"key 'mass_ci95': expected a number >= 0"),
])
def test_identified_json_keys_are_held_to_the_identifications_checks(tmp_path, key, value,
                                                                     message):
    """Only r_G and mass were checked: a file with a negative half-width or 0 samples is
    no identification quadcog wrote, and none to trust. Null or absent is accepted."""
    p = tmp_path / "id.json"
    p.write_text(json.dumps(dict(GOOD, **{key: value})))
    with pytest.raises(IdentificationError, match=rf"^{re.escape(str(p))}: {message}"):
        identified_cog(p)
    p.write_text(json.dumps(dict(GOOD, **{key: None})))
    assert identified_cog(p).tolist() == GOOD["r_G"]


def test_identified_json_that_is_no_object_is_refused(tmp_path):
    p = tmp_path / "id.json"
    p.write_text("[0.002, 0, 0]")
    with pytest.raises(IdentificationError, match=r"expected the identification .*: an "
                                                  r"object with the key 'r_G', got "
                                                  r"\[0.002, 0, 0\]"):
        identified_cog(p)


# -- the least squares -------------------------------------------------------------------------
def test_regression_of_a_level_hover_with_z_g_forced_in_says_what_is_missing():
    """min_tilt=0 puts z_G's column, all zeros at a level hover, in the least squares:
    numpy's LinAlgError 'Singular matrix' was raised."""
    with pytest.raises(IdentificationError, match=r"^hover.csv: the flight does not determine "
                                                  r"x_G, y_G, z_G by least squares: the scaled "
                                                  r"regressor's condition number is inf"):
        regression(LOG, CRAZYFLIE, min_tilt=0.0)


def test_regression_warm_up_follows_its_filter_rate():
    """The warm-up, 5 / filter_rate as documented, stayed the default's 0.25 s whatever the
    rate: with lam = 1/s the first 5 s of the filter's start-up were fitted."""
    default = regression(LOG, CRAZYFLIE)
    slow = regression(LOG, CRAZYFLIE, filter_rate=2.0)
    assert "first 0.25 s of the window" in default.notes[1]
    assert "first 2.5 s of the window" in slow.notes[1]
    assert slow.samples == default.samples - 225            # 2.25 s more at 100 Hz
    with pytest.raises(IdentificationError, match=r"too few samples for the least squares "
                                                  r"\(0 in 0 blocks of 1 s after the filter's "
                                                  r"warm-up of 500 s\)"):
        regression(LOG, CRAZYFLIE, filter_rate=0.01)


@pytest.mark.parametrize("rate", [1e300, 1e7, 0.0, -1.0])
def test_regression_filter_rate_within_the_models_scale(rate):
    with pytest.raises(IdentificationError, match=r"^regression: filter_rate: expected a "
                                                  r"number in \(0.0, 1000000.0\] \(1/s\)"):
        regression(LOG, CRAZYFLIE, filter_rate=rate)


@pytest.mark.parametrize("call, message", [
    (lambda: identify(LOG, "x900"), r"^vehicle: expected a preset name \(hummingbird, "
                                    r"crazyflie, .*\) or a quadcog Vehicle, got 'x900'$"),
    (lambda: identify(LOG, method="best"), r"^method: expected one of auto, static, "
                                           r"regression, got 'best'$"),
    (lambda: rotor_thrusts(LOG, CRAZYFLIE, "nope"), r"^rotor_model: expected a name of "
                                                     r"bitcraze-voltage, .* or a RotorModel, "
                                                     r"got 'nope'$"),
])
def test_unknown_names_are_said_in_the_grammar_of_bad_input(call, message):
    """Were 'vehicle 'x900' is unknown; expected ...', outside "where: expected, got"."""
    with pytest.raises(IdentificationError, match=message):
        call()


def test_a_flight_given_twice_is_refused(tmp_path):
    """The same flight twice was pooled as two: the samples doubled and the intervals
    narrowed by about 1/sqrt(2) without a new sample; as its own baseline it gave a shift of
    exactly 0 with an interval. Found by its samples, whatever the file or source is called."""
    from quadcog.logs import write_log
    a = write_log(LOG, tmp_path / "a.csv", "csv")
    b = write_log(LOG, tmp_path / "copy.parquet", "parquet")
    with pytest.raises(IdentificationError, match=r"^logs\[1\]: expected a flight not given "
                                                  r"before, got .*copy.parquet, the same "
                                                  r"samples as logs\[0\]"):
        identify([a, b], method="static")
    with pytest.raises(IdentificationError, match=r"^baseline\[0\]: expected a flight not "
                                                  r"given before, got hover.csv, the same "
                                                  r"samples as logs\[0\]"):
        identify(LOG, baseline=LOG, method="static")
    other = dataclasses.replace(LOG, t=LOG.t + 100.0)      # another flight (its own times)
    assert identify([LOG, other], method="static").samples == 2 * RESULT.samples

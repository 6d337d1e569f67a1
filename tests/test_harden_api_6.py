"""Issue 33, sixth hostile pass: payloads, identification helpers, the animate, export and
px4 commands' paths and the AdaptiveQuadBench vehicle converter. Each test states the general
rule: a bad input is a typed quadcog error naming it, never a raw traceback, a NaN or a file
written before the refusal. Oracles are written here (Path("") is the current folder; the
parallel-axis term m r^2 of r = 1e300 m overflows; 4 k_eta omega_max^2 must exceed m g)."""
import os

import numpy as np
import pytest

from quadcog.aqb.convert import euler_zyx, motor_speeds, vehicle_from_quad_params
from quadcog.aqb.protocol import AQB_QUAD_PARAMS
from quadcog.cli import main
from quadcog.errors import IdentificationError, InputError, ParameterError, Px4Error, QuadcogError
from quadcog.identification.identified import identified_cog
from quadcog.identification.plausibility import check_types, column_name, vehicle_type
from quadcog.identification.segments import t_quantile
from quadcog.logs import FlightLog
from quadcog.px4.tree import find_source
from quadcog.sim.timeline import PayloadProfile
from quadcog.vehicles.payload import Payload, check_reach
from quadcog.viz.animation import animate_run, read_run

HOSTILE = [None, "abc", b"abc", True, 1j, np.zeros((2, 2)), np.array(1.0),
           np.ma.masked_array([1.0], mask=[True]), 10 ** 400, float("nan"), [], {}, object()]


def _log():
    t = np.arange(0.0, 1.0, 0.01)
    return FlightLog("hover.csv", "csv", t, {"position": np.zeros((t.size, 3))}, {}, {})


# -- paths: an empty one is no path (Path("") is the current folder) ------------------------
@pytest.mark.parametrize("argv", [
    ["export", "--controller", "pd", "--out", ""],
    ["run", "parcel-hover", "--out", ""],
    ["animate", ""],
    ["animate", "x", "--out", ""],
    ["px4", "parcel-hover", "--px4", ""],
])
def test_an_empty_path_option_is_refused_and_nothing_is_written(argv, tmp_path, monkeypatch,
                                                                capsys):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2
    assert "empty string" in capsys.readouterr().err
    assert os.listdir(tmp_path) == []


def test_a_build_that_would_be_refused_is_refused_before_the_app_is_written(tmp_path,
                                                                            monkeypatch,
                                                                            capsys):
    monkeypatch.chdir(tmp_path)
    argv = ["export", "--controller", "pd", "--target", "crazyflie", "--build",
            "--firmware", str(tmp_path / "no_such_tree"), "--out", "app"]
    assert main(argv) == 2
    assert "error" in capsys.readouterr().err
    assert not (tmp_path / "app").exists()


@pytest.mark.parametrize("path, kind", [(os.devnull, "a device"), ("", "path")])
def test_run_folders_and_px4_trees_say_what_the_path_is(path, kind):
    with pytest.raises(InputError, match=kind):
        read_run(path)
    with pytest.raises(Px4Error, match=kind):
        find_source(path)


@pytest.mark.parametrize("value", HOSTILE + [""])
def test_animate_refuses_what_is_no_path(value, tmp_path):
    with pytest.raises(InputError):
        animate_run(value)
    with pytest.raises(InputError):
        animate_run(tmp_path, value)


# -- payloads: no NaN from a position beyond the model's scale, typed errors -----------------
def test_payload_positions_beyond_the_scale_are_refused_not_nan():
    moved = PayloadProfile([
        {"t": 0.0, "action": "attach", "name": "a", "mass": 0.01, "position": (0, 0, 0)},
        {"t": 1.0, "action": "move", "name": "a", "position": (1e300, 0.0, 0.0)}])
    with pytest.raises(ParameterError, match="1e"):
        moved.sample([0.0, 1.0, 2.0])
    p = Payload(0.01, (0.0, 0.0, 0.0))
    for bad in ([[1e300, 0, 0]], [[np.nan, 0, 0]], np.zeros(3), "abc", None):
        try:
            out = p.inertial_parameters(bad) if bad is not None else None
        except QuadcogError:
            continue
        assert bad is None and out is None


@pytest.mark.parametrize("value", [v for v in HOSTILE if v is not None] + [-1.0, 0.0])
def test_check_reach_refuses_every_hostile_argument_typed(value):
    if not isinstance(value, float):          # a number is a position of the wrong shape
        with pytest.raises(QuadcogError):
            check_reach(value, None, 0.1, "payload 'x'")
        with pytest.raises(QuadcogError):
            check_reach((0, 0, 0), value, 0.1, "payload 'x'")
    if not (isinstance(value, np.ndarray) and value.shape == ()):   # array(1.0): a 1 m arm
        with pytest.raises(QuadcogError):
            check_reach((0, 0, 0), None, value, "payload 'x'")


def test_a_payload_name_is_a_plain_str():
    assert type(Payload(0.01, (0, 0, 0), name=np.str_("box")).name) is str


# -- identification: helpers that took anything and answered ---------------------------------
@pytest.mark.parametrize("text, message", [
    ('{"r_G": [[0.001], [0], [0]]}', "r_G"),
    ('{"r_G": [0, 0, 0], "mass": 1e300}', "mass"),
])
def test_identified_json_of_another_shape_or_mass_is_refused(text, message, tmp_path):
    path = tmp_path / "id.json"
    path.write_text(text)
    with pytest.raises(IdentificationError, match=message):
        identified_cog(path)


@pytest.mark.parametrize("value", HOSTILE + [0, -1, 2.5])
def test_identification_helpers_refuse_hostile_arguments(value):
    log = _log()
    if type(value) is int and value > 1:       # 10**400: the normal quantile, no TypeError
        assert t_quantile(value) == pytest.approx(1.959964, rel=1e-6)
    else:
        with pytest.raises(IdentificationError):
            t_quantile(value)
    with pytest.raises(IdentificationError):
        column_name(log, "position", -1 if value is None else 3 if type(value) is int
                    and value == 0 else value)       # position has components 0, 1, 2
    with pytest.raises(IdentificationError):
        column_name(value, "position")
    with pytest.raises(IdentificationError):
        vehicle_type(value)
    with pytest.raises(IdentificationError):
        check_types([log], [], value if value is not None else "crazyflie")


# -- AdaptiveQuadBench's quad_params: impossible rotors named by key ------------------------
@pytest.mark.parametrize("changes, key", [
    ({"rotor_speed_max": 1e300}, "rotor_speed_max"),
    ({"rotor_speed_min": 1e300}, "rotor_speed_min"),
    ({"rotor_speed_max": 10.0}, "rotor_speed_max"),       # lifts less than its weight
    ({"mass": 1e3}, "mass"),
])
def test_quad_params_of_rotors_that_cannot_be_are_refused(changes, key):
    with pytest.raises(ParameterError, match=key):
        vehicle_from_quad_params({**AQB_QUAD_PARAMS, **changes})


@pytest.mark.parametrize("value", HOSTILE)
def test_converter_functions_refuse_hostile_arguments(value):
    vehicle = vehicle_from_quad_params(AQB_QUAD_PARAMS)
    with pytest.raises(InputError):
        euler_zyx(value)
    with pytest.raises(InputError):
        motor_speeds(value, [1.0, 0.0, 0.0, 0.0])
    with pytest.raises(InputError):
        motor_speeds(vehicle, value)

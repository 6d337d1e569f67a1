"""Issue 33, fourth hostile pass: what the third pass found and left, fixed.

- an empty path: ``identified_cog("")`` and ``quadcog identify ""`` named the current folder
  ('.', "is a folder" / "no such log file") instead of the empty argument;
- a CSV log whose time spans beyond a float printed numpy's overflow warnings before its
  error;
- a run folder's vehicle.json without fields, or with rotor positions that are not a list:
  "missing 15 required positional arguments", "'int' object is not iterable";
- a sweep value of 401 digits was printed in full in the message;
- a ULog that quadcog wrote from a Crazyflie flight named the vehicle "quadcog", so
  ``identify(..., vehicle="crazyflie")`` refused it as another vehicle type.
"""
import dataclasses
import json
import warnings

import pytest

import quadcog
from quadcog.cli import main
from quadcog.errors import IdentificationError, InputError, LogError, LogFormatError, SweepError
from quadcog.identification import identify
from quadcog.identification.identified import identified_cog
from quadcog.identification.plausibility import vehicle_type
from quadcog.identification.simulated import simulated_log
from quadcog.logs import read_log, write_log
from quadcog.logs.samples import resolve_log_argument
from quadcog.sweeps.spec import load_sweep
from quadcog.vehicles.vehicle import CRAZYFLIE
from quadcog.viz.animation import read_run


def test_an_empty_path_is_named_as_empty(capsys):
    with pytest.raises(IdentificationError, match="got ''"):
        identified_cog("")
    with pytest.raises(LogError, match="got ''"):
        resolve_log_argument("")
    assert main(["identify", ""]) != 0
    err = capsys.readouterr().err
    assert "got ''" in err and "'.'" not in err and ".: " not in err


def test_a_time_span_beyond_a_float_is_refused_without_numpy_warnings(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("t_s,x_m\n-1e308,0\n1e308,0\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error")           # numpy's overflow warning would raise here
        with pytest.raises(LogFormatError, match="beyond the range of a float"):
            read_log(p)


@pytest.fixture(scope="module")
def run_folder(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    assert main(["run", "fig6", "--out", str(out), "--no-plot", "--quiet",
                 "--set", "duration=0.5"]) == 0
    return out


@pytest.mark.parametrize("change, message", [
    (lambda d: (d.pop("m"), d.pop("Ixx")), r"missing vehicle field\(s\) \['m', 'Ixx'\]"),
    (lambda d: d.update(rotor_positions=5), "key 'rotor_positions'"),
    (lambda d: d.update(m="abc"), "m must be a number"),
])
def test_a_broken_vehicle_json_names_its_key(run_folder, tmp_path, change, message):
    for name in ("metrics.json", "vehicle.json", "trajectory.csv"):
        (tmp_path / name).write_bytes((run_folder / name).read_bytes())
    data = json.loads((tmp_path / "vehicle.json").read_text())
    change(data)
    (tmp_path / "vehicle.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match=message):
        read_run(tmp_path)


def test_a_huge_sweep_value_is_not_printed_in_full(tmp_path):
    digits = "1" * 401
    p = tmp_path / "big.toml"
    p.write_text(f'name = "big"\nscenario = "fig6"\nmode = "grid"\n[[dimension]]\n'
                 f'key = "duration"\nvalues = [1.0, {digits}]\n')
    with pytest.raises(SweepError) as info:
        load_sweep(p)
    assert "an integer of 401 digits" in str(info.value) and digits not in str(info.value)


def test_a_ulog_written_from_a_crazyflie_flight_is_identified_as_one(tmp_path):
    result = quadcog.simulate(quadcog.CascadePD(CRAZYFLIE), trajectory="hover", duration=6.0)
    log = simulated_log(result, CRAZYFLIE)
    named, anonymous = tmp_path / "cf.ulg", tmp_path / "anonymous.ulg"
    write_log(log, named, "ulog")
    write_log(dataclasses.replace(log, meta={}), anonymous, "ulog")
    assert vehicle_type(read_log(named)) == "crazyflie"
    assert vehicle_type(read_log(anonymous)) is None     # quadcog's placeholder names none
    for path in (named, anonymous):
        assert abs(identify([path], vehicle="crazyflie").r_G[0]) < 1e-3

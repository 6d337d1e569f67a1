"""Scenario files: every key validated with the file, the key and what was expected."""
import json
from pathlib import Path
import subprocess
import sys
import tomllib

import numpy as np
import pytest

from quadcog.cli import main
from quadcog.scenarios.scenario import ScenarioError, load_scenario, parse, run_file
from quadcog.studies.paper import CLAIMS, scenario_path

ROOT = Path(__file__).resolve().parent.parent
BASE = {"name": "t", "controller": "fl", "duration": 1.0}


@pytest.mark.parametrize("data, message", [
    (dict(BASE, colour="red"), "key 'colour': unknown; expected one of"),
    (dict(BASE, duration="long"), "key 'duration': expected a finite real number, got 'long'"),
    (dict(BASE, duration=-2.0), r"key 'duration': expected a positive number \(s\), got -2.0"),
    (dict(BASE, controller="lqr"), "key 'controller': expected one of 'pd', 'fl', 'adaptive'"),
    ({"name": "t", "controller": "fl"}, "missing key 'duration'"),
    (dict(BASE, trajectory={"kind": "square"}), "trajectory.kind': expected one of 'hover'"),
    (dict(BASE, trajectory={"kind": "circle", "radius": "big"}),
     "trajectory.radius': expected a finite real number"),
    (dict(BASE, trajectory={"kind": "hover", "radius": 1.0}), "unknown for kind 'hover'"),
    (dict(BASE, trajectory={"kind": "circle", "radius": -1.0}), "circle radius: expected a positive number, got -1.0"),
    (dict(BASE, cog=[{"t": 2.0, "r": [0.01, 0, 0]}, {"t": 1.0, "r": [0, 0, 0]}]),
     "cog\\[1\\].t': expected entries in time order"),
    (dict(BASE, cog=[{"t": 1.0, "r": [0.01, 0]}]), "cog\\[0\\].r': expected an array of 3"),
    (dict(BASE, cog=[{"t": 1.0}]), "cog\\[0\\]': missing key 'r'"),
    (dict(BASE, cog=[{"t": 1.0, "r": [0, 0, 0], "speed": 2}]), "cog\\[0\\].speed': unknown"),
    (dict(BASE, disturbance=[{"t": 1.0, "duration": -1.0}]), "disturbance duration: expected a positive number"),
    (dict(BASE, vehicle={"mass": 1.0}), "vehicle.mass': unknown vehicle field"),
    (dict(BASE, vehicle={"m": -1.0}), "m = -1.0 must be > 0"),
    (dict(BASE, controller_params={"gamma": 0.1}), "unknown for controller 'fl'"),
    (dict(BASE, truth={"parallel_axis": "yes"}), "truth.parallel_axis': expected true or false"),
    (dict(BASE, limits={"max_tilt": 1.0}), "limits.max_tilt': unknown"),
])
def test_scenario_errors(data, message):
    with pytest.raises(ScenarioError, match=message) as e:
        parse(data, "my.toml")
    assert str(e.value).startswith("my.toml")


def test_bad_file(tmp_path):
    p = tmp_path / "bad.toml"
    p.write_text("name = \n")
    with pytest.raises(ScenarioError, match="bad.toml: not valid TOML"):
        load_scenario(p)
    with pytest.raises(ScenarioError, match="no such scenario file"):
        load_scenario(tmp_path / "missing.toml")


def test_run_command_writes_outputs(tmp_path, capsys):
    src = tmp_path / "s.toml"
    src.write_text("""
name = "demo"
controller = "adaptive"
duration = 3.0
[trajectory]
kind = "helix"
radius = 0.5
period = 6.0
climb_rate = 0.1
[[cog]]
t = 0.5
r = [0.02, 0.0, 0.0]
ramp = 0.5
[[disturbance]]
t = 1.0
duration = 0.2
force = [0.3, 0.0, 0.0]
moment = [0.0, 0.0, 0.0]
[vehicle]
m = 0.7
[controller_params]
gamma = 0.01
projection_radius = false
[truth]
parallel_axis = true
rotor_saturation = true
""")
    out = tmp_path / "out"
    # in this process (`python -m quadcog` in a subprocess: the tests below)
    assert main(["run", str(src), "--out", str(out)]) == 0
    stderr = capsys.readouterr().err
    m = json.loads((out / "metrics.json").read_text())
    for key in ("diverged", "diverged_at", "diverged_cause", "rms_position_error",
                "max_position_error", "final_position_error", "rms_position_error_tail",
                "r_hat_final", "r_G_final"):
        assert key in m, key
    assert m["r_G_final"] == [0.02, 0.0, 0.0] and not m["diverged"]
    rows = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1)
    header = (out / "trajectory.csv").read_text().splitlines()[0].split(",")
    # the default table: every 10 ms of the 3 s (3001 steps of 1 ms with --full-rate)
    assert rows.shape == (301, len(header)) and header[:4] == ["t_s", "x_m", "y_m", "z_m"]
    assert (out / "flight.png").stat().st_size > 10_000
    assert "demo" in stderr              # the progress bar's final line


def test_run_command_error_names_file(tmp_path):
    src = tmp_path / "broken.toml"
    src.write_text('name = "x"\ncontroller = "fl"\nduration = -1.0\n')
    res = subprocess.run([sys.executable, "-m", "quadcog", "run", str(src), "--out",
                          str(tmp_path / "o")], cwd=ROOT, capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin",
                              "HOME": str(Path.home())})
    assert res.returncode == 2
    assert "broken.toml: key 'duration': expected a positive number" in res.stderr


def test_unreadable_inputs(tmp_path):
    folder = tmp_path / "dir.toml"
    folder.mkdir()
    with pytest.raises(ScenarioError, match="is a folder, not a TOML file"):
        load_scenario(folder)
    latin = tmp_path / "latin.toml"
    latin.write_bytes(b'name = "\xff"\n')
    with pytest.raises(ScenarioError, match="latin.toml: not UTF-8 text"):
        load_scenario(latin)


def test_cli_bad_out_folder(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    res = subprocess.run([sys.executable, "-m", "quadcog", "run", str(scenario_path("fig3a")),
                          "--out", str(blocker / "sub")], cwd=ROOT, capture_output=True,
                         text=True, env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin",
                                         "HOME": str(Path.home())})
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "--out" in res.stderr and "cannot create the folder" in res.stderr


def test_run_time_error_names_the_file(tmp_path):
    src = tmp_path / "coarse.toml"
    src.write_text('name = "c"\ncontroller = "fl"\nduration = 2.0\ndt = 0.5\n')
    with pytest.raises(ScenarioError, match=r"coarse.toml: dt = 0.5 s is too large"):
        run_file(src, tmp_path / "o", progress=False)


def test_shipped_scenarios_by_name(tmp_path, monkeypatch):
    from quadcog.scenarios.lookup import scenario_path, shipped_scenarios
    listed = shipped_scenarios()
    # every figure of the paper ships, with its description read from the file
    assert {c.scenario for c in CLAIMS} <= set(listed)
    for name, description in listed.items():
        assert description and load_scenario(name).name == name
    assert scenario_path("fig6.toml") == scenario_path("fig6")
    # a folder called like a shipped scenario (e.g. an earlier --out fig6) does not shadow it
    monkeypatch.chdir(tmp_path)
    (tmp_path / "fig6").mkdir()
    assert scenario_path("fig6").is_file()
    # an existing file wins over the shipped name
    (tmp_path / "fig7").write_text('name = "mine"\ncontroller = "fl"\nduration = 1.0\n')
    assert load_scenario("fig7").name == "mine"
    with pytest.raises(ScenarioError, match=r"fig99: no such scenario file.*shipped: .*fig3a"):
        load_scenario("fig99")


def test_cli_scenarios_lists_names_and_descriptions():
    res = subprocess.run([sys.executable, "-m", "quadcog", "scenarios"], cwd="/",
                         capture_output=True, text=True,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin",
                              "HOME": str(Path.home())})
    assert res.returncode == 0, res.stderr
    lines = dict(line.split(None, 1) for line in res.stdout.splitlines())
    fig6 = tomllib.loads((ROOT / "quadcog" / "scenarios" / "fig6.toml").read_text())
    assert lines["fig6"].strip() == fig6["description"]
    assert set(lines) == {p.stem for p in (ROOT / "quadcog" / "scenarios").glob("*.toml")}

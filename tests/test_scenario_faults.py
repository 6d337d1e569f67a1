"""Issue 10's scenario-file reproducers, as files: each ends in a ScenarioError that names the
file, the key, the value and what was expected (or in a correct run)."""
import pytest

from quadcog.scenarios.scenario import ScenarioError, load_scenario

HEAD = 'name = "t"\ncontroller = "fl"\n'


def _load(tmp_path, text, encoding="utf-8", name="s.toml"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding) if isinstance(text, str) else text)
    return load_scenario(path)


def test_byte_order_mark_is_accepted(tmp_path):
    s = _load(tmp_path, HEAD + "duration = 2.0\n", encoding="utf-8-sig")
    assert s.name == "t" and s.duration == 2.0


@pytest.mark.parametrize("depth", [1100, 100_000])
def test_deep_nesting(tmp_path, depth):
    with pytest.raises(ScenarioError, match=r"s.toml: (arrays or tables nested too deeply|key "
                                            r"'x': unknown)"):
        _load(tmp_path, HEAD + "duration = 1.0\nx = " + "[" * depth + "]" * depth + "\n")


@pytest.mark.parametrize("text, message", [
    ("duration = 1.0\n[trajectory]\nkind = {}\n",
     r"key 'trajectory.kind': expected one of 'hover', 'circle', 'figure8', 'helix', 'waypoints', "
     r"'flip', 'banked_circle', got a table"),
    ('duration = 1.0\n[trajectory]\nkind = ["hover"]\n',
     r"key 'trajectory.kind': expected one of .*, got \['hover'\]"),
    ("duration = 1.0\ncog = [1]\n", r"key 'cog': expected an array of tables .*, got \[1\]"),
    ('duration = 1.0\ndisturbance = ["x"]\n',
     r"key 'disturbance': expected an array of tables .*, got \['x'\]"),
    ("duration = 1" + "0" * 400 + "\n",
     r"key 'duration': expected a finite real number, got an integer of 401 digits"),
    ("duration = 1e400\n", r"key 'duration': expected a finite real number, got inf"),
    ("duration = 20.0\ndt = 1e-9\n", r"duration / dt = 20.0 s / 1e-09 s gives 2e\+10 steps, "
                                     r"about 11.9 TiB of memory; expected at most 10,000,000"),
    ("duration = 1e20\n", r"gives 1e\+23 steps"),
    ("duration = 1.0\ndt = 5e-324\n", r"more steps than a float can count"),
    ("duration = 1.0\ninitial_offset = [1e200, 0, 0]\n",
     r"key 'initial_offset': expected an offset shorter than limits.max_position_error = 10 m"),
    ("duration = 1.0\n[vehicle]\nIzz = 5e-324\n", r"Izz = 5e-324 is out of scale"),
    ("duration = 1.0\n[vehicle]\nc_y = 1e308\n", r"c_y = 1e\+308 is out of scale"),
    ("duration = 1.0\n[vehicle]\nmax_rotor_thrust = -1\n", r"max_rotor_thrust = -1.0 must be > 0"),
    ("duration = 1.0\n[limits]\nmax_tilt_deg = -1\n",
     r"key 'limits.max_tilt_deg': expected a number in \(0.0, 180.0\] \(deg\), got -1"),
    ("duration = 1.0\n[limits]\nmax_position_error = 0\n",
     r"key 'limits.max_position_error': expected a positive number \(m\), got 0"),
    ("duration = 1.0\n[truth]\nmotor_lag = 1\n", r"key 'truth.motor_lag': expected true or false"),
    ("duration = true\n", r"key 'duration': expected a finite real number, got True"),
    ("duration = 1.0\n[[cog]]\nt = -1\nr = [0, 0, 0]\n",
     r"key 'cog\[0\].t': expected a number >= 0 \(s\), got -1"),
    ("duration = 1.0\n[[cog]]\nt = 1\nr = [0, 0, true]\n",
     r"key 'cog\[0\].r'\[2\]: expected a real number, got True"),
    ("duration = 1.0\n[controller_params]\npoles_z = []\n",
     r"key 'controller_params.poles_z': expected a non-empty array of numbers"),
    ("duration = 1.0\n[controller_params]\npoles_z = [[-1], [-2, -3]]\n",
     r"key 'controller_params.poles_z': expected an array of numbers"),
])
def test_malformed_scenario_files(tmp_path, text, message):
    with pytest.raises(ScenarioError, match=message) as e:
        _load(tmp_path, HEAD + text)
    assert str(e.value).startswith(str(tmp_path / "s.toml"))
    assert "np." not in str(e.value) and "float64" not in str(e.value)

"""The `quadcog` command as a user meets it: help, version, names, defaults, --set, outputs."""
import csv
import json
from pathlib import Path
import re
import tomllib

import numpy as np
import pytest

from quadcog.cli import main, parser
from quadcog.model.columns import trajectory_columns

ROOT = Path(__file__).resolve().parent.parent
SHORT = ["--set", "duration=0.3", "--quiet"]        # keep the flights short


def test_version_is_the_package_version(capsys):
    expected = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["version"]
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0
    assert capsys.readouterr().out.strip() == f"quadcog {expected}"


def test_every_subcommand_has_a_one_line_help_and_a_description():
    ap = parser()
    sub = next(a for a in ap._actions if a.dest == "command")
    helps = {c.dest: c.help for c in sub._choices_actions}
    assert set(helps) == set(sub.choices) >= {"tour", "scenarios", "run", "animate", "paper",
                                              "analyze"}
    for name, p in sub.choices.items():
        assert helps[name] and "\n" not in helps[name], name
        assert p.description, f"{name} has no description"


def test_run_by_name_from_another_folder_writes_to_out_scenario(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "fig3a", *SHORT, "--every", "7"]) == 0      # with its plot
    out = tmp_path / "out" / "fig3a"
    assert {p.name for p in out.iterdir()} >= {"metrics.json", "trajectory.csv", "flight.png",
                                               "vehicle.json"}
    with open(out / "trajectory.csv") as fh:
        rows = list(csv.reader(fh))
    header, data = rows[0], np.array(rows[1:], dtype=float)
    assert tuple(header) == trajectory_columns()
    # 0.3 s at 1 ms: samples 0..300; every 7th and the last one
    t = data[:, 0]
    assert np.allclose(t[:-1], np.arange(0, 301, 7)[:len(t) - 1] * 1e-3)
    assert t[-1] == pytest.approx(0.3)
    assert len(t) == len(range(0, 301, 7)) + 1


def test_every_csv_column_names_its_unit():
    units = {"s", "m", "rad", "m_s", "rad_s", "N", "N_m", "m_s2", "m_s3", "kg"}
    names = trajectory_columns()
    # 37, then the commanded and applied thrust of each rotor, then the whole body's mass
    assert len(names) == len(set(names)) == 46
    assert names[-1] == "mass_kg"
    for n in names:
        assert any(n.endswith("_" + u) for u in units), n
    # angles in radians, rates in rad/s: the state's rows 3..5 and 9..11
    assert names[4:7] == ("phi_rad", "theta_rad", "psi_rad")
    assert names[10:13] == ("p_rad_s", "q_rad_s", "r_rad_s")


def test_set_overrides_reach_the_flight(tmp_path):
    """A heavier truth vehicle than the controller believes leaves a standing height error:
    the override must change the flight, not only the file."""
    base, heavy = tmp_path / "base", tmp_path / "heavy"
    args = ["run", "fig3b", "--set", "duration=2", "--set", "initial_offset=[0, 0, 0]",
            "--set", "trajectory={kind='hover'}", "--quiet", "--no-plot"]
    assert main([*args, "--out", str(base)]) == 0
    assert main([*args, "--set", "controller_model={m=0.68}", "--set", "vehicle.m=0.8",
                 "--out", str(heavy)]) == 0
    assert not (base / "flight.png").exists()
    z = {}
    for k, d in (("base", base), ("heavy", heavy)):
        with open(d / "trajectory.csv") as fh:
            r = list(csv.DictReader(fh))
        z[k] = float(r[-1]["z_m"]) - float(r[-1]["ref_z_m"])
    assert abs(z["base"]) < 1e-3
    assert z["heavy"] < -0.05          # sags under the 120 g it does not know about


@pytest.mark.parametrize("setting, words", [
    ("vehicle.m=abc", ["vehicle.m", "expected a finite real number", "'abc'",
                       "--set vehicle.m=abc"]),
    ("vehicle.m=-1", ["vehicle", "m"]),
    ("nope=1", ["'nope'", "unknown"]),
    ("controller=xyz", ["'controller'", "'pd', 'fl', 'adaptive'", "'xyz'"]),
    ("duration", ["KEY=VALUE"]),
    ("cog[5].t=1", ["cog[5]", "entry"]),
    # the spelling of earlier releases: the message shows the accepted one
    ("cog.0.t=1", ["cog.0.t", "cog[0].t", "brackets"]),
])
def test_bad_set_is_one_line_naming_the_key(setting, words, tmp_path, capsys):
    assert main(["run", "fig6", "--set", setting, "--quiet", "--out", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("quadcog: error:") and err.count("\n") == 1, err
    for w in words:
        assert w in err, (w, err)


def test_switching_the_controller_drops_parameters_it_does_not_take(tmp_path, capsys):
    assert main(["run", "fig6", "--set", "controller=pd", *SHORT, "--no-plot",
                 "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err
    assert re.search(r"warning: .*controller 'pd'.*gamma", err), err
    assert json.loads((tmp_path / "metrics.json").read_text())["controller"] == "pd"


def test_parquet_without_pyarrow_or_with_it(tmp_path, capsys):
    code = main(["run", "fig3a", *SHORT, "--no-plot", "--format", "parquet",
                 "--out", str(tmp_path)])
    try:
        import pyarrow.parquet as pq
    except ImportError:
        assert code == 2 and "pip install pyarrow" in capsys.readouterr().err
        return
    assert code == 0
    table = pq.read_table(tmp_path / "trajectory.parquet")
    assert tuple(table.column_names) == trajectory_columns()


def test_bad_every_is_refused(capsys):
    with pytest.raises(SystemExit) as e:
        main(["run", "fig3a", "--every", "0"])
    assert e.value.code == 2
    assert "--every" in capsys.readouterr().err

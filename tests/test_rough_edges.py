"""The rough edges a new user met (issue 22): extras checked before any flight, one flag name
per meaning, shipped files named by their names, a clear diverged line, a decimated table by
default, per-rotor commanded and applied thrust, sensing from Python, BatchResult as a table."""
import csv
import importlib.util
import math

import numpy as np
import pytest

import quadcog
from quadcog.cli import main, parser
from quadcog.errors import MissingDependencyError

SHORT = ["--quiet", "--no-plot"]


def test_sweep_without_pyarrow_stops_before_any_flight(monkeypatch, capsys, tmp_path):
    real = importlib.util.find_spec
    monkeypatch.setattr(importlib.util, "find_spec",
                        lambda name, *a: None if name == "pyarrow" else real(name, *a))
    import quadcog.sweeps.runner as runner
    monkeypatch.setattr(runner, "run_cli", lambda *a, **k: pytest.fail("a flight was flown"))
    assert main(["sweep", "failure-map", "--out", str(tmp_path / "s")]) == 2
    err = capsys.readouterr().err
    assert "pyarrow" in err and "pip install 'quadcog[sweep]'" in err
    with pytest.raises(MissingDependencyError, match=r"quadcog\[sweep\]"):
        quadcog.sweep("failure-map", out=tmp_path / "t")
    assert not (tmp_path / "t" / "chunks").exists()


def test_sweep_help_names_the_extra(capsys):
    with pytest.raises(SystemExit):
        main(["sweep", "--help"])
    assert "pip install 'quadcog[sweep]'" in " ".join(capsys.readouterr().out.split())


def test_animate_takes_out_and_the_old_output():
    ap = parser()
    assert ap.parse_args(["animate", "d", "--out", "a.gif"]).out.name == "a.gif"
    assert ap.parse_args(["animate", "d", "--output", "b.gif"]).out.name == "b.gif"


def test_scenarios_show_prints_the_shipped_file(capsys):
    import tomllib

    from quadcog.scenarios.lookup import scenario_path
    assert main(["scenarios", "--show", "fig6"]) == 0
    out = capsys.readouterr().out
    assert out == scenario_path("fig6").read_text(encoding="utf-8-sig")
    assert tomllib.loads(out)["name"] == "fig6"
    assert main(["scenarios", "--show", "fig99"]) == 2
    err = capsys.readouterr().err
    assert "fig99" in err and "fig6-real" in err and "(" in err and "'fig" not in err


def test_sweeps_lists_the_shipped_sweep_files(capsys):
    assert main(["sweeps"]) == 0
    assert capsys.readouterr().out.startswith("failure-map  ")
    assert main(["sweeps", "--show", "failure-map"]) == 0
    assert 'name = "failure-map"' in capsys.readouterr().out


def test_messages_name_a_shipped_scenario_by_its_name(capsys):
    from quadcog.scenarios.lookup import display_name, scenario_path
    assert display_name(scenario_path("fig6")) == "shipped scenario 'fig6'"
    assert display_name("my/own.toml") == "my/own.toml"
    assert main(["run", "fig6", "--set", "vehicle.m=-1", *SHORT]) == 2
    err = capsys.readouterr().err
    assert "shipped scenario 'fig6'" in err and str(scenario_path("fig6")) not in err


def test_a_diverged_run_says_so_and_exits_0(tmp_path, capsys):
    """Fig. 5 diverges by design: a valid result, exit status 0, one clear line."""
    assert main(["run", "fig5", "--set", "duration=1.6", "--out", str(tmp_path), *SHORT]) == 0
    out = capsys.readouterr().out
    assert "DIVERGED at 1.3" in out and "valid result" in out


def _rows(path):
    with open(path) as fh:
        return list(csv.reader(fh))[1:]


def test_the_table_is_decimated_to_10_ms_unless_asked(tmp_path):
    assert main(["run", "fig3a", "--set", "duration=0.3", "--out", str(tmp_path / "a"), *SHORT]) == 0
    t = np.array([float(r[0]) for r in _rows(tmp_path / "a" / "trajectory.csv")])
    assert np.allclose(t, np.arange(0, 31) * 0.01)            # every 10 ms, the last included
    assert main(["run", "fig3a", "--set", "duration=0.3", "--full-rate",
                 "--out", str(tmp_path / "b"), *SHORT]) == 0
    assert len(_rows(tmp_path / "b" / "trajectory.csv")) == 301


@pytest.fixture(scope="module")
def fig5():
    """Feedback linearization through the CoG step of Fig. 5, until it tips over."""
    cog = quadcog.CogProfile([(0.5, (0.06, 0.06, 0.0), 0.0)])
    return quadcog.simulate(quadcog.FeedbackLinearization(), "hover", duration=1.5, cog=cog)


def test_rotor_thrusts_commanded_and_applied(fig5):
    """Applied: what the rotors give, >= 0, and the mixer of it is the applied U (an
    independent inverse: the vehicle's own mixer). Commanded: the law's U, re-evaluated here
    at one sample, through the inverse mixer; negative after the step (a rotor asked to pull)."""
    res, v = fig5, quadcog.HUMMINGBIRD
    f, fc = res.rotor_thrust, res.rotor_command
    assert f.shape == fc.shape == (len(res.t), 4)
    assert f.min() >= 0 and np.allclose(f @ v.mixer().T, res.U, atol=1e-9)
    assert fc.min() < 0 and np.all(fc[res.t < 0.5] > 0)
    k = int(np.searchsorted(res.t, 0.7))
    ctl = quadcog.FeedbackLinearization()
    U = np.array(ctl.function()(res.t[k], res.x[k], res.ref[k], [])[0]).ravel()
    assert np.allclose(fc[k], np.linalg.solve(v.mixer(), U), rtol=1e-9, atol=1e-9)


def test_run_table_has_a_column_per_rotor_with_units(tmp_path):
    from quadcog.model.columns import ROTOR_COMMAND, ROTOR_THRUST, trajectory_columns
    names = trajectory_columns()
    assert names[ROTOR_COMMAND] + names[ROTOR_THRUST] == tuple(
        f"rotor{i}_command_N" for i in range(1, 5)) + tuple(f"rotor{i}_thrust_N" for i in range(1, 5))
    assert main(["run", "fig5", "--set", "duration=1.2", "--out", str(tmp_path), *SHORT]) == 0
    rows = np.array(_rows(tmp_path / "trajectory.csv"), dtype=float)
    assert rows.shape[1] == len(names) and rows[:, ROTOR_THRUST].min() >= 0
    assert rows[:, ROTOR_COMMAND].min() < 0


def test_thrust_axis_is_not_flattened_by_a_spike(fig5):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig = fig5.plot()
    panel = next(a for a in fig.axes if a.get_ylabel() == "rotor thrust (N)")
    lo, hi = panel.get_ylim()
    assert np.abs(fig5.rotor_command).max() > 1e3       # the spike of the last samples
    assert hi < 50 and lo > -50                          # the hover thrusts stay readable
    for a in fig.axes:
        assert "(" in a.get_ylabel() and ")" in a.get_xlabel() + a.get_ylabel()
    plt.close(fig)


def test_simulate_takes_sensing():
    s = quadcog.Sensing(seed=3)
    ctl = quadcog.AdaptiveFeedbackLinearization()
    a = quadcog.simulate(ctl, "hover", duration=0.5, sensing=s)
    b = quadcog.simulate(quadcog.Sensed(ctl, s, 0.001), "hover", duration=0.5)
    c = quadcog.simulate(ctl, "hover", duration=0.5)
    assert np.array_equal(a.x, b.x) and not np.array_equal(a.x, c.x)


def test_batch_result_prints_a_summary_and_gives_a_table():
    from quadcog.sim.divergence import DivergenceCause
    r = quadcog.BatchResult(
        rms_position_error=np.array([0.1, 0.2, 0.3]), max_position_error=np.array([1.0, 2, 3]),
        rms_position_error_tail=np.array([0.01, math.inf, 0.03]),
        final_position_error=np.array([0.0, 5, 0]), diverged=np.array([False, True, False]),
        diverged_at=np.array([math.nan, 1.5, math.nan]),
        diverged_cause=[None, DivergenceCause.TILT, None], final_state=np.zeros((3, 12)),
        seconds=0.5)
    text = repr(r)
    assert "3 flights" in text and "1 diverged" in text and "0.02 m" in text and "array" not in text
    cols = r.columns()
    assert list(cols["diverged_cause"]) == ["", "TILT", ""]
    if importlib.util.find_spec("pyarrow"):
        table = r.to_arrow()
        assert table.num_rows == 3 and table.column("rms_position_error_tail_m").to_pylist()[0] == 0.01


def test_export_a_scenario_controller_with_your_own_vehicle_and_gains(tmp_path, capsys):
    """`quadcog export --scenario` writes the controller a scenario flies (its params, its
    controller model, --set applied): the same files as exporting that controller object,
    built here by hand, from Python."""
    from quadcog.embedded import export_controller
    sets = ["vehicle.m=0.8", "controller_params.gamma=0.02"]
    assert main(["export", "--scenario", "fig6", *[a for s in sets for a in ("--set", s)],
                 "--out", str(tmp_path / "cli")]) == 0
    # fig6 writes the paper's poles out (the defaults would follow the 0.8 kg vehicle)
    ctl = quadcog.AdaptiveFeedbackLinearization(
        vehicle=quadcog.HUMMINGBIRD.replace(m=0.8), gamma=0.02, poles_z=(-3.0, -4.0),
        poles_attitude=(-10.0, -12.0), poles_psi=(-4.0, -5.0), poles_position=(-1.5, -2.0),
        max_tilt=0.6)
    command = ("quadcog export --scenario fig6 --set vehicle.m=0.8 --set "
               "controller_params.gamma=0.02 --precision float32 --out DIR")
    export_controller(ctl, "float32", tmp_path / "py", name="adaptive", command=command)
    for name in ("quadcog_adaptive.h", "quadcog_adaptive.c"):
        assert (tmp_path / "cli" / name).read_text() == (tmp_path / "py" / name).read_text()
    header = (tmp_path / "cli" / "quadcog_adaptive.h").read_text()
    assert "m        = 0.8 kg" in header and "gamma = [0.02, 0.02, 0.02]" in header
    assert main(["export", "--controller", "pd", "--set", "vehicle.m=1", "--out",
                 str(tmp_path / "x")]) == 2
    assert "--set needs --scenario" in capsys.readouterr().err


def test_the_exported_files_name_what_wrote_them(tmp_path):
    """The first line of an exported file names its writer: the `quadcog export` command line,
    the Python call, or `make embedded` for generated/embedded/ (not `make embedded` always)."""
    from quadcog.embedded import export_controller
    from quadcog.embedded.make_embedded import embedded_dir
    assert main(["export", "--controller", "pd", "--precision", "double", "--out",
                 str(tmp_path / "cli")]) == 0
    export_controller("pd", "double", tmp_path / "py")
    first = {where: {f: (tmp_path / where / f).read_text().splitlines()[0]
                     for f in ("quadcog_pd.h", "quadcog_pd.c")} for where in ("cli", "py")}
    for line in first["cli"].values():
        assert line.startswith("/* DO NOT EDIT: written by `quadcog export --controller pd "
                               "--precision double --out DIR` from"), line
    for line in first["py"].values():
        assert "written by `quadcog.embedded.export_controller('pd', 'double')`" in line, line
    shipped = (embedded_dir() / "double" / "quadcog_pd.h").read_text().splitlines()[0]
    assert "written by `make embedded`" in shipped and "quadcog export" not in shipped

"""Ninth hostile pass on the commands, the studies and the sweeps (issue 33).

- failure_map took a step time past the run (t_step=1e308: every flight hovered with r_G = 0)
  and durations whose step count the sweep refused only after analyze's first minutes of work;
- a sweep took a chunk of 10**9 flights and a threshold of 1e308 m (the plot overflowed);
- admissibility(None, None) raised numpy's TypeError;
- long names and --set texts were printed whole (scenarios --show, run, argparse's errors);
- animate --out x.gif/ wrote x.gif; a FIFO or link as the GIF was found only after drawing;
- a --set file path was resolved against the scenario file's folder, through the text of the
  --set itself (`--set vehicle.file=sub/v.urdf` read "s.toml with --set vehicle.file=sub/
  sub/v.urdf"), and a sweep's [set] path against the base scenario's (the package) folder;
- an empty scenario name was read as the current folder; `run --controller X` without --stack
  ended with a bare SystemExit; sweep --out FILE said "File exists";
- a scenario of thousands of CoG changes after its end printed thousands of warnings;
- analyze, paper and beyond opened a FIFO or followed a link in their output folder after
  their minutes of work, and left a half-written set of files when interrupted;
- the progress line printed a name with a newline on two lines.
"""
import io
import os
from pathlib import Path
import shutil
import warnings

from conftest import cli_error_line, small_sweep
import numpy as np
import pytest

from quadcog.cli import main, parser
from quadcog.errors import InputError, ScenarioError, SizeError, SweepError
from quadcog.files import one_line
from quadcog.scenarios.lookup import scenario_path
from quadcog.scenarios.scenario import load_scenario
from quadcog.studies.analysis.failure_map import admissibility, failure_map
from quadcog.sweeps.spec import MAX_CHUNK, MAX_THRESHOLD, from_dict
from quadcog.viz.animation import check_output, frame_times
from quadcog.viz.progress import ProgressCounter

ROOT = Path(__file__).resolve().parent.parent
URDF = ROOT / "tests" / "data" / "vehicles" / "gym-pybullet-drones" / "cf2x.urdf"
SCENARIO = 'name = "s"\ncontroller = "pd"\nduration = 0.05\n'
LONG = "A" * 5000






# -- 1. the failure map: a step time within the run, a duration the flights can take ---------

@pytest.mark.parametrize("t_step", [1e308, 2.0, 2.5])
def test_failure_map_refuses_a_step_at_or_after_the_end(t_step):
    with pytest.raises(InputError, match="failure_map: t_step.*within the run"):
        failure_map(grid=2, duration=2.0, t_step=t_step)


@pytest.mark.parametrize("duration, error, text", [
    (1e308, SizeError, "more steps than a float can count"),
    (1e5, SizeError, "steps"),
    (1e-308, InputError, "at least one step")])
def test_failure_map_refuses_a_duration_the_flights_cannot_take(duration, error, text):
    with pytest.raises(error, match=f"failure_map: duration.*{text}"):
        failure_map(grid=2, duration=duration, t_step=0.0)


@pytest.mark.parametrize("duration", [1e308, 1e-308, 0.5, 1.0])
def test_analyze_refuses_the_duration_before_any_work(tmp_path, monkeypatch, duration):
    import quadcog.studies.analysis as analysis

    def worked():
        raise AssertionError("analyze worked before refusing the duration")
    monkeypatch.setattr(analysis, "pd_design", worked)
    with pytest.raises(InputError, match="failure_map: duration"):
        analysis.analyze(tmp_path / "a", progress=False, duration=duration)
    assert not (tmp_path / "a").exists()


def test_failure_map_threshold_is_bounded():
    with pytest.raises(InputError, match="failure_map: threshold"):
        failure_map(grid=2, duration=2.0, threshold=1e308)


@pytest.mark.parametrize("args, text", [
    ((None, None), "x_G"), (([0.0], None), "y_G"), (("ab", [0.0]), "x_G"),
    (([[0.0]], [0.0]), "x_G"), (([np.nan], [0.0]), r"x_G\[0\]"),
    (([0.0], [0.0], "x"), "z_G"), (([0.0], [0.0], 0.0, [1.0, 2.0]), "base")])
def test_admissibility_names_a_bad_argument(args, text):
    with pytest.raises(InputError, match=f"admissibility: {text}"):
        admissibility(*args)


def test_admissibility_refuses_a_grid_beyond_one_map():
    with pytest.raises(SizeError, match="admissibility"):
        admissibility(np.zeros(2000), np.zeros(2000))
    adm, lam = admissibility([0.0, 0.05], [0.0])
    assert adm.tolist() == [[True, True]] and lam.shape == (1, 2)


# -- 2. sweep files: the chunk and the threshold bounded ---------------------------------------



@pytest.mark.parametrize("chunk", [10 ** 9, 10 ** 100, MAX_CHUNK + 1])
def test_a_chunk_beyond_the_limit_is_refused(chunk):
    with pytest.raises(SizeError, match=f"key 'chunk'.*{MAX_CHUNK}"):
        from_dict(small_sweep(chunk=chunk))


@pytest.mark.parametrize("threshold", [1e308, MAX_THRESHOLD * 2, 10 ** 400])
def test_a_threshold_beyond_the_limit_is_refused(threshold):
    with pytest.raises(SweepError, match="key 'threshold'"):
        from_dict(small_sweep(threshold=threshold))


# -- 4. names of any length are printed as one short line ------------------------------------

@pytest.mark.parametrize("command", ["scenarios", "sweeps"])
def test_show_shortens_a_long_name(capsys, command):
    assert main([command, "--show", LONG]) == 2
    line = cli_error_line(capsys)
    assert len(line) < 400 and "5000 characters" in line, line


def test_run_names_a_long_scenario_name_as_no_scenario(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(["run", LONG]) == 2
    line = cli_error_line(capsys)
    assert "no such scenario file" in line and len(line) < 500, line


def test_a_long_set_text_is_shortened_in_the_messages(tmp_path):
    (tmp_path / "s.toml").write_text(SCENARIO)
    with pytest.raises(ScenarioError) as e:
        load_scenario(tmp_path / "s.toml", ["controller=" + LONG])
    assert "key 'controller'" in str(e.value) and len(str(e.value)) < 1000, str(e.value)[:300]


def test_argparse_errors_are_one_short_line(capsys):
    with pytest.raises(SystemExit) as e:
        main(["targets", "--laws", LONG])
    assert e.value.code == 2
    line = cli_error_line(capsys)
    assert "--laws" in line and len(line) < 600, line


def test_one_line_shortens_long_words_only():
    assert one_line("a b c") == "a b c"
    text = one_line("x: " + "B" * 1000 + " y")
    assert "(1000 characters)" in text and text.endswith(" y") and len(text) < 400
    path = "/".join(["folder"] * 30)            # a long real path (209 characters) stays
    assert one_line(path) == path


# -- 5. animate: a folder path is no GIF; links and FIFOs refused before drawing --------------

@pytest.mark.parametrize("out", ["x.gif/", "sub/", "a/b.gif/"])
def test_animate_refuses_a_folder_path_as_the_gif(tmp_path, monkeypatch, out):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(SystemExit) as e:
        parser().parse_args(["animate", "run", "--out", out])
    assert e.value.code == 2
    with pytest.raises(InputError, match="not a folder path"):
        check_output(out)
    assert not list(tmp_path.iterdir())


def test_animate_refuses_a_link_or_fifo_before_drawing(tmp_path):
    os.mkfifo(tmp_path / "f.gif")
    (tmp_path / "l.gif").symlink_to(tmp_path / "target.gif")
    for name, kind in (("f.gif", "FIFO"), ("l.gif", "symbolic link")):
        with pytest.raises(InputError, match=kind):
            check_output(tmp_path / name)
    assert check_output(tmp_path / "new.gif") == tmp_path / "new.gif"


def test_frame_times_take_any_speed_without_overflow():
    t = np.linspace(0.0, 2.0, 2001)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(frame_times(t, 15, 1e-308, 120)) == 120
        assert frame_times(t, 15, 1e308, 120).tolist() == [0.0, 2.0]
    assert frame_times(t, 15, 1.0, 1).tolist() == [2.0]     # at most max_frames


# -- 6. file paths of --set: relative to the current folder; missing ones refused ------------

@pytest.fixture
def layout(tmp_path, monkeypatch):
    """tmp/sub/s.toml (no vehicle), tmp/sub/f.toml ([vehicle] file = "v.urdf"), tmp/sub/v.urdf
    and tmp/here.urdf; the current folder is tmp."""
    sub = tmp_path / "sub"
    sub.mkdir()
    (sub / "s.toml").write_text(SCENARIO)
    (sub / "f.toml").write_text(SCENARIO + '[vehicle]\nfile = "v.urdf"\n')
    shutil.copy(URDF, sub / "v.urdf")
    shutil.copy(URDF, tmp_path / "here.urdf")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_a_set_path_is_relative_to_the_current_folder(layout):
    sc = load_scenario("sub/s.toml", ["vehicle.file=here.urdf"])
    assert sc.vehicle.m == pytest.approx(0.027)
    assert ("key 'vehicle.file'", layout / "here.urdf") in sc.inputs
    # a path with a folder part: it was joined to the text of the --set itself
    sc = load_scenario("sub/s.toml", ["vehicle.file=sub/v.urdf"])
    assert ("key 'vehicle.file'", layout / "sub" / "v.urdf") in sc.inputs
    # not the scenario file's folder: sub/here.urdf does not exist, here.urdf does
    with pytest.raises(ScenarioError, match="no such file.*current folder"):
        load_scenario("sub/s.toml", ["vehicle.file=v.urdf"])


def test_a_file_path_stays_relative_to_the_scenario_file_with_a_set(layout):
    sc = load_scenario("sub/f.toml", ['description="a/b"'])
    assert ("key 'vehicle.file'", layout / "sub" / "v.urdf") in sc.inputs


@pytest.mark.parametrize("value, text", [("nope.urdf", "nope.urdf: no such file"),
                                         ('""', "expected the path of"),
                                         ("nope.json", "nope.json: no such file")])
def test_a_set_path_that_names_nothing_is_refused(layout, value, text):
    key = "vehicle.identified" if value.endswith(".json") else "vehicle.file"
    with pytest.raises(ScenarioError, match=f"key '{key}'.*{text}"):
        load_scenario("sub/s.toml", [f"{key}={value}"])


def test_run_help_says_what_a_set_path_is_relative_to():
    sub = next(a for a in parser()._actions if getattr(a, "choices", None))
    text = " ".join(sub.choices["run"].format_help().split())
    assert "relative to the current folder" in text and "relative to that file's" in text


def test_a_sweep_set_path_is_relative_to_the_sweep_file(tmp_path, monkeypatch):
    folder = tmp_path / "sweeps"
    folder.mkdir()
    shutil.copy(URDF, folder / "v.urdf")
    monkeypatch.chdir(tmp_path)
    data = {"scenario": "fig6",
            "set": {"duration": 0.05, "controller": "fl", "controller_params": {},
                    "vehicle.file": "v.urdf", "cog": []},
            "dimension": [{"key": "vehicle.file", "values": ["v.urdf"]}]}
    s = from_dict(data, str(folder / "sw.toml"), folder)
    assert s.flights[0].values["vehicle.file"] == str(folder / "v.urdf")
    assert ("key 'vehicle.file'", folder / "v.urdf") in s.inputs
    assert "site-packages" not in str(s.base)


# -- 7, 8, 11: empty names, --controller without --stack, sweep --out FILE ---------------------

@pytest.mark.parametrize("spec", ["", "  "])
def test_an_empty_scenario_name_is_refused(spec):
    with pytest.raises(ScenarioError, match="scenario: expected a scenario file"):
        scenario_path(spec)


def test_run_controller_without_stack_is_onecli_error_line(capsys, tmp_path, monkeypatch,
                                                        no_flight):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "fig3a", "--controller", "pid", "--out", "o"]) == 2
    assert cli_error_line(capsys).startswith("quadcog: error: --controller pid: ")


def test_sweep_out_that_is_a_file_is_named_as_such(capsys, tmp_path):
    pytest.importorskip("distributed")
    (tmp_path / "f").write_text("x")
    assert main(["sweep", "failure-map", "--out", str(tmp_path / "f")]) == 2
    line = cli_error_line(capsys)
    assert "--out" in line and "not a folder" in line, line


# -- 12. warnings: at most MAX_WARNINGS lines, then a count ------------------------------------

def test_a_flood_of_warnings_is_cut_short(capsys, tmp_path, monkeypatch):
    from quadcog.cli import MAX_WARNINGS
    monkeypatch.chdir(tmp_path)
    late = "".join(f"[[cog]]\nt = {1 + i}\nr = [0.0, 0.0, 0.0]\n" for i in range(40))
    (tmp_path / "s.toml").write_text(SCENARIO + late)
    assert main(["run", "s.toml", "--out", "o", "--quiet", "--no-plot"]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == MAX_WARNINGS + 1, err
    assert err[-1] == f"quadcog: warning: {40 - MAX_WARNINGS} more warnings not shown"


# -- 13. analyze, paper, beyond: their files checked first, written together -----------------

def _fifo_and_link(folder, fifo, link):
    folder.mkdir(parents=True, exist_ok=True)
    os.mkfifo(folder / fifo)
    (folder.parent / "precious.txt").write_text("keep")
    (folder / link).symlink_to(folder.parent / "precious.txt")


def test_analyze_refuses_a_fifo_or_link_before_any_work(tmp_path, monkeypatch):
    import quadcog.studies.analysis as analysis

    def worked():
        raise AssertionError("analyze worked before checking its files")
    monkeypatch.setattr(analysis, "pd_design", worked)
    out = tmp_path / "a"
    _fifo_and_link(out, "analysis.json", "failure_map.png")
    with pytest.raises(InputError, match="failure_map.png.*symbolic link"):
        analysis.analyze(out, grid=2, progress=False, duration=2.0)
    os.unlink(out / "failure_map.png")
    with pytest.raises(InputError, match="analysis.json.*FIFO"):
        analysis.analyze(out, grid=2, progress=False, duration=2.0)
    assert (tmp_path / "precious.txt").read_text() == "keep"


@pytest.mark.parametrize("where", ["summary.json", "fig6/metrics.json", "beyond/beyond.md"])
def test_paper_refuses_a_fifo_before_any_flight(tmp_path, monkeypatch, where):
    import quadcog.studies.paper as paper

    def flown(*args, **kwargs):
        raise AssertionError("the paper flew before checking its files")
    monkeypatch.setattr(paper, "run_with_progress", flown)
    out = tmp_path / "p"
    (out / where).parent.mkdir(parents=True)
    os.mkfifo(out / where)
    with pytest.raises(InputError, match="FIFO"):
        paper.run_paper(out, progress=False)


def test_beyond_refuses_a_link_before_any_flight(tmp_path, monkeypatch):
    import quadcog.studies.beyond as beyond

    def flown(*args, **kwargs):
        raise AssertionError("beyond flew before checking its files")
    monkeypatch.setattr(beyond, "run_with_progress", flown)
    _fifo_and_link(tmp_path / "b", "x", "beyond.json")
    with pytest.raises(InputError, match="symbolic link"):
        beyond.run_beyond(tmp_path / "b", progress=False)
    assert (tmp_path / "precious.txt").read_text() == "keep"


def test_paper_writes_its_summaries_together(tmp_path, monkeypatch):
    """Interrupted while its summaries are written, the paper leaves none of them (it wrote
    summary.json first, and readme_table.md last)."""
    from quadcog.scenarios.scenario import Scenario
    import quadcog.studies.paper as paper

    real_run = Scenario.run
    monkeypatch.setattr(Scenario, "run", lambda self, progress=None: real_run(
        type(self)(**{**self.__dict__, "duration": 0.05}), progress))

    def interrupted(rows):
        raise KeyboardInterrupt
    monkeypatch.setattr(paper, "readme_table", interrupted)
    monkeypatch.setattr(paper, "CLAIMS", paper.CLAIMS[:1] + paper.CLAIMS[2:3])
    monkeypatch.setattr(paper, "_comparison_plot", lambda results, out: Path(out).write_text("png"))
    real_write = paper.write_outputs
    monkeypatch.setattr(paper, "write_outputs", lambda *a, **k: real_write(*a, **k, plot=False))
    out = tmp_path / "p"
    with pytest.raises(KeyboardInterrupt):
        paper.run_paper(out, progress=False, beyond=False)
    left = sorted(p.name for p in out.iterdir() if p.is_file())
    assert left == [], left


# -- 10. progress lines: one line whatever the name holds -----------------------------------

def test_progress_line_of_a_name_with_a_newline_is_one_line():
    stream = io.StringIO()
    ProgressCounter("sweep a\nb" + "n" * 3000, 1, stream=stream)(1)
    lines = stream.getvalue().splitlines()
    assert len(lines) == 1 and "a\\nb" in lines[0] and len(lines[0]) < 400, lines


# -- export: its files never replace the scenario it reads ------------------------------------

@pytest.mark.parametrize("target, rel", [("c", "quadcog_adaptive.c"),
                                         ("crazyflie", "src/quadcog_adaptive.h")])
def test_export_refuses_to_overwrite_its_scenario(tmp_path, capsys, target, rel):
    scenario = tmp_path / rel
    scenario.parent.mkdir(parents=True, exist_ok=True)
    text = 'name = "s"\ncontroller = "adaptive"\nduration = 0.3\n'
    scenario.write_text(text)
    assert main(["export", "--scenario", str(scenario), "--target", target,
                 "--out", str(tmp_path)]) == 2
    assert "is the same file as the scenario file" in cli_error_line(capsys)
    assert scenario.read_text() == text
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == [scenario.name]


def test_export_names_are_the_files_export_writes(tmp_path):
    from quadcog.cli import export_names
    from quadcog.embedded import export_controller
    from quadcog.embedded.crazyflie_app import write_crazyflie_app
    written = export_controller("fl", out=tmp_path / "c")
    assert sorted(str(p.relative_to(tmp_path / "c")) for p in written) == \
        sorted(export_names("c", "fl"))
    written = write_crazyflie_app("fl", tmp_path / "cf")
    assert sorted(str(p.relative_to(tmp_path / "cf")) for p in written) == \
        sorted(export_names("crazyflie", "fl"))


# -- targets: --out and its files checked before the flights -------------------------------

@pytest.mark.parametrize("case", ["fifo", "file"])
def test_targets_checks_its_output_before_flying(tmp_path, monkeypatch, capsys, case):
    import quadcog.studies.targets as targets

    def flown(*args, **kwargs):
        raise AssertionError("targets flew before checking --out")
    monkeypatch.setattr(targets, "run_targets", flown)
    out = tmp_path / "t"
    if case == "fifo":
        out.mkdir()
        os.mkfifo(out / "targets.json")
    else:
        out.write_text("x")
    assert main(["targets", "--out", str(out), "--vehicles", "crazyflie", "--laws", "pd",
                 "--cases", "hover"]) == 2
    line = cli_error_line(capsys)
    assert ("FIFO" if case == "fifo" else "not a folder") in line, line

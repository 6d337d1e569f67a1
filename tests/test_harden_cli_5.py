"""Fifth hostile pass on the commands' files and messages (issue 33).

- outputs overwrote the inputs they read (``run --identified DIR/vehicle.json --out DIR``, a
  scenario or sweep file named like a result in ``--out``): every output is now compared with
  every input (resolved, symbolic links followed, inodes) and refused before the work;
- identify's two outputs could be one file (the figure lost), and a bad ``--out``/identify.png
  was found only after the identification, named as a "run file";
- run and export made ``--out`` and its parents before validating anything;
- ``--json sub/`` wrote a file ``sub``; ``--json ""`` was named '.';
- TOML integers past Python's 4300 digits ended in an internal error;
- folders, FIFOs, devices and link loops were "no such file"; newlines in names broke the
  one-line rule; 300-digit numbers were printed in full;
- an identification JSON with a negative mass was used;
- a large sweep validated for minutes without a word.
"""
import json
import os
import re

from conftest import cli_error_line
import pytest

from quadcog.cli import main
from quadcog.errors import IdentificationError, ScenarioError
from quadcog.identification.identified import identified_cog
from quadcog.scenarios.lookup import read_toml

SCENARIO = 'name = "s"\ncontroller = "pd"\nduration = 0.2\n'
SWEEP = ('scenario = "fig7"\nset = {duration = 0.2}\n[[dimension]]\nkey = "vehicle.m"\n'
         'values = [0.5, 0.6]\n')
HUGE = "9" * 5000






@pytest.mark.parametrize("case", ["identified", "scenario_named_like_a_result", "symlink",
                                  "hardlink"])
def test_run_refuses_outputs_that_are_its_inputs(tmp_path, monkeypatch, capsys, no_flight,
                                                 case):
    monkeypatch.chdir(tmp_path)
    out = tmp_path / "out"
    out.mkdir()
    (tmp_path / "s.toml").write_text(SCENARIO)
    argv = ["run", "s.toml", "--out", "out", "--quiet", "--no-plot"]
    if case == "identified":
        read = out / "vehicle.json"
        read.write_text(json.dumps({"r_G": [0.01, 0, 0]}))
        argv += ["--identified", str(read)]
    elif case == "scenario_named_like_a_result":
        read = out / "metrics.json"
        read.write_text(SCENARIO)
        argv[1] = str(read)
    elif case == "symlink":
        read = tmp_path / "s.toml"
        (out / "trajectory.csv").symlink_to(read)
    else:
        read = tmp_path / "s.toml"
        os.link(read, out / "flight.png")        # a file a run would replace or remove
    before = read.read_bytes()
    assert main(argv) == 2
    line = cli_error_line(capsys)
    assert "is the same file as" in line and "--out" in line, line
    assert read.read_bytes() == before


def test_sweep_refuses_to_overwrite_its_sweep_file(tmp_path, monkeypatch, capsys):
    import quadcog.sweeps.runner as runner

    def flown(*args, **kwargs):
        raise AssertionError("the sweep was flown before the refusal")
    monkeypatch.setattr(runner, "_run", flown)
    spec = tmp_path / "results.csv"
    spec.write_text(SWEEP)
    assert main(["sweep", str(spec), "--out", str(tmp_path)]) == 2
    line = cli_error_line(capsys)
    assert "is the same file as the sweep file" in line and "--out" in line, line
    assert spec.read_text() == SWEEP
    inside = tmp_path / "o" / "chunks" / "s.toml"        # anything under chunks/ may go
    inside.parent.mkdir(parents=True)
    inside.write_text(SWEEP)
    assert main(["sweep", str(inside), "--out", str(tmp_path / "o")]) == 2
    assert "chunks" in cli_error_line(capsys)


@pytest.fixture
def no_identification(monkeypatch):
    import quadcog.identification as ident

    def identified(*args, **kwargs):
        raise AssertionError("identified before the refusal")
    monkeypatch.setattr(ident, "identify", identified)


@pytest.mark.parametrize("case", ["json_is_the_figure", "json_is_the_folder", "png_symlink",
                                  "png_folder", "png_fifo"])
def test_identify_checks_every_output_before_the_work(tmp_path, monkeypatch, capsys,
                                                      no_identification, case):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "in.csv").write_text("t_s,x_m\n0,0\n1,0\n")
    out = tmp_path / "o"
    argv = ["identify", "in.csv", "--out", "o"]
    if case == "json_is_the_figure":
        out.mkdir()
        argv += ["--json", "o/identify.png"]
    elif case == "json_is_the_folder":
        argv += ["--json", "o"]
    else:
        out.mkdir()
        png = out / "identify.png"
        if case == "png_symlink":
            (tmp_path / "keep.png").write_text("keep")
            png.symlink_to(tmp_path / "keep.png")
        elif case == "png_folder":
            png.mkdir()
        else:
            os.mkfifo(png)
    assert main(argv) == 2
    line = cli_error_line(capsys)
    assert "--out" in line and "run file" not in line, line
    if case == "json_is_the_folder":
        assert not out.exists()


def test_failed_commands_leave_no_folders(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["run", "no_such_scenario", "--out", "ex/deep/a/b/c"]) == 2
    assert main(["export", "--controller", "nope", "--out", "ex/new"]) == 2
    assert main(["export", "--scenario", "no_such_scenario", "--out", "ex/new"]) == 2
    capsys.readouterr()
    assert not (tmp_path / "ex").exists()


@pytest.mark.parametrize("value", ["sub/", ""])
def test_json_refuses_a_folder_like_name_as_given(tmp_path, monkeypatch, capsys,
                                                  no_identification, value):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "in.csv").write_text("t_s,x_m\n0,0\n1,0\n")
    assert main(["identify", "in.csv", "--json", value]) == 2
    line = cli_error_line(capsys)
    assert f"--json: expected a file name (not a folder), got {value!r}" in line, line
    assert list(tmp_path.iterdir()) == [tmp_path / "in.csv"]


def test_integers_past_pythons_digit_limit_name_the_key(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "big.toml").write_text(SCENARIO + f"[vehicle]\nm = {HUGE}\n")
    with pytest.raises(ScenarioError, match=r"key 'vehicle\.m' \(line 5\).*5000 digits"):
        read_toml(tmp_path / "big.toml")
    assert main(["run", "big.toml", "--out", "o"]) == 2
    assert "'vehicle.m'" in cli_error_line(capsys)
    assert main(["run", "fig7", "--set", f"vehicle.m={HUGE}", "--out", "o"]) == 2
    line = cli_error_line(capsys)
    assert "'vehicle.m'" in line and "5000 digits" in line and HUGE not in line
    (tmp_path / "sweep.toml").write_text(
        SWEEP.replace("values = [0.5, 0.6]", f"range = {{start = 0.5, stop = 1, num = {HUGE}}}"))
    assert main(["sweep", "sweep.toml", "--out", "o"]) == 2
    assert "num" in cli_error_line(capsys)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("kind, said", [("folder", "is a folder"), ("fifo", "FIFO"),
                                        ("device", "a device"), ("loop", "loops")])
def test_paths_that_are_not_regular_files_say_what_they_are(tmp_path, monkeypatch, capsys,
                                                            kind, said):
    monkeypatch.chdir(tmp_path)
    path = {"device": "/dev/null"}.get(kind, str(tmp_path / "p.toml"))
    if kind == "folder":
        os.mkdir(path)
    elif kind == "fifo":
        os.mkfifo(path)
    elif kind == "loop":
        os.symlink(path, path)
    for argv in (["identify", path], ["run", path, "--out", "o"]):
        assert main(argv) == 2
        line = cli_error_line(capsys)
        assert said in line and "no such" not in line, line


def test_messages_stay_on_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.toml").write_text(SCENARIO)
    for argv in (["identify", "a\nb.csv"], ["scenarios", "--show", "a\nb"],
                 ["run", "s.toml", "--set", "sensing.seed=1e300", "--out", "o"]):
        assert main(argv) == 2
        line = cli_error_line(capsys)
        assert not re.search(r"\d{40}", line), line     # long numbers are shortened
    assert main(["run", "s.toml", "--set", 'name="a\\nb"', "--out", "o", "--quiet",
                 "--no-plot"]) == 0
    out = capsys.readouterr().out
    assert len(out.strip().splitlines()) == 1 and "a\\nb" in out, out


@pytest.mark.parametrize("mass", [-3, 0, True, "1", 1e400])
def test_an_identification_with_an_impossible_mass_is_refused(tmp_path, mass):
    p = tmp_path / "id.json"
    p.write_text(json.dumps({"r_G": [0.01, 0, 0], "mass": mass}).replace("Infinity", "1e400"))
    with pytest.raises(IdentificationError, match="key 'mass'"):
        identified_cog(p)
    p.write_text(json.dumps({"r_G": [0.01, 0, 0], "mass": None}))
    assert identified_cog(p)[0] == 0.01


def test_a_large_sweep_shows_its_validation(monkeypatch, capsys):
    import quadcog.sweeps.spec as spec
    monkeypatch.setattr(spec, "VALIDATE_PROGRESS_AT", 2)
    spec.from_dict({"scenario": "fig7", "set": {"duration": 0.2},
                    "dimension": [{"key": "vehicle.m", "values": [0.5, 0.6, 0.7]}]},
                   progress=True)
    assert "validating" in capsys.readouterr().err

"""Issue 21, run folders and `quadcog animate`: a new run into an old folder replaces it whole
(no trajectory, plot or GIF of the earlier run survives), an interrupted or failed commit
leaves the previous folder, and damaged run folders or unwritable output names end in one
line naming the file, never a traceback."""
import json
import os
from pathlib import Path
import subprocess
import sys
import tempfile

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
import numpy as np
import pytest

from quadcog.errors import InputError, QuadcogError
from quadcog.files import COMPLETE_MARKER, RUN_FILES, RunFiles
from quadcog.model.columns import trajectory_columns
from quadcog.viz.animation import check_output, read_run

ROOT = Path(__file__).resolve().parent.parent
set_hypothesis_home_dir(tempfile.mkdtemp(prefix="quadcog-hypothesis-"))
SETTINGS = dict(derandomize=True, database=None, deadline=None, max_examples=40,
                suppress_health_check=list(HealthCheck))


def _old_run(folder):
    folder.mkdir(parents=True, exist_ok=True)
    for name in RUN_FILES:
        (folder / name).write_text(f"old {name}\n")
    (folder / "notes.txt").write_text("mine\n")      # not a run file: never touched


def test_a_new_run_replaces_every_file_of_the_old_one(tmp_path):
    _old_run(tmp_path)
    with RunFiles(tmp_path) as files:
        files.path("metrics.json").write_text("{}\n")
        files.path("trajectory.parquet").write_text("new\n")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["metrics.json", "notes.txt",
                                                           "trajectory.parquet"]
    assert (tmp_path / "trajectory.parquet").read_text() == "new\n"


def test_a_failed_run_keeps_the_old_folder_whole(tmp_path):
    _old_run(tmp_path)
    before = {p.name: p.read_text() for p in tmp_path.iterdir()}
    with pytest.raises(KeyboardInterrupt):
        with RunFiles(tmp_path) as files:
            files.path("metrics.json").write_text("{}\n")
            files.path("flight.gif").write_text("half a GIF")
            raise KeyboardInterrupt
    assert {p.name: p.read_text() for p in tmp_path.iterdir()} == before


def test_the_marker_goes_first_and_comes_back_last(tmp_path, monkeypatch):
    """Caught between two renames (SIGKILL), the folder must not look complete."""
    _old_run(tmp_path)
    seen = []
    real = os.replace

    def spy(src, dst):
        seen.append((Path(dst).name, (tmp_path / COMPLETE_MARKER).exists()))
        real(src, dst)
    monkeypatch.setattr(os, "replace", spy)
    with RunFiles(tmp_path) as files:
        for name in ("metrics.json", "trajectory.csv", "vehicle.json"):
            files.path(name).write_text("new\n")
    assert seen[-1] == ("metrics.json", False)
    assert all(not present for _, present in seen)


@settings(**SETTINGS)
@given(old=st.sets(st.sampled_from(RUN_FILES)), new=st.sets(st.sampled_from(RUN_FILES),
                                                            min_size=1))
def test_property_the_folder_holds_exactly_the_new_run(old, new):
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        for name in old:
            (folder / name).write_text("old")
        with RunFiles(folder) as files:
            for name in new:
                files.path(name).write_text("new")
        assert {p.name for p in folder.iterdir()} == new
        assert all((folder / n).read_text() == "new" for n in new)


def _run_cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "quadcog", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=180)


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    from quadcog.scenarios.scenario import run_file
    out = tmp_path_factory.mktemp("run") / "fig3a"
    run_file("fig3a", out, progress=False, overrides=["duration=1"], plot=False)
    return out


def test_run_into_an_old_folder_leaves_nothing_of_it(run_dir, tmp_path):
    from quadcog.scenarios.scenario import run_file
    out = tmp_path / "o"
    _old_run(out)
    run_file("fig3a", out, progress=False, overrides=["duration=1"], plot=False)
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "notes.txt",
                                                      "trajectory.csv", "vehicle.json"]
    assert json.loads((out / "metrics.json").read_text())["name"] == "fig3a"


def _copy(run_dir, tmp_path):
    import shutil
    dst = tmp_path / "damaged"
    shutil.copytree(run_dir, dst)
    return dst


def _csv(run_dir):
    return (run_dir / "trajectory.csv").read_bytes()


DAMAGE = {
    "truncated": lambda d, raw: (d / "trajectory.csv").write_bytes(raw[: len(raw) // 2 + 7]),
    "non-utf8": lambda d, raw: (d / "trajectory.csv").write_bytes(raw[:200] + b"\xff\xfe" +
                                                                   raw[200:]),
    "text cell": lambda d, raw: (d / "trajectory.csv").write_bytes(
        raw.replace(b"\n0.0,", b"\nabc,", 1)),
    "nan cell": lambda d, raw: (d / "trajectory.csv").write_bytes(
        raw.split(b"\n")[0] + b"\n" + b",".join([b"nan"] * len(trajectory_columns())) + b"\n"),
    "header only": lambda d, raw: (d / "trajectory.csv").write_bytes(raw.split(b"\n")[0] +
                                                                      b"\n"),
    "empty": lambda d, raw: (d / "trajectory.csv").write_bytes(b""),
    "broken metrics": lambda d, raw: (d / "metrics.json").write_text("{"),
    "foreign metrics": lambda d, raw: (d / "metrics.json").write_text("[1, 2]"),
    "metrics name": lambda d, raw: (d / "metrics.json").write_text('{"name": 5}'),
    "broken vehicle": lambda d, raw: (d / "vehicle.json").write_text("nul"),
    "foreign vehicle": lambda d, raw: (d / "vehicle.json").write_text('{"wings": 2}'),
    "bad vehicle": lambda d, raw: (d / "vehicle.json").write_text(
        json.dumps(dict(json.loads((d / "vehicle.json").read_text()), m="heavy"))),
    "broken parquet": lambda d, raw: ((d / "trajectory.csv").unlink(),
                                      (d / "trajectory.parquet").write_bytes(b"PAR1junk")),
}


@pytest.mark.parametrize("damage", sorted(DAMAGE))
def test_damaged_run_folders_are_named_errors(run_dir, tmp_path, damage):
    d = _copy(run_dir, tmp_path)
    DAMAGE[damage](d, _csv(run_dir))
    with pytest.raises(InputError) as e:
        read_run(d)
    assert str(d) in str(e.value)


def test_cli_animate_on_a_damaged_folder_is_one_line(run_dir, tmp_path):
    d = _copy(run_dir, tmp_path)
    DAMAGE["non-utf8"](d, _csv(run_dir))
    res = _run_cli("animate", str(d))
    assert res.returncode == 2 and "Traceback" not in res.stderr
    assert "not UTF-8" in res.stderr and not (d / "flight.gif").exists()


@pytest.mark.parametrize("name", ["movie.mp4", "noext", "folder.gif/"])
def test_output_names_that_cannot_be_a_gif(tmp_path, name):
    (tmp_path / "folder.gif").mkdir()
    with pytest.raises(InputError, match="output"):
        check_output(tmp_path / name)


@settings(**SETTINGS)
@given(cut=st.integers(0, 4000), junk=st.binary(max_size=8))
def test_property_any_damaged_csv_is_an_input_error_or_a_finite_table(run_dir, cut, junk):
    raw = _csv(run_dir)
    with tempfile.TemporaryDirectory() as d:
        folder = Path(d)
        (folder / "trajectory.csv").write_bytes(raw[:cut] + junk + raw[cut + len(junk):
                                                                      cut + 3000])
        try:
            table, _, _ = read_run(folder)
        except InputError:
            return
        assert table.shape[1] == len(trajectory_columns()) and np.isfinite(table).all()


@pytest.mark.slow
def test_run_with_animate_commits_the_gif_with_the_rest(tmp_path):
    out = tmp_path / "o"
    _old_run(out)
    res = _run_cli("run", "fig3a", "--set", "duration=0.5", "--quiet", "--no-plot",
                   "--animate", "--out", str(out))
    assert res.returncode == 0, res.stderr
    gif = (out / "flight.gif").read_bytes()
    assert gif[:6] in (b"GIF89a", b"GIF87a")
    assert not [p for p in out.iterdir() if "partial" in p.name]


def test_a_quadcog_error_is_not_swallowed_by_interrupted():
    from quadcog.errors import Interrupted
    assert not issubclass(Interrupted, QuadcogError) and issubclass(Interrupted,
                                                                    KeyboardInterrupt)


@pytest.mark.parametrize("at_frame", [0, 3])
def test_interrupt_while_drawing_is_an_interrupt_and_leaves_no_gif(run_dir, tmp_path,
                                                                   monkeypatch, at_frame):
    """matplotlib finishes a GIF in a `finally`; with no frame yet that raised IndexError in
    place of the interrupt (the issue's traceback)."""
    import signal

    from quadcog.errors import Interrupted
    from quadcog.viz import animation
    calls = []
    real = animation.rotation_matrix

    def interrupting(*a):
        calls.append(1)
        if len(calls) > at_frame:
            raise Interrupted(signal.SIGINT)
        return real(*a)
    monkeypatch.setattr(animation, "rotation_matrix", interrupting)
    out = tmp_path / "anim.gif"
    with pytest.raises(Interrupted):
        animation.animate_run(run_dir, out, max_frames=10)
    assert not out.exists() and not [p for p in tmp_path.iterdir() if "partial" in p.name]

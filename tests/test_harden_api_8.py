"""Eighth hostile-input pass: the failure map's and analyze's arguments, sweep_path's type,
and the embedded export's output folder and files."""
import os

import pytest

from quadcog.embedded import export_controller
from quadcog.errors import ExportError, InputError, SizeError, SweepError
from quadcog.studies.analysis import analyze
from quadcog.studies.analysis.failure_map import failure_map
from quadcog.sweeps import load_sweep, sweep, sweep_path

BAD_MAP = [
    ("grid", 2.5), ("grid", "3"), ("grid", None), ("grid", True), ("grid", 0), ("grid", -1),
    ("duration", "x"), ("duration", float("nan")), ("duration", 0),
    ("half_width", -0.1), ("half_width", 0.0), ("half_width", float("inf")),
    ("t_step", float("nan")), ("t_step", "1"),
    ("threshold", "a"), ("threshold", -1.0),
    ("controllers", "pd"), ("controllers", ("pd", "pd")), ("controllers", 3),
    ("progress", 1),
]


@pytest.mark.parametrize("key, value", BAD_MAP)
def test_failure_map_refuses_a_bad_argument_by_name(key, value):
    with pytest.raises(InputError, match=f"failure_map: {key}"):
        failure_map(**{"grid": 2, "duration": 2.0, key: value})


@pytest.mark.parametrize("grid", [10 ** 9, 600])
def test_failure_map_refuses_a_grid_beyond_one_sweep(grid):
    with pytest.raises(SizeError, match="failure_map: grid"):
        failure_map(grid=grid, duration=2.0)


@pytest.mark.parametrize("key, value", [("grid", 2.5), ("grid", 10 ** 9), ("duration", "x"),
                                        ("duration", float("nan"))])
def test_analyze_checks_the_map_arguments_before_any_work(tmp_path, key, value):
    with pytest.raises(InputError, match=f"failure_map: {key}"):
        analyze(tmp_path / "a", progress=False, **{key: value})
    assert not (tmp_path / "a").exists()


@pytest.mark.parametrize("spec", [None, 3, [], {}, ""])
@pytest.mark.parametrize("call", [sweep_path, load_sweep, sweep])
def test_sweep_entry_points_refuse_a_spec_that_is_no_path(call, spec):
    if call is sweep and isinstance(spec, dict):
        pytest.skip("a dict is a parsed sweep file for sweep()")
    with pytest.raises(SweepError, match="sweep: expected a sweep file path"):
        call(spec)


def test_export_refuses_a_null_byte_folder():
    with pytest.raises(ExportError, match="out"):
        export_controller("pd", out="a\0b")


def test_export_names_a_file_it_cannot_write(tmp_path):
    (tmp_path / "quadcog_pd.h").mkdir()
    with pytest.raises(ExportError, match=r"quadcog_pd\.h: is a folder"):
        export_controller("pd", out=tmp_path)
    assert os.path.isdir(tmp_path / "quadcog_pd.h")


def test_export_writes_its_header_and_source_together_or_not_at_all(tmp_path):
    """A source that cannot be replaced (here a folder) leaves the old header as it was: the
    export wrote the new header first, then failed on the source, leaving a mismatched pair."""
    (tmp_path / "quadcog_pd.h").write_text("/* the old header */")
    (tmp_path / "quadcog_pd.c").mkdir()
    with pytest.raises(ExportError, match=r"quadcog_pd\.c: is a folder"):
        export_controller("pd", out=tmp_path)
    assert (tmp_path / "quadcog_pd.h").read_text() == "/* the old header */"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quadcog_pd.c", "quadcog_pd.h"]


def test_export_refuses_an_empty_folder_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(ExportError, match=r"^out: expected a folder path"):
        export_controller("pd", out="")
    assert not list(tmp_path.iterdir())

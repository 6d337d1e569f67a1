"""quadcog.files' path and JSON checks: a path with a null byte is refused in the caller's
terms (os.stat's raw ValueError "embedded null byte" reached read_log, write_log, identify
and identified_cog), and every JSON file quadcog reads refuses an object that gives a key
twice (``json`` kept the last value in silence)."""
import pytest

from quadcog.errors import IdentificationError, InputError
from quadcog.files import input_file, output_path, path_kind, read_json


@pytest.mark.parametrize("name", ["a\0b.json", "\0", "sub/\0.csv"])
def test_a_null_byte_is_refused_in_words(tmp_path, name):
    path = str(tmp_path / name)
    assert path_kind(path) == "a path with a null byte (no file has one)"
    with pytest.raises(InputError, match="null byte"):
        input_file(path, "a flight log file")
    with pytest.raises(InputError, match=r"^--json: expected a file name without a null byte"):
        output_path(path, "--json")
    with pytest.raises(InputError, match="no null byte"):
        read_json(path)


@pytest.mark.parametrize("text, key", [
    ('{"r_G": [0, 0, 0], "r_G": [0.1, 0, 0]}', "r_G"),
    ('{"a": {"b": 1, "b": 2}}', "b"),                    # at any depth
    ('[{"x": 1}, {"y": 1, "y": 1}]', "y"),               # even with equal values
    ('{"r_G": 1, "r\\u005fG": 2}', "r_G"),               # spelled with an escape
])
def test_a_key_given_twice_is_refused(tmp_path, text, key):
    path = tmp_path / "f.json"
    path.write_text(text)
    with pytest.raises(IdentificationError, match=rf"key '{key}': expected once in the "
                                                  "identification, got it twice"):
        read_json(path, "identification", IdentificationError)


def test_other_exception_classes_get_the_same_message(tmp_path):
    class BuildError(Exception):
        pass
    path = tmp_path / "f.json"
    path.write_text('{"a": 1, "a": 1}')
    with pytest.raises(BuildError, match="key 'a': expected once"):
        read_json(path, "manifest", BuildError)
    path.write_text('{"a": 1, "b": [1, 2, {"c": null}]}')
    assert read_json(path) == {"a": 1, "b": [1, 2, {"c": None}]}


@pytest.mark.parametrize("kind", ["link", "fifo"])
def test_figures_and_analysis_files_never_write_through_a_link_or_fifo(tmp_path, kind):
    """save_figure (every plot function that takes a path), the failure map's .npz and .json
    and the analysis .json wrote with savefig, savez and open(): through a link into its
    target, and into a FIFO (blocking until a reader came)."""
    import os

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from quadcog.files import save_figure
    from quadcog.studies.analysis.analysis_files import write_json
    from quadcog.studies.analysis.failure_map import save_failure_map
    victim = tmp_path / "victim"
    victim.write_text("precious\n")

    def target(name):
        path = tmp_path / name
        if kind == "link":
            path.symlink_to(victim)
        else:
            os.mkfifo(path)
        return path
    fig = plt.figure()
    with pytest.raises(InputError, match="figure .*: is a (symbolic link|FIFO)"):
        save_figure(fig, target("f.png"))
    plt.close(fig)
    with pytest.raises(InputError, match="analysis .json .*: is a (symbolic link|FIFO)"):
        write_json({"a": 1.0}, target("analysis.json"))
    fm = {"x_G": [0.0], "y_G": [0.0], "admissible": [[True]], "lambda_min": [[1.0]],
          "controllers": {}}
    with pytest.raises(InputError, match="failure map .npz .*: is a (symbolic link|FIFO)"):
        save_failure_map(fm, target("fm.npz"), tmp_path / "fm.json")
    assert victim.read_text() == "precious\n" and not (tmp_path / "fm.json").exists()


def test_a_figure_is_written_whole_in_the_format_of_its_suffix(tmp_path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from quadcog.files import save_figure
    fig = plt.figure()
    fig.add_subplot().plot([0, 1], [1, 0])
    assert save_figure(fig, tmp_path / "f.png", dpi=50).read_bytes()[:4] == b"\x89PNG"
    assert save_figure(fig, tmp_path / "f.pdf").read_bytes()[:4] == b"%PDF"
    assert save_figure(fig, tmp_path / "noext").read_bytes()[:4] == b"\x89PNG"
    plt.close(fig)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.pdf", "f.png", "noext"]

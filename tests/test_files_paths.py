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

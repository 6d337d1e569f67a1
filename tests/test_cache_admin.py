"""`quadcog cache`: what the cache holds, by kind, and clearing it without harm: only what
was asked, never an entry whose build lock another process holds, never what a link inside
the cache points to; and a reader that leaves a pipe early is not an error."""
import fcntl
import os
from pathlib import Path
import subprocess
import sys

import pytest

from quadcog.codegen import cache
from quadcog.errors import InputError


def _fake_cache(root: Path, n_libraries: int = 2) -> Path:
    root.mkdir(parents=True, exist_ok=True)
    for i in range(n_libraries):
        stem = f"law_{i}-{i:020x}"
        (root / f"{stem}.so").write_bytes(b"x" * 1000)
        (root / f"{stem}.so.sha256").write_text("0" * 64)
        (root / f"{stem}.lock").write_text("")
    build = root / "px4" / "7f1eab822ccd8491"
    (build / "PX4-Autopilot" / "build").mkdir(parents=True)
    (build / "PX4-Autopilot" / "build" / "px4").write_bytes(b"y" * 5000)
    (build / "lock").write_text("")
    (root / "aqb" / "abc").mkdir(parents=True)
    (root / "aqb" / "abc" / "setup.py").write_text("z" * 300)
    return root


def test_entries_group_a_library_with_its_sidecars_and_each_folder_by_key(tmp_path):
    found = cache.entries(_fake_cache(tmp_path))
    by_name = {e.name: e for e in found}
    assert [e.kind for e in found] == ["libraries", "libraries", "aqb", "px4"]
    lib = by_name["law_0-" + "0" * 20]
    assert lib.size == 1000 + 64 and len(lib.paths) == 3
    assert by_name["px4/7f1eab822ccd8491"].size == 5000
    assert by_name["aqb/abc"].size == 300


def test_clear_removes_only_the_kinds_asked_and_leaves_a_busy_build(tmp_path):
    root = _fake_cache(tmp_path, 3)
    with open(root / ("law_1-" + "0" * 19 + "1.lock"), "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)              # a build of this library is under way
        removed, busy = cache.clear(["libraries"], root)
    assert [e.name for e in busy] == ["law_1-" + "0" * 19 + "1"]
    assert len(removed) == 2
    left = sorted(p.name for p in root.iterdir())
    assert left == ["aqb", "law_1-" + "0" * 19 + "1.lock", "law_1-" + "0" * 19 + "1.so",
                    "law_1-" + "0" * 19 + "1.so.sha256", "px4"]
    with open(root / "px4" / "7f1eab822ccd8491" / "lock", "a+") as fh:
        fcntl.flock(fh, fcntl.LOCK_EX)              # PX4 being built in the cache
        removed, busy = cache.clear([], root)
    assert [e.name for e in busy] == ["px4/7f1eab822ccd8491"]
    assert (root / "px4" / "7f1eab822ccd8491" / "PX4-Autopilot").is_dir()
    assert not (root / "aqb" / "abc").exists()
    removed, busy = cache.clear([], root)
    assert busy == [] and [e.name for e in cache.entries(root)] == []


def test_clear_does_not_follow_a_link_out_of_the_cache(tmp_path):
    root = _fake_cache(tmp_path / "cache")
    outside = tmp_path / "users_tree"
    outside.mkdir()
    (outside / "keep.txt").write_text("mine")
    (root / "vendor").mkdir()
    (root / "vendor" / "tree").symlink_to(outside)
    (root / "px4" / "7f1eab822ccd8491" / "PX4-Autopilot" / "src").symlink_to(outside)
    cache.clear([], root)
    assert (outside / "keep.txt").read_text() == "mine"
    assert not os.path.lexists(root / "vendor" / "tree")


def test_bad_kinds_and_a_cache_that_is_not_a_folder_are_refused(tmp_path):
    root = _fake_cache(tmp_path)
    with pytest.raises(InputError, match=r"'pxx'.*expected some of .*px4"):
        cache.clear(["pxx"], root)
    with pytest.raises(InputError, match="string 'px4'"):
        cache.clear("px4", root)
    assert cache.clear(["crazyflie"], root) == ([], [])    # a known kind, none here
    (tmp_path / "file").write_text("")
    with pytest.raises(InputError, match="not a folder"):
        cache.entries(tmp_path / "file")
    assert cache.entries(tmp_path / "missing") == []


def _quadcog(args, env_cache, **kw):
    env = dict(os.environ, QUADCOG_CACHE_DIR=str(env_cache))
    return subprocess.run([sys.executable, "-m", "quadcog", *args], env=env,
                          capture_output=True, text=True, timeout=120, **kw)


def test_the_command_lists_by_kind_and_clears(tmp_path):
    root = _fake_cache(tmp_path)
    r = _quadcog(["cache"], root)
    assert r.returncode == 0, r.stderr
    assert f"{root}: 4 entries" in r.stdout
    assert "libraries" in r.stdout and "px4" in r.stdout and "4.9 KB" in r.stdout
    r = _quadcog(["cache", "--clear", "px4"], root)
    assert r.returncode == 0 and "removed 1 entries (4.9 KB)" in r.stdout
    assert not (root / "px4" / "7f1eab822ccd8491").exists() and (root / "aqb").is_dir()
    r = _quadcog(["cache", "--clear", "nonsense"], root)
    assert r.returncode == 2 and "'nonsense'" in r.stderr and "Traceback" not in r.stderr


def test_a_reader_that_leaves_the_pipe_early_is_not_an_error(tmp_path):
    root = _fake_cache(tmp_path, 3000)                 # a listing longer than a pipe holds
    env = dict(os.environ, QUADCOG_CACHE_DIR=str(root))
    p = subprocess.Popen([sys.executable, "-m", "quadcog", "cache", "--all"], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    p.stdout.readline()
    p.stdout.close()                                   # `| head -1`
    err = p.stderr.read().decode()
    assert p.wait(timeout=120) == 141 and err == ""


def test_nothing_but_quadcog_s_entries_is_listed_or_removed(tmp_path):
    """QUADCOG_CACHE_DIR set by mistake to a folder of the user's (their home): `quadcog
    cache --clear` removed every file and every folder's contents there (notes.txt,
    Documents/thesis/...); only compiled libraries (STEM-KEY.so, KEY of 20 hex digits) and
    the folders of cache.KINDS are quadcog's."""
    home = tmp_path / "home"
    (home / "Documents" / "thesis").mkdir(parents=True)
    (home / "Documents" / "thesis" / "ch1.tex").write_text("chapter one\n")
    (home / "notes.txt").write_text("notes\n")
    (home / "libfoo.so").write_text("a user's library\n")
    (home / "photos-0123456789abcdef0123.txt").write_text("not a library\n")
    (home / "plant_step-0123456789abcdef0123.so").write_text("quadcog's\n")
    (home / "plant_step-0123456789abcdef0123.lock").write_text("")
    (home / "px4" / "0123abcd").mkdir(parents=True)
    user_files = sorted(p for p in home.rglob("*") if "plant_step" not in p.name
                        and "0123abcd" not in str(p))
    found = cache.entries(home)
    assert sorted(e.name for e in found) == ["plant_step-0123456789abcdef0123", "px4/0123abcd"]
    removed, busy = cache.clear(folder=home)
    assert len(removed) == 2 and busy == []
    assert sorted(home.rglob("*")) == user_files
    assert (home / "Documents" / "thesis" / "ch1.tex").read_text() == "chapter one\n"

"""The compile cache under faults: damaged or planted libraries are rebuilt, never loaded;
unusable cache folders give a warning and a working fallback; interrupted builds leave no
build folders behind."""
import os
from pathlib import Path
import shutil
import signal
import socket
import subprocess
import sys
import time

from conftest import default_sigint
import numpy as np
import pytest

import quadcog
from quadcog.codegen import compiler as build
from quadcog.codegen.compiler import compile_library, file_digest, is_verified

ROOT = Path(__file__).resolve().parent.parent
TWICE = b"double f(double x) { return 2.0 * x; }\n"
THRICE = b"double f(double x) { return 3.0 * x; }\n"


def _f(lib, x):
    """Call f(x) of a library in a child process (a broken library must not kill pytest)."""
    code = (f"import ctypes; f = ctypes.CDLL({str(lib)!r}).f; f.restype = ctypes.c_double; "
            f"f.argtypes = [ctypes.c_double]; print(f({x}))")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    return float(res.stdout)


def _build_folders(folder):
    return sorted(p.name for p in Path(folder).glob(".*build-*"))


def test_digest_recorded_after_build(tmp_path):
    lib = compile_library(TWICE, "t", folder=tmp_path)
    assert (tmp_path / (lib.name + ".sha256")).read_text().strip() == file_digest(lib)
    assert is_verified(lib) and _f(lib, 1.5) == 3.0
    assert _build_folders(tmp_path) == []


@pytest.mark.parametrize("damage", ["truncated", "planted", "no digest", "symlink"])
def test_damaged_library_is_rebuilt(tmp_path, damage):
    lib = compile_library(TWICE, "t", folder=tmp_path)
    good = file_digest(lib)
    other = compile_library(THRICE, "t", folder=tmp_path / "other")
    if damage == "truncated":
        data = lib.read_bytes()
        lib.write_bytes(data[:len(data) // 2])
    elif damage == "planted":                   # a library built from other source
        shutil.copyfile(other, lib)
    elif damage == "no digest":
        shutil.copyfile(other, lib)
        (tmp_path / (lib.name + ".sha256")).unlink()
    else:
        lib.unlink()
        lib.symlink_to(other)
    assert not is_verified(lib)
    if damage == "no digest":                   # e.g. left by an earlier version: no warning
        again = compile_library(TWICE, "t", folder=tmp_path)
    else:
        with pytest.warns(quadcog.QuadcogWarning, match="does not match the SHA-256 recorded"):
            again = compile_library(TWICE, "t", folder=tmp_path)
    assert again == lib and not lib.is_symlink() and file_digest(lib) == good
    assert _f(again, 1.5) == 3.0


def test_truncated_generated_library_does_not_crash_load(tmp_path):
    """Issue 10's reproducer: a right-named quadcog_gen .so truncated to half its size used to
    kill the interpreter with SIGBUS on every load()."""
    model = quadcog.load()
    p = quadcog.default_parameters(x_G=0.03)
    U = [0.68 * 9.81, 0.0, -0.68 * 9.81 * 0.03, 0.0]
    model.dynamics(np.zeros(12), U, p)                     # builds into the default cache
    src = quadcog.paths.generated_dir() / "c" / "quadcog_gen.c"
    good = build.library_path(src.read_bytes(), "quadcog_gen", build.find_compiler())
    cache = tmp_path / "cache"
    cache.mkdir()
    lib = cache / good.name
    lib.write_bytes(good.read_bytes()[:good.stat().st_size // 2])
    shutil.copyfile(good.with_name(good.name + ".sha256"), lib.with_name(lib.name + ".sha256"))
    code = ("import numpy as np, quadcog; p = quadcog.default_parameters(x_G=0.03); "
            f"print(np.abs(quadcog.load().dynamics(np.zeros(12), {U}, p)).max())")
    res = subprocess.run([sys.executable, "-W", "always", "-c", code], capture_output=True,
                         text=True, timeout=300,
                         env=dict(os.environ, QUADCOG_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT)))
    assert res.returncode == 0, res.stderr
    assert float(res.stdout) < 1e-12                       # hover trim: x_dot = 0
    assert "does not match the SHA-256 recorded" in res.stderr
    assert file_digest(lib) == file_digest(good)


def _read_only(monkeypatch, tmp_path):
    cache = tmp_path / "ro"
    cache.mkdir()
    if os.geteuid() != 0:
        cache.chmod(0o555)
    else:           # root writes anywhere: make the cache's lock and build folder fail as EACCES
        real_exclusive = build._exclusive

        def exclusive(path):
            if Path(path).parent == cache:
                raise PermissionError(13, "Permission denied", str(path))
            return real_exclusive(path)
        monkeypatch.setattr(build, "_exclusive", exclusive)
    return cache


@pytest.mark.parametrize("fault", ["read-only", "a file", "folder in the library's place",
                                   "below a file"])
def test_unusable_cache_folder_warns_and_works(tmp_path, monkeypatch, fault):
    monkeypatch.setattr(build, "_warned", set())
    if fault == "read-only":
        cache = _read_only(monkeypatch, tmp_path)
    elif fault == "a file":
        cache = tmp_path / "cache"
        cache.write_text("not a folder")
    elif fault == "below a file":
        (tmp_path / "file").write_text("x")
        cache = tmp_path / "file" / "cache"
    else:
        cache = tmp_path / "cache"
        build.library_path(TWICE, "t", build.find_compiler(), folder=cache).mkdir(parents=True)
    with pytest.warns(quadcog.QuadcogWarning, match=f"compile cache {cache} cannot be used"):
        lib = compile_library(TWICE, "t", folder=cache)
    assert lib.parent == build._private_cache() and is_verified(lib)
    assert _f(lib, 2.0) == 4.0
    if cache.is_dir():
        assert not list(cache.glob("*.so")) or fault != "read-only"
        assert _build_folders(cache) == []


def test_read_only_cache_with_a_verified_library_is_used(tmp_path, monkeypatch):
    lib = compile_library(TWICE, "t", folder=tmp_path / "ro")
    monkeypatch.setattr(build, "_exclusive", lambda path: (_ for _ in ()).throw(
        PermissionError(13, "Permission denied", str(path))))
    assert compile_library(TWICE, "t", folder=tmp_path / "ro") == lib     # no lock needed


def test_ctrl_c_during_compile_leaves_no_build_folder(tmp_path, monkeypatch):
    real_run = subprocess.run

    def interrupted(cmd, *args, **kwargs):
        if "-o" not in cmd:                 # `cc --version`
            return real_run(cmd, *args, **kwargs)
        assert _build_folders(tmp_path), "the build folder should exist while compiling"
        raise KeyboardInterrupt
    monkeypatch.setattr(build.subprocess, "run", interrupted)
    with pytest.raises(KeyboardInterrupt):
        compile_library(TWICE, "t", cc="cc", folder=tmp_path)
    assert _build_folders(tmp_path) == []


def test_killed_build_is_cleaned_up_by_the_next(tmp_path):
    """A build killed outright (SIGKILL: no cleanup runs) leaves its folder; the next build in
    the cache removes it, since its process is gone. Also a SIGINT'd build cleans up itself."""
    slow = tmp_path / "slowcc"
    slow.write_text('#!/bin/sh\n[ "$1" = --version ] && { echo slowcc; exit 0; }\nexec sleep 60\n')
    slow.chmod(0o755)
    cache = tmp_path / "cache"
    code = (f"from quadcog.codegen.compiler import compile_library; "
            f"compile_library({TWICE!r}, 't', cc={str(slow)!r}, folder={str(cache)!r})")
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    for sig in (signal.SIGKILL, signal.SIGINT):
        proc = subprocess.Popen([sys.executable, "-c", code], env=env, stderr=subprocess.PIPE,
                                start_new_session=True, preexec_fn=default_sigint)
        deadline = time.time() + 60
        while not _build_folders(cache) and time.time() < deadline:
            time.sleep(0.05)
        assert _build_folders(cache), "the build never started"
        os.killpg(proc.pid, sig)           # the whole group, as a terminal's Ctrl-C does
        proc.wait(timeout=60)
        if sig == signal.SIGKILL:
            left = _build_folders(cache)
            assert len(left) == 1 and f"-{proc.pid}-" in left[0]
            lib = compile_library(TWICE, "t", folder=cache)
            assert _build_folders(cache) == [] and _f(lib, 1.0) == 2.0
        else:
            assert proc.returncode == -signal.SIGINT and b"KeyboardInterrupt" in proc.stderr.read()
            assert _build_folders(cache) == []


def test_build_folders_of_live_processes_are_kept(tmp_path):
    mine = tmp_path / f".build-{socket.gethostname()}-{os.getpid()}-abc"
    mine.mkdir()
    legacy_fresh = tmp_path / ".quadcog_gen-build-xyz"
    legacy_fresh.mkdir()
    assert build.remove_stale_build_folders(tmp_path) == []
    old = time.time() - 2 * 3600
    os.utime(legacy_fresh, (old, old))
    assert build.remove_stale_build_folders(tmp_path) == [legacy_fresh]
    assert mine.is_dir()

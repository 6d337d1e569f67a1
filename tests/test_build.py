"""The compile cache: keyed, atomic, safe with 8 processes at once; VM fallback without cc."""
import os
from pathlib import Path
import subprocess
import sys

import pytest

import quadcog
from quadcog.codegen.compiler import compile_library, library_path

ROOT = Path(__file__).resolve().parent.parent

SCRIPT = """
import sys, numpy as np, quadcog
m = quadcog.load()
p = quadcog.default_parameters()
x = np.zeros(12)
xd = m.dynamics(x, [p[0] * p[1], 0, 0, 0], p)
print(m.backend, float(np.abs(xd).max()))
"""


def _env(cache, **extra):
    env = dict(os.environ, QUADCOG_CACHE_DIR=str(cache), PYTHONPATH=str(ROOT))
    env.update(extra)
    return env


def test_eight_processes_build_at_once(tmp_path):
    cache = tmp_path / "cache"
    procs = [subprocess.Popen([sys.executable, "-c", SCRIPT], env=_env(cache),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
             for _ in range(8)]
    outs = [p.communicate(timeout=300) for p in procs]
    for p, (out, err) in zip(procs, outs):
        assert p.returncode == 0, err
        backend, residual = out.split()
        assert backend == "c" and float(residual) < 1e-12
    libs = sorted(cache.glob("quadcog_gen-*.so"))
    assert len(libs) == 1, libs
    leftovers = [f for f in cache.iterdir() if f.suffix not in (".so", ".lock", ".sha256")]
    assert not leftovers, leftovers


def test_cache_key_changes_with_source_and_flags(tmp_path):
    a = library_path(b"int f(void){return 1;}", "t", "cc", folder=tmp_path)
    b = library_path(b"int f(void){return 2;}", "t", "cc", folder=tmp_path)
    c = library_path(b"int f(void){return 1;}", "t", "cc", ("-O0", "-shared", "-fPIC"), tmp_path)
    assert len({a, b, c}) == 3


def test_compile_error_is_typed(tmp_path):
    with pytest.raises(quadcog.CompileError, match="failed with exit code"):
        compile_library(b"this is not C", "broken", folder=tmp_path)


def test_virtual_machine_fallback_without_compiler(tmp_path):
    code = SCRIPT + """
import warnings
ctl = quadcog.FeedbackLinearization()
r = quadcog.simulate(ctl, 'circle', duration=0.5)
print(r.metrics.rms_position_error)
"""
    res = subprocess.run([sys.executable, "-W", "always", "-c", code],
                         env=_env(tmp_path / "c2", CC="no-such-compiler"),
                         capture_output=True, text=True, timeout=300)
    assert res.returncode == 0, res.stderr
    lines = res.stdout.split("\n")
    assert lines[0].startswith("casadi-vm")
    assert "QuadcogWarning" in res.stderr and "no C compiler" in res.stderr
    compiled = quadcog.simulate(quadcog.FeedbackLinearization(), "circle", duration=0.5)
    assert float(lines[1]) == pytest.approx(compiled.metrics.rms_position_error, rel=1e-9)
    # nothing was compiled into that run's cache (a missing folder globs to nothing)
    assert sorted(p.name for p in (tmp_path / "c2").glob("*.so")) == []

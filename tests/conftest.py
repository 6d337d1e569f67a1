"""Shared fixtures: seeded samplers of admissible parameter sets and states; long subprocess
jobs started in the background (background_job)."""
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
import shutil
import tempfile

import numpy as np
import pytest

import quadcog
from quadcog.model.sampling import random_points

N_POINTS = 200       # every identity is checked at this many random points at least


@pytest.fixture(scope="session")
def model():
    return quadcog.load()


@pytest.fixture(scope="session")
def points():
    """N_POINTS seeded (x, U, p, vartheta) tuples."""
    return random_points(N_POINTS)


@pytest.fixture(scope="session")
def derived():
    """The SymPy derivation (tests may import SymPy; the runtime may not)."""
    from derive.model import derive_model
    return derive_model()


def assert_close(actual, expected, rtol, what, point=None):
    """|actual - expected|_max <= rtol * max(1, |expected|_max), with a readable message."""
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    scale = max(1.0, float(np.max(np.abs(expected))))
    err = float(np.max(np.abs(actual - expected)))
    assert err <= rtol * scale, (
        f"{what}: max abs error {err:.3e} > {rtol:g} * {scale:.3g}"
        + (f" at point {point}" if point is not None else "")
        + f"\nactual:\n{actual}\nexpected:\n{expected}")
    return err / scale


# -- long subprocess jobs, started in the background ------------------------------------------
# A few tests wait for seconds on work that is only subprocesses and files (a derivation, the
# cross-compilations and QEMU runs, wheel builds). A test module registers such a job with
# background_job(); once the tests are collected, the jobs of the tests that will run start
# on one background thread, in registration (file) order, while the first tests run on the
# other core. The test then takes the result with background_result(), which runs the job
# there and then if it was not started (--collect-only). A job's exception is raised in the
# test that takes its result.

_JOBS = {}            # name -> dict(module=file name, user, prepare=callable, future=None, lane)
_POOLS = {}           # lane -> a one-thread executor: jobs of one lane run one after another
_DIRS = []


def background_dir(prefix):
    """A temporary folder for a job's files, removed at the end of the session."""
    _DIRS.append(Path(tempfile.mkdtemp(prefix=f"quadcog-test-{prefix}-")))
    return _DIRS[-1]


def background_job(name, module, user, prepare, lane="main"):
    """Register ``prepare`` for ``user``, the fixture or the test of ``module`` (its __file__)
    that takes the result (a test's name, or one parametrized case as ``test_x[id]``): the job
    starts if a collected test of that module is or uses it. ``prepare`` is called in the main
    thread (for anything that touches CasADi or quadcog state) and returns the function that
    does the long work on the background thread of ``lane``; that function's return value is
    the job's result. Jobs of another lane run beside those of the first (subprocesses that
    would otherwise wait behind one another)."""
    _JOBS.setdefault(name, dict(module=Path(module).name, user=user, prepare=prepare,
                                future=None, lane=lane))


def background_result(name):
    """The result of job ``name`` (waits for it; runs it now if it was not started)."""
    job = _JOBS[name]
    if job["future"] is None:
        return job["prepare"]()()
    future, job["future"] = job["future"], None          # a second call runs it again
    return future.result()


def _start(job):
    try:
        work = job["prepare"]()
    except Exception as e:                               # raised in the test, not here
        def work(e=e):
            raise e
    if job["lane"] not in _POOLS:
        _POOLS[job["lane"]] = ThreadPoolExecutor(max_workers=1,
                                                 thread_name_prefix=f"tests-bg-{job['lane']}")
    return _POOLS[job["lane"]].submit(work)


def pytest_collection_finish(session):
    if session.config.option.collectonly:
        return
    for job in _JOBS.values():
        if any(item.path.name == job["module"] and (job["user"] in item.fixturenames or
                                                     job["user"] in (item.originalname,
                                                                     item.name))
               for item in session.items):
            job["future"] = _start(job)


def pytest_sessionfinish(session):
    for pool in _POOLS.values():
        pool.shutdown(wait=True, cancel_futures=True)
    for folder in _DIRS:
        shutil.rmtree(folder, ignore_errors=True)


def default_sigint():
    """``preexec_fn`` of a child that a test interrupts: SIGINT at its default, as a terminal
    user's process has it. A shell without job control starts a background job (``cmd &``
    in a script, a CI runner) with SIGINT ignored, the child would inherit that, and Python
    keeps an inherited ignore until the program installs a handler, so an early Ctrl-C would
    be lost and the test would depend on how pytest was started."""
    import signal
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupt_mid_flight(argv, sig, *, group=False, **popen):
    """Run ``argv`` with stderr on a terminal (so its progress bar draws as a user sees it),
    send ``sig`` once the bar shows the work under way, and return (status, stderr with
    newlines). A fixed sleep raced the compiled kernel, which flies 600 s in about a second;
    on a pipe the bar prints only when done. ``group``: signal the process group (Ctrl-C)."""
    import os
    import pty
    import select
    import subprocess
    master, slave = pty.openpty()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=slave, text=True,
                            preexec_fn=default_sigint, **popen)
    os.close(slave)
    seen, sent = b"", False
    try:
        while True:
            ready, _, _ = select.select([master], [], [], 120)
            assert ready, f"no output for 120 s: {seen!r}"
            try:
                chunk = os.read(master, 4096)
            except OSError:              # EIO: the child closed the terminal
                chunk = b""
            if not chunk:
                break
            seen += chunk
            if not sent and b"%" in seen:
                assert proc.poll() is None, f"the run ended before it could be interrupted: {seen!r}"
                os.killpg(proc.pid, sig) if group else proc.send_signal(sig)
                sent = True
        proc.communicate(timeout=60)
    finally:                             # a failed assertion leaves no run behind
        os.close(master)
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert sent, f"the run showed no progress before it ended: {seen!r}"
    return proc.returncode, seen.decode(errors="replace").replace("\r\n", "\n")


def cli_error_line(capsys):
    """The one line a refused command printed on stderr (argparse's usage lines aside), with
    no traceback and no internal error."""
    err = capsys.readouterr().err
    lines = [l for l in err.strip().splitlines() if not l.startswith("usage:")
             and not l.startswith(" ")]
    assert len(lines) == 1, err          # one line, whatever the names hold
    assert "Traceback" not in err and "internal error" not in err
    return lines[0]


@pytest.fixture
def no_flight(monkeypatch):
    """Any flight is a failure of the test: refusals come before the work."""
    from quadcog.scenarios.scenario import Scenario

    def flown(*args, **kwargs):
        raise AssertionError("the scenario was flown before the refusal")
    monkeypatch.setattr(Scenario, "run", flown)


def small_sweep(**extra):
    """A sweep file's data: two 0.3 s flights of fig6 under fl, ``extra`` keys added."""
    data = {"scenario": "fig6", "set": {"duration": 0.3, "controller": "fl",
                                        "controller_params": {}},
            "dimension": [{"key": "cog[0].r[0]", "values": [0.0, 0.01]}]}
    data.update(extra)
    return data

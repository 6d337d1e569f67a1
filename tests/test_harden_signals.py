"""Issue 21, signals: SIGINT and SIGTERM in `quadcog run`, `sweep`, `animate`, `identify` give
one line (`quadcog: interrupted`), exit status 130 / 143, no temporary file left and no child
process; SIGKILL of `quadcog sweep` leaves no worker running for long; Ctrl-C while the
command is still starting prints no traceback."""
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

from conftest import default_sigint, interrupt_mid_flight
import pytest

from quadcog.errors import Interrupted
from quadcog.interrupts import install_handlers, restore_handlers

ROOT = Path(__file__).resolve().parent.parent
FINAL = {"metrics.json", "vehicle.json", "trajectory.csv", "flight.png"}


def _start(*args, **kw):
    return subprocess.Popen([sys.executable, "-m", "quadcog", *args], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            preexec_fn=default_sigint, **kw)


def _children(pid):
    kids = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                if int((d / "stat").read_text().rsplit(")", 1)[1].split()[1]) == pid:
                    kids.append(int(d.name))
            except (OSError, ValueError, IndexError):
                pass
    return kids


def _alive(pid):
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_handlers_raise_interrupted_with_the_shell_status():
    previous = install_handlers()
    try:
        for sig, status in ((signal.SIGINT, 130), (signal.SIGTERM, 143)):
            with pytest.raises(Interrupted) as e:
                os.kill(os.getpid(), sig)
                time.sleep(1)
            assert e.value.status == status and isinstance(e.value, KeyboardInterrupt)
            install_handlers()
    finally:
        restore_handlers(previous)
    assert signal.getsignal(signal.SIGTERM) == previous[signal.SIGTERM]


@pytest.mark.parametrize("sig, status", [(signal.SIGTERM, 143),
                                         pytest.param(signal.SIGINT, 130,
                                                      marks=pytest.mark.slow)])
def test_run_interrupted_mid_flight_leaves_the_previous_folder(tmp_path, sig, status):
    out = tmp_path / "run"
    out.mkdir()
    (out / "metrics.json").write_text('{"old": true}\n')
    (out / "trajectory.csv").write_text("old\n")
    code, err = interrupt_mid_flight(
        [sys.executable, "-m", "quadcog", "run", "fig3a", "--set", "duration=300", "--out",
         str(out)], sig, cwd=ROOT)
    assert code == status, err
    assert err.strip().endswith("quadcog: interrupted") and "Traceback" not in err
    assert "\nquadcog: interrupted" in "\n" + err, err    # not run on after the bar
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "trajectory.csv"]
    assert (out / "metrics.json").read_text() == '{"old": true}\n'


@pytest.fixture(scope="module")
def interpreter_startup():
    """Seconds the interpreter takes to start (site, the editable-install finder) before any
    quadcog code runs: a signal then is Python's own, beyond the package's reach."""
    t0 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "pass"], check=True)
    return time.perf_counter() - t0


@pytest.mark.parametrize("delay", [0.05, 0.15])
def test_ctrl_c_while_starting_prints_no_traceback(tmp_path, delay, interpreter_startup):
    proc = _start("run", "fig3a", "--out", str(tmp_path / "o"))
    time.sleep(interpreter_startup + delay)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == -signal.SIGINT:    # before the interpreter had a handler at all:
        assert err == ""                     # ended by the signal itself, silently
        return
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "quadcog: interrupted" in err


SLOW_SWEEP = """
scenario = "fig6"
chunk = 1
[set]
duration = 30.0
controller = "fl"
controller_params = {}
[[dimension]]
key = "cog[0].r[0]"
values = [0.0, 0.01, 0.02, 0.03, 0.04, 0.05]
"""


def _sweep_with_workers(tmp_path):
    path = tmp_path / "slow.toml"
    path.write_text(SLOW_SWEEP)
    out = tmp_path / "out"
    proc = _start("sweep", str(path), "--out", str(out))
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline and len(_children(proc.pid)) < 2:
        time.sleep(0.05)
    kids = _children(proc.pid)
    return proc, out, kids


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: the sweep uses no pool")
def test_sweep_sigterm_ends_its_workers_and_removes_its_files(tmp_path):
    proc, out, kids = _sweep_with_workers(tmp_path)
    assert len(kids) >= 2
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 143, err
    assert "quadcog: interrupted" in err and "Traceback" not in err
    assert not any(_alive(k) for k in kids)
    left = [p.name for p in out.rglob("*") if "partial" in p.name or p.name.endswith(".tmp")]
    assert left == [] and not (out / ".sweep.lock").exists()


@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="one core: the sweep uses no pool")
def test_sigkill_of_a_sweep_leaves_no_worker_running(tmp_path):
    proc, out, kids = _sweep_with_workers(tmp_path)
    assert len(kids) >= 2
    proc.kill()
    proc.communicate(timeout=30)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(_alive(k) for k in kids):
        time.sleep(0.1)
    survivors = [k for k in kids if _alive(k)]
    for k in survivors:                 # do not leave them to the next test
        os.kill(k, signal.SIGKILL)
    assert survivors == []


@pytest.mark.slow
def test_animate_interrupted_leaves_no_partial_gif(tmp_path):
    out = tmp_path / "run"
    res = subprocess.run([sys.executable, "-m", "quadcog", "run", "fig3a", "--set",
                          "duration=2", "--no-plot", "--quiet", "--out", str(out)], cwd=ROOT,
                         capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    proc = _start("animate", str(out), "--max-frames", "400", "--fps", "100")
    time.sleep(3.0)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    if proc.returncode == 0:
        pytest.skip("the animation finished before the signal")
    assert proc.returncode == 130 and "Traceback" not in err
    assert not (out / "flight.gif").exists()
    assert not [p for p in out.iterdir() if "partial" in p.name]

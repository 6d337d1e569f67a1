"""Issue 33: Ctrl-C (SIGINT to the whole process group, as a terminal sends it) to a sweep on
two local Dask workers prints the one clean line and no worker's KeyboardInterrupt
traceback."""
import os
from pathlib import Path
import signal
import subprocess
import sys
import time

import pytest

from quadcog.sweeps.worker_setup import dask_setup

pytest.importorskip("distributed")
ROOT = Path(__file__).resolve().parent.parent
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


def test_the_worker_preload_ignores_sigint():
    old = signal.getsignal(signal.SIGINT)
    try:
        dask_setup(None)
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, old)


@pytest.mark.slow
@pytest.mark.skipif((os.cpu_count() or 1) < 2, reason="two workers on one core")
def test_ctrl_c_to_a_dask_sweep_prints_no_worker_traceback(tmp_path):
    (tmp_path / "slow.toml").write_text(SLOW_SWEEP)
    proc = subprocess.Popen([sys.executable, "-m", "quadcog", "sweep", "slow.toml", "--out",
                             "out", "--workers", "2"], cwd=tmp_path, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True,
                            env=dict(os.environ, PYTHONPATH=str(ROOT)))
    deadline = time.monotonic() + 180      # until the workers have flown a chunk
    while time.monotonic() < deadline and not list((tmp_path / "out").rglob("*.parquet")):
        time.sleep(0.2)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "quadcog: interrupted" in err
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err


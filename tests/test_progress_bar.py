"""The progress bar on a terminal and on a log: a long run's log shows how far it got."""
import io

import pytest

from quadcog.errors import InputError
import quadcog.viz.progress as progress
from quadcog.viz.progress import ProgressBar


class Clock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


class Tty(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_line_every_log_every_seconds_then_the_final_one(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    log = io.StringIO()                      # not a terminal
    bar = ProgressBar("run", stream=log, log_every=10.0)          # 5 s by default
    for k in range(1, 101):                  # 100 updates, 1 s apart
        clock.t = float(k)
        bar(k / 200)
    bar.close()
    lines = log.getvalue().strip("\n").split("\n")
    # at 10, 20, ..., 100 s, then close()'s line: each a whole line with its percentage
    assert len(lines) == 11, lines
    assert lines[0].startswith("run [") and "5.0%" in lines[0] and "10.0 s" in lines[0]
    assert "50.0%" in lines[-1]
    assert all("\r" not in line for line in lines[:-1])


def test_a_short_run_on_a_log_prints_only_the_final_line(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    log = io.StringIO()
    bar = ProgressBar("run", stream=log)
    for k in range(1, 11):
        clock.t = k * 0.1
        bar(k / 10)
    bar.close()
    assert log.getvalue().count("\n") == 1 and "100.0%" in log.getvalue()


def test_a_terminal_redraws_one_line(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    tty = Tty()
    bar = ProgressBar("run", stream=tty)
    for k in range(1, 11):
        clock.t = k * 1.0
        bar(k / 10)
    bar.close()
    out = tty.getvalue()
    assert out.count("\n") == 1 and out.count("\r") == 11, out


def test_a_closed_bar_that_was_never_called_prints_nothing():
    log = io.StringIO()
    ProgressBar("run", stream=log).close()
    assert log.getvalue() == ""


@pytest.mark.parametrize("bad", [0, -1.0, float("nan"), "10"])
def test_log_every_must_be_positive(bad):
    with pytest.raises(InputError, match="log_every"):
        ProgressBar("run", log_every=bad)


def test_the_default_interval_is_the_config_entry(monkeypatch):
    from quadcog import config
    monkeypatch.setitem(config.defaults, "progress.log_every", 2.5)
    assert ProgressBar("run").log_every == 2.5

"""The progress bar and the counter on a terminal and on a log: a long run's log shows how far
it got."""
import io

import pytest

from quadcog.errors import InputError
import quadcog.viz.progress as progress
from quadcog.viz.progress import ProgressBar, ProgressCounter


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


def test_the_counter_on_a_log_first_line_at_once_then_every_log_every_then_done(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    log = io.StringIO()
    count = ProgressCounter("sweep s", total=100, done=20, stream=log, log_every=5.0)
    for k in range(1, 81):                   # one flight a second after the 20 resumed
        clock.t = float(k)
        count(1)
    lines = log.getvalue().strip("\n").split("\n")
    # at 1 s, then 6, 11, ..., 76 s (16 lines), and the final one at 80 s
    assert len(lines) == 17, lines
    assert lines[0] == "sweep s: 21/100 flights (21 %), 1.0 flights/s, 79 s left"
    assert lines[-1] == "sweep s: 100/100 flights (100 %), 1.0 flights/s"


def test_the_counter_on_a_terminal_ends_its_line_when_done(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress.time, "perf_counter", clock)
    tty = Tty()
    count = ProgressCounter("sweep s", total=3, stream=tty)
    for k in range(1, 4):
        clock.t = float(k)
        count(1)
    out = tty.getvalue()
    assert out.count("\r") == 3 and out.endswith("\n") and out.count("\n") == 1, out

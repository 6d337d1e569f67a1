"""Progress on stderr for long runs: a bar for a fraction done (``ProgressBar``) and a
counter of items done of a total with the rate (``ProgressCounter``, a sweep's flights).

Both redraw one line on a terminal (at most every 0.2 s) and, on a stream that is not a
terminal (a log, CI, a pipe), write a whole line at most every
``config.defaults["progress.log_every"]`` seconds, so a log of a long run shows how far it got.
"""
import math
import sys
import time
from typing import TextIO

from quadcog import config
from quadcog.files import one_line
from quadcog.validate import positive

__all__ = ["ProgressBar", "ProgressCounter"]

REDRAW = 0.2                # s between two redraws on a terminal


class _Printer:
    """One line of progress: redrawn on a terminal, a line now and then on a log."""

    def __init__(self, stream: TextIO | None, log_every: float | None, where: str,
                 first_at_once: bool) -> None:
        self.stream = stream or sys.stderr
        self.log_every = positive(config.get("progress.log_every", log_every),
                                  f"{where}: log_every", "s")
        self._live = getattr(self.stream, "isatty", lambda: False)()
        self._t0 = time.perf_counter()
        # when the last line was written: a terminal draws at the first call; a log's first
        # line comes after log_every unless the first call is to show at once
        self._last = -math.inf if first_at_once or self._live else self._t0

    def _due(self, now: float, final: bool) -> bool:
        return final or now - self._last >= (REDRAW if self._live else self.log_every)

    def _show(self, text: str, now: float, final: bool) -> None:
        self._last = now
        text = one_line(text, word=120)     # a label from a file: a newline, 5000 characters
        if self._live:
            self.stream.write("\r" + text + ("\n" if final else ""))
        else:
            self.stream.write(text + "\n")
        self.stream.flush()


class ProgressBar(_Printer):
    """A progress bar: call it with a fraction in [0, 1].

    On a terminal it redraws one line at most every 0.2 s and finishes on close(). On a stream
    that is not a terminal (a log, CI, a pipe) it writes a whole line at most every
    ``log_every`` seconds and the final line on close().

    Parameters
    ----------
    label : str
        Printed before the bar.
    stream : file-like, optional
        Where to print (default ``sys.stderr``).
    width : int
        Characters of the bar.
    log_every : float, optional
        Seconds between the lines written to a stream that is not a terminal (> 0; default
        ``config.defaults["progress.log_every"]``).
    """

    def __init__(self, label: str, stream: TextIO | None = None, width: int = 30,
                 log_every: float | None = None) -> None:
        super().__init__(stream, log_every, "ProgressBar", first_at_once=False)
        self.label, self.width = label, width
        self._fraction = 0.0
        self._called = False

    def __call__(self, fraction: float) -> None:
        self._fraction, self._called = fraction, True
        now = time.perf_counter()
        # a terminal draws a full bar at once; the final line of a log is close()'s
        if (self._live and fraction >= 1) or (fraction < 1 and self._due(now, False)):
            self._show(self._line(fraction, now), now, False)

    def _line(self, fraction: float, now: float) -> str:
        n = int(self.width * min(max(fraction, 0.0), 1.0))
        return (f"{self.label} [{'#' * n}{'.' * (self.width - n)}] "
                f"{100 * fraction:5.1f}% {now - self._t0:6.1f} s")

    def close(self) -> None:
        """Print the final state of the bar and end the line (nothing if never called)."""
        if not self._called:
            return
        now = time.perf_counter()
        self._show(self._line(self._fraction, now), now, True)


class ProgressCounter(_Printer):
    """``done/total <unit> (percent), rate, time left``: call it with the number just done.

    On a terminal the line is redrawn (at most every 0.2 s) and ended when all are done; on a
    log a line is written at the first call, then at most every ``log_every`` seconds, and
    when all are done.

    Parameters
    ----------
    label : str
        What the line starts with.
    total : int
        Items in all.
    done : int
        Items already done before this run (resumed work): counted, but not in the rate.
    stream : file-like, optional
        Where to write (default: stderr).
    log_every : float, optional
        Seconds between lines when the stream is not a terminal (> 0; default
        ``config.defaults["progress.log_every"]``).
    unit : str
        What is counted, in the plural (default "flights").
    """

    def __init__(self, label: str, total: int, done: int = 0, stream: TextIO | None = None,
                 log_every: float | None = None, unit: str = "flights") -> None:
        super().__init__(stream, log_every, "ProgressCounter", first_at_once=True)
        self.label, self.total, self.done, self.unit = label, total, done, unit
        self._start_done = done

    def __call__(self, n_new: int) -> None:
        self.done += n_new
        now = time.perf_counter()
        final = self.done >= self.total
        if not self._due(now, final):
            return
        rate = (self.done - self._start_done) / max(now - self._t0, 1e-9)
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        text = (f"{self.label}: {self.done}/{self.total} {self.unit} "
                f"({100 * self.done / max(self.total, 1):.0f} %), {rate:.1f} {self.unit}/s"
                + (f", {left:.0f} s left" if not final and math.isfinite(left) else ""))
        self._show(text + (" " * 8 if self._live else ""), now, final)

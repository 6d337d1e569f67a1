"""A minimal progress bar on stderr for long runs."""
import sys
import time
from typing import TextIO

from quadcog import config
from quadcog.validate import positive

__all__ = ["ProgressBar"]


class ProgressBar:
    """A progress bar: call it with a fraction in [0, 1].

    On a terminal it redraws one line at most every 0.2 s and finishes on close(). On a stream
    that is not a terminal (a log, CI, a pipe) it writes a whole line at most every
    ``log_every`` seconds, so a log of a long run shows how far it got, and the final line on
    close().

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
        self.label, self.stream, self.width = label, stream or sys.stderr, width
        self.log_every = positive(config.get("progress.log_every", log_every),
                                  "ProgressBar: log_every", "s")
        self._last = 0.0
        self._t0 = time.perf_counter()
        self._live = getattr(self.stream, "isatty", lambda: False)()
        self._fraction = 0.0
        self._called = False

    def __call__(self, fraction: float) -> None:
        self._fraction, self._called = fraction, True
        now = time.perf_counter()
        if not self._live:
            # a log gets a whole line now and then; the last one is close()'s
            if fraction < 1 and now - self._t0 >= self.log_every + self._last:
                self._last = now - self._t0
                self.stream.write(self._line(fraction, now) + "\n")
                self.stream.flush()
            return
        if now - self._last < 0.2 and fraction < 1:
            return
        self._last = now
        self.stream.write("\r" + self._line(fraction, now))
        self.stream.flush()

    def _line(self, fraction: float, now: float) -> str:
        n = int(self.width * min(max(fraction, 0.0), 1.0))
        return (f"{self.label} [{'#' * n}{'.' * (self.width - n)}] "
                f"{100 * fraction:5.1f}% {now - self._t0:6.1f} s")

    def close(self) -> None:
        """Print the final state of the bar and end the line (nothing if never called)."""
        if not self._called:
            return
        self._live, self._last = True, 0.0
        self(self._fraction)
        self.stream.write("\n")
        self.stream.flush()

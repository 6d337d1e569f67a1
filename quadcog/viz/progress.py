"""A minimal progress bar on stderr for long runs."""
import sys
import time
from typing import TextIO

__all__ = ["ProgressBar"]


class ProgressBar:
    """A progress bar: call it with a fraction in [0, 1].

    It prints at most every 0.2 s and finishes on close(). On a stream that is not a terminal
    (a log, CI) it prints only the final line.

    Parameters
    ----------
    label : str
        Printed before the bar.
    stream : file-like, optional
        Where to print (default ``sys.stderr``).
    width : int
        Characters of the bar.
    """

    def __init__(self, label: str, stream: TextIO | None = None, width: int = 30) -> None:
        self.label, self.stream, self.width = label, stream or sys.stderr, width
        self._last = 0.0
        self._t0 = time.perf_counter()
        self._live = getattr(self.stream, "isatty", lambda: False)()
        self._fraction = 0.0
        self._called = False

    def __call__(self, fraction: float) -> None:
        self._fraction, self._called = fraction, True
        if not self._live:
            return
        now = time.perf_counter()
        if now - self._last < 0.2 and fraction < 1:
            return
        self._last = now
        n = int(self.width * min(max(fraction, 0.0), 1.0))
        self.stream.write(f"\r{self.label} [{'#' * n}{'.' * (self.width - n)}] "
                          f"{100 * fraction:5.1f}% {now - self._t0:6.1f} s")
        self.stream.flush()

    def close(self) -> None:
        """Print the final state of the bar and end the line (nothing if never called)."""
        if not self._called:
            return
        self._live, self._last = True, 0.0
        self(self._fraction)
        self.stream.write("\n")
        self.stream.flush()

"""SIGINT and SIGTERM as one exception, and worker processes that do not outlive their parent.

``install_handlers`` (called first thing by the `quadcog` command) turns both signals into
``quadcog.errors.Interrupted`` raised in the main thread, so ``finally`` clauses and context
managers (``quadcog.files.RunFiles``, the sweep lock, process pools) clean up on the way out
and ``main`` prints one line and exits 130 or 143. ``die_with_parent`` is the initializer of
quadcog's worker processes: on Linux it asks the kernel for SIGKILL when the parent dies
(``prctl(PR_SET_PDEATHSIG)``), elsewhere a daemon thread polls the parent's pid; either way a
worker does not outlive a killed ``quadcog sweep`` by more than ``WATCHDOG_PERIOD`` seconds.
"""
from collections.abc import Iterator
import contextlib
import ctypes
import ctypes.util
import os
import signal
import sys
import threading

from quadcog.errors import Interrupted

__all__ = ["HANDLED", "WATCHDOG_PERIOD", "install_handlers", "restore_handlers", "die_with_parent",
           "received", "children_without_sigint"]

HANDLED = (signal.SIGINT, signal.SIGTERM)
WATCHDOG_PERIOD = 1.0       # s between two looks at the parent's pid (non-Linux fallback)
_PR_SET_PDEATHSIG = 1       # from <linux/prctl.h>


_RECEIVED: list[int] = []   # the signal that arrived, if one did


def _raise(signum, frame):
    # Once is enough: a second signal during clean-up must not abort the clean-up.
    for s in HANDLED:
        signal.signal(s, signal.SIG_IGN)
    _RECEIVED.append(signum)
    raise Interrupted(signum)


def received() -> Interrupted | None:
    """The interrupt that arrived since ``install_handlers``, if one did.

    A signal that lands inside a call into compiled code (CasADi's SWIG layer) can come out as
    another exception (a ``NotImplementedError`` about the arguments): the command asks here
    before it reports an error, so the user sees the interrupt, not a mangled message.

    Returns
    -------
    quadcog.errors.Interrupted or None
        The interrupt (its ``status`` is 130 or 143), or None.
    """
    return Interrupted(_RECEIVED[0]) if _RECEIVED else None


def install_handlers() -> dict:
    """Make SIGINT and SIGTERM raise ``Interrupted`` in the main thread.

    Returns
    -------
    dict
        {signal: previous handler} for ``restore_handlers``; empty off the main thread
        (Python allows handlers only there).
    """
    if threading.current_thread() is not threading.main_thread():
        return {}
    _RECEIVED.clear()
    return {s: signal.signal(s, _raise) for s in HANDLED}


def restore_handlers(previous: dict) -> None:
    """Put back the handlers ``install_handlers`` replaced.

    Parameters
    ----------
    previous : dict
        What ``install_handlers`` returned.

    Returns
    -------
    None
    """
    for s, handler in previous.items():
        signal.signal(s, handler if handler is not None else signal.SIG_DFL)


def _watchdog(parent):
    import time
    while True:
        time.sleep(WATCHDOG_PERIOD)
        if os.getppid() != parent:
            os._exit(128 + signal.SIGTERM)


def die_with_parent() -> None:
    """Initializer of a worker process: end it when the process that started it dies.

    Also restores the default SIGINT/SIGTERM actions in the worker (Ctrl-C reaches the whole
    process group; the parent alone reports and cleans up, and it ends the pool).

    Returns
    -------
    None
    """
    parent = os.getppid()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
            if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0:
                if os.getppid() != parent:      # the parent died before prctl took effect
                    os._exit(128 + signal.SIGTERM)
                return
        except (OSError, AttributeError):
            pass
    threading.Thread(target=_watchdog, args=(parent,), daemon=True,
                     name="quadcog-parent-watchdog").start()


@contextlib.contextmanager
def children_without_sigint() -> Iterator[None]:
    """Start processes in the block with SIGINT blocked, so that they never see Ctrl-C.

    A terminal's Ctrl-C goes to the whole foreground process group: Dask's nannies and
    workers (started by ``multiprocessing``, which keeps the signal mask across fork and
    exec) would each print a KeyboardInterrupt traceback under the parent's clean line. With
    SIGINT blocked they are ended by the parent only (it closes the cluster on the way out).
    In the parent the signal is held for the block and delivered right after it.

    Yields
    ------
    None
    """
    main = threading.current_thread() is threading.main_thread()
    if not (main and hasattr(signal, "pthread_sigmask")):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)

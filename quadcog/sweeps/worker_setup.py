"""The Dask worker processes' preload (``LocalCluster(preload=...)``): Ctrl-C is the parent's.

A terminal's Ctrl-C reaches the whole foreground process group; a Dask worker would raise
KeyboardInterrupt in its event loop and print a traceback under the sweep's one clean line.
The worker ignores SIGINT instead; the parent, which handles it, closes the cluster and so
ends the workers (``quadcog.sweeps.runner``)."""
import logging
import signal
import threading
from typing import Any

__all__ = ["dask_setup"]


def dask_setup(worker: Any) -> None:
    """Called by Dask in each worker process as it starts: ignore SIGINT there.

    Parameters
    ----------
    worker : distributed.Worker
        The worker starting (unused).
    """
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    # a worker that outlives the scheduler by a heartbeat on the way out logs an error with
    # a traceback: the sweep's outcome comes through its futures, not these lines
    logging.getLogger("distributed").setLevel(logging.CRITICAL)

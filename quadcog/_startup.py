"""Ctrl-C and SIGTERM while the `quadcog` command is still importing: one line, exit 130/143.

Imported first by ``quadcog/__init__.py``. Only when this process is the `quadcog` command
(the console script, or ``python -m quadcog``) does it install handlers, and only until
``quadcog.cli.main`` installs its own (``quadcog.interrupts.install_handlers``): nothing is
written during the imports, so there is nothing to clean up and the process ends at once.
A library user's process is never touched.
"""
import os
import signal
import sys
import threading

__all__ = ["is_command", "install_import_handlers"]


def is_command() -> bool:
    """Whether this process runs the `quadcog` command.

    Returns
    -------
    bool
        True for the ``quadcog`` console script and for ``python -m quadcog``.
    """
    argv = list(getattr(sys, "orig_argv", []) or [])
    if "-m" in argv[:-1] and argv[argv.index("-m") + 1] == "quadcog":
        return True
    return bool(sys.argv) and os.path.basename(sys.argv[0] or "") == "quadcog"


def _exit_now(signum, frame):
    os.write(2, b"quadcog: interrupted\n")
    os._exit(128 + signum)


def install_import_handlers() -> bool:
    """Install the end-at-once handlers when this process is the `quadcog` command.

    Returns
    -------
    bool
        Whether they were installed.
    """
    if not is_command() or threading.current_thread() is not threading.main_thread():
        return False
    for s in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(s) in (signal.default_int_handler, signal.SIG_DFL):
            signal.signal(s, _exit_now)
    return True


install_import_handlers()

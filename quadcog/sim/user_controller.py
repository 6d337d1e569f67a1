"""A user's Python controller, guarded: its calls checked and its failures named.

The protocol, stated with shapes and units in ``quadcog.controllers.template.ControllerProtocol``
(and ``FullControllerProtocol``): ``ctrl(t, x, ref, c)`` returns ``U`` (4,), or
``(U, c_dot)`` when it has a state; optional ``n_state``, ``initial_state()``,
``project_numpy(c)``, ``estimates_cog``, ``name``.
"""
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError, QuadcogError

__all__ = ["user_call", "user_state"]


def _guarded(fn: Callable[..., Any], what: str, when: str, *args: Any) -> Any:
    """``fn(*args)`` of a user's controller; an exception it raises becomes an InputError
    naming ``what`` and ``when`` (the cause kept)."""
    try:
        return fn(*args)
    except QuadcogError:
        raise
    except Exception as e:              # the user's function failed: say when, keep the cause
        hint = (" (a Python controller is called as ctrl(t, x, ref, c))"
                if isinstance(e, TypeError) and "positional argument" in str(e) else "")
        raise InputError(f"{what} raised {type(e).__name__} at {when}: {e}{hint}") from e



def _finite(value: Any, where: str, n: int) -> npt.NDArray[np.float64]:
    """``value`` as n finite numbers, else an InputError naming ``where``."""
    a = validate.vector(value, where, n, finite=False)
    if not np.isfinite(a).all():
        raise InputError(f"{where}: expected {n} finite numbers, got {validate.plain(a.tolist())}")
    return a



def user_call(controller: Callable[..., Any], n_state: int
              ) -> tuple[Callable[..., tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]],
                         Callable[..., npt.NDArray[np.float64]]]:
    """The checked calls of a user's Python controller.

    A typed error names the time when the controller raises or returns anything but finite
    numbers of the right shapes.

    Parameters
    ----------
    controller : callable
        ``ctrl(t, x, ref, c) -> U or (U, c_dot)``, with an optional ``project_numpy(c)``.
    n_state : int
        Its number of states.

    Returns
    -------
    call : callable
        ``call(t, x, ref, c)`` -> (U (4,) [N, N m, N m, N m], c_dot (n_state,)).
    project : callable
        ``project(c, t)``: its ``project_numpy(c)``, or c unchanged without one.

    Raises
    ------
    quadcog.InputError
        (from the calls) The controller raised, or returned non-finite numbers or the wrong
        shapes.
    """
    user_project = getattr(controller, "project_numpy", None)

    def call(t: float, x: npt.NDArray[np.float64], ref: npt.NDArray[np.float64],
             c: npt.NDArray[np.float64]
             ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        when = f"t = {validate.plain(float(t))} s"
        out = _guarded(controller, "controller", when, float(t), x.copy(), ref.copy(), c.copy())
        U, c_dot = out if isinstance(out, tuple) and len(out) == 2 else (out, np.zeros(0))
        return (_finite(U, f"controller output at {when}", 4),
                _finite(c_dot, f"controller output c_dot at {when}", n_state))

    def project(c: npt.NDArray[np.float64], t: float) -> npt.NDArray[np.float64]:
        if user_project is None:
            return c
        when = f"t = {validate.plain(float(t))} s"
        return _finite(_guarded(user_project, "controller.project_numpy", when, c.copy()),
                       f"controller.project_numpy output at {when}", n_state)
    return call, project



def user_state(controller: Any) -> tuple[int, npt.NDArray[np.float64]]:
    """The state size and start of a user's Python controller, checked.

    Parameters
    ----------
    controller : callable
        With optional ``n_state`` and ``initial_state()``.

    Returns
    -------
    n_state : int
        Its ``n_state`` (default 0).
    c0 : (n_state,) numpy.ndarray
        Its ``initial_state()`` (default zeros).

    Raises
    ------
    quadcog.InputError
        A bad ``n_state``, or ``initial_state()`` raised or returned the wrong numbers.
    """
    n = validate.integer(getattr(controller, "n_state", 0), "controller.n_state", lo=0,
                         hi=10_000)
    if not hasattr(controller, "initial_state"):
        return n, np.zeros(n)
    c0 = _guarded(controller.initial_state, "controller.initial_state()", "the start")
    return n, _finite(c0, "controller.initial_state()", n)

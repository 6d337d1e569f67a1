"""A user's Python controller, guarded: its calls checked and its failures named.

The protocol, stated with shapes and units in ``quadcog.controllers.template.ControllerProtocol``
(and ``FullControllerProtocol``): ``ctrl(t, x, ref, c)`` returns ``U`` (4,), or
``(U, c_dot)`` when it has a state; optional ``n_state``, ``initial_state()``,
``project_numpy(c)``, ``estimates_cog``, ``name``.
"""
import numpy as np

from quadcog import validate
from quadcog.errors import InputError, QuadcogError

__all__ = ["user_call", "user_state"]


def _guarded(fn, what, when, *args):
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



def _finite(value, where, n):
    """``value`` as n finite numbers, else an InputError naming ``where``."""
    a = validate.vector(value, where, n, finite=False)
    if not np.isfinite(a).all():
        raise InputError(f"{where}: expected {n} finite numbers, got {validate.plain(a.tolist())}")
    return a



def user_call(controller, n_state):
    """(call, project) for a user's Python controller: ``call(t, x, ref, c)`` returns
    (U (4,), c_dot (n_state,)) and ``project(c, t)`` its optional ``project_numpy(c)``,
    checked: a typed error naming the time when the controller raises or returns anything but
    finite numbers of those shapes."""
    user_project = getattr(controller, "project_numpy", None)

    def call(t, x, ref, c):
        when = f"t = {validate.plain(float(t))} s"
        out = _guarded(controller, "controller", when, float(t), x.copy(), ref.copy(), c.copy())
        U, c_dot = out if isinstance(out, tuple) and len(out) == 2 else (out, np.zeros(0))
        return (_finite(U, f"controller output at {when}", 4),
                _finite(c_dot, f"controller output c_dot at {when}", n_state))

    def project(c, t):
        if user_project is None:
            return c
        when = f"t = {validate.plain(float(t))} s"
        return _finite(_guarded(user_project, "controller.project_numpy", when, c.copy()),
                       f"controller.project_numpy output at {when}", n_state)
    return call, project



def user_state(controller):
    """(n_state, c0) of a user's Python controller: its optional ``n_state`` and
    ``initial_state()`` (default 0 and zeros), checked."""
    n = validate.integer(getattr(controller, "n_state", 0), "controller.n_state", lo=0,
                         hi=10_000)
    if not hasattr(controller, "initial_state"):
        return n, np.zeros(n)
    c0 = _guarded(controller.initial_state, "controller.initial_state()", "the start")
    return n, _finite(c0, "controller.initial_state()", n)

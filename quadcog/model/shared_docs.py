"""The descriptions of the arguments that many generated-function methods share, written once.

``Model``'s methods (``quadcog.model.functions``) take the same state ``x``, input ``U`` and
parameters ``p``; their docstrings hold a line ``%(x)s`` where the description goes, and
``@shared_parameters`` fills it in at import, with the placeholder's indentation (the idea of
SciPy's ``doccer``). A change of the state's description is one edit here. The names and
order of the entries come from the contract (``derive/contract.py``, through
``quadcog.model.conventions``), so they cannot drift from what the functions take.
"""
from collections.abc import Callable
import re
from typing import TypeVar

from quadcog.model.conventions import PARAM_NAMES, STATE_NAMES

__all__ = ["SHARED", "interpolate", "shared_parameters"]

F = TypeVar("F", bound=Callable[..., object])

SHARED = {
    "x": (f"x : ({len(STATE_NAMES)},) array_like\n"
          f"    State [{', '.join(STATE_NAMES)}]:\n"
          "    position of O in ground axes (m), ZYX Euler angles (rad), body-axis velocities\n"
          "    (m/s) and rates (rad/s)."),
    "U": ("U : (4,) array_like\n"
          "    Inputs: thrust along body z (N) and the three body moments about O (N m)."),
    "p": (f"p : ({len(PARAM_NAMES)},) array_like\n"
          f"    Parameters [{', '.join(PARAM_NAMES[:5])}, ..., {', '.join(PARAM_NAMES[-3:])}]\n"
          "    (SI units), admissible (else ParameterError)."),
}
_PLACEHOLDER = re.compile(r"^(?P<indent>[ \t]*)%\((?P<name>\w+)\)s[ \t]*$", re.M)


def interpolate(doc: str) -> str:
    """``doc`` with every line ``%(name)s`` replaced by ``SHARED[name]``, indented as it.

    Parameters
    ----------
    doc : str
        A docstring.

    Returns
    -------
    str
        The docstring filled in.
    """
    def fill(m: re.Match[str]) -> str:
        return "\n".join(m.group("indent") + line for line in SHARED[m.group("name")]
                         .splitlines())
    return _PLACEHOLDER.sub(fill, doc)


def shared_parameters(fn: F) -> F:
    """Decorator: fill the shared descriptions into ``fn``'s docstring.

    Parameters
    ----------
    fn : callable
        A function whose docstring holds ``%(x)s``, ``%(U)s`` or ``%(p)s`` lines.

    Returns
    -------
    callable
        ``fn``, its ``__doc__`` filled in.
    """
    if fn.__doc__:
        fn.__doc__ = interpolate(fn.__doc__)
    return fn

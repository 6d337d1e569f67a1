"""Linear models as python-control objects, for users to continue in python-control.

``hover_statespace`` is the generated model's Jacobian linearization at a level hover (with
the CoG wherever the vehicle has it, held by the trim input of docs/model.md sec. 3.3);
``loop_statespace`` is a state-feedback loop broken at the plant input,
L(s) = K (s I - A)^{-1} B, whose margins and singular values ``pd_design`` reports.
"""
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from quadcog.model.conventions import INPUT_NAMES, N_STATE, STATE_NAMES, hover_trim
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["hover_statespace", "loop_statespace"]


def hover_statespace(vehicle: Vehicle | None = None,
                     position: Sequence[float] = (0.0, 0.0, 1.0), yaw: float = 0.0,
                     outputs: Sequence[str] | None = None) -> Any:
    """The hover linearization as a ``control.StateSpace``.

    Parameters
    ----------
    vehicle : quadcog.Vehicle, optional
        Default ``quadcog.HUMMINGBIRD``; its ``x_G, y_G, z_G`` place the CoG (the trim input
        then holds the moment ``[m g y_G, -m g x_G]``).
    position : (3,) sequence of float
        Where it hovers [m] (the linearization does not depend on it; it names the point).
    yaw : float
        Heading of the hover [rad].
    outputs : sequence of state names, optional
        The rows of C, e.g. ``("x", "y", "z", "psi")``; default all 12 states (C = I).

    Returns
    -------
    control.StateSpace
        12 states ``x, y, z, phi, theta, psi, u, v, w, p, q, r`` (m, rad, m/s, rad/s), 4 inputs
        ``U1`` (N), ``U2..U4`` (N m), D = 0; deviations from the hover state and trim input.
        Signal names carry no units (python-control's names); ``quadcog.model.columns``
        lists them. (python-control ships no type stubs: typed as Any.)

    Raises
    ------
    quadcog.errors.InputError
        For an unknown state name in ``outputs``.
    """
    import control

    from quadcog.model.functions import load
    from quadcog.vehicles.vehicle import HUMMINGBIRD
    vehicle = vehicle or HUMMINGBIRD
    p = vehicle.parameters()
    x0 = np.zeros(N_STATE)
    x0[:3], x0[5] = position, yaw
    A, B = load().linearization(x0, hover_trim(p), p)
    names = list(outputs) if outputs is not None else list(STATE_NAMES)
    unknown = [n for n in names if n not in STATE_NAMES]
    if unknown:
        from quadcog.errors import InputError
        raise InputError(f"outputs: unknown state name(s) {unknown}; expected names from "
                         f"{STATE_NAMES}")
    C = np.eye(12)[[STATE_NAMES.index(n) for n in names]]
    return control.ss(A, B, C, np.zeros((len(names), 4)), states=list(STATE_NAMES),
                      inputs=list(INPUT_NAMES), outputs=names,
                      name=f"{vehicle.name or 'vehicle'} hover")


def loop_statespace(A: ArrayLike, B: ArrayLike, K: ArrayLike) -> Any:
    """L(s) = K (s I - A)^{-1} B as a ``control.StateSpace``.

    The plant x_dot = A x + B u closed by u = -K x, broken at the plant input.

    Parameters
    ----------
    A : (n, n) array_like
        State matrix [1/s].
    B : (n, m) array_like
        Input matrix.
    K : (m, n) array_like
        State feedback gain.

    Returns
    -------
    control.StateSpace
        The loop: m inputs in, m signals out (typed as Any: no stubs).
    """
    import control
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))
    return control.ss(A, B, K, np.zeros((K.shape[0], B.shape[1])))



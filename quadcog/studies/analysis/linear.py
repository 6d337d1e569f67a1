"""Linear models as python-control objects, for users to continue in python-control.

``hover_statespace`` is the generated model's Jacobian linearization at a level hover (with
the CoG wherever the vehicle has it, held by the trim input of docs/model.md sec. 3.3);
``loop_statespace`` is a state-feedback loop broken at the plant input,
L(s) = K (s I - A)^{-1} B, whose margins and singular values ``pd_design`` reports.
"""
import numpy as np

from quadcog.model.conventions import INPUT_NAMES, N_STATE, STATE_NAMES, hover_trim


def hover_statespace(vehicle=None, position=(0.0, 0.0, 1.0), yaw=0.0, outputs=None):
    """The hover linearization as a ``control.StateSpace``.

    Parameters
    ----------
    vehicle : quadcog.Vehicle, optional
        Default ``quadcog.HUMMINGBIRD``; its ``x_G, y_G, z_G`` place the CoG (the trim input
        then holds the moment ``[m g y_G, -m g x_G]``).
    position : 3 numbers (m)
        Where it hovers (the linearization does not depend on it; it names the point).
    yaw : float (rad)
        Heading of the hover.
    outputs : sequence of state names, optional
        The rows of C, e.g. ``("x", "y", "z", "psi")``; default all 12 states (C = I).

    Returns
    -------
    control.StateSpace
        12 states ``x, y, z, phi, theta, psi, u, v, w, p, q, r`` (m, rad, m/s, rad/s), 4 inputs
        ``U1`` (N), ``U2..U4`` (N m), D = 0; deviations from the hover state and trim input.
        Signal names carry no units (python-control's names); ``quadcog.model.columns`` lists them.
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


def loop_statespace(A, B, K):
    """L(s) = K (s I - A)^{-1} B as a ``control.StateSpace``: the plant x_dot = A x + B u
    closed by u = -K x, broken at the plant input (m inputs in, m signals out)."""
    import control
    A, B, K = (np.asarray(a, dtype=float) for a in (A, B, K))
    return control.ss(A, B, K, np.zeros((K.shape[0], B.shape[1])))



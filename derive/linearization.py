"""Jacobian linearization A = df/dx, B = df/dU of x_dot = f(x) + g(x) U."""
from derive.symbols import U, state


def linearization(xdot):
    """Return (A, B): 12x12 and 12x4 Jacobians of the 12-state vector field."""
    return xdot.jacobian(state), xdot.jacobian(U)

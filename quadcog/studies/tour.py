"""`quadcog tour`: the generated functions evaluated at hover, as a first look."""
from collections.abc import Callable

import numpy as np

from quadcog.model.conventions import N_STATE, R_G, hover_trim
from quadcog.model.functions import load
from quadcog.vehicles.vehicle import default_parameters

__all__ = ["tour"]


def tour(print_: Callable[[str], object] = print) -> None:
    """Print every generated function evaluated at hover of the default vehicle with a CoG
    offset r_G = [3, -2, 0] cm.

    Parameters
    ----------
    print_ : callable
        Called with each text to show (default: ``print``).
    """
    model = load()
    p = default_parameters(x_G=0.03, y_G=-0.02)
    x = np.zeros(N_STATE)
    U = hover_trim(p)
    fmt = {"float_kind": lambda v: f"{v: .4g}"}

    def show(title, value):
        text = np.array2string(np.asarray(value), formatter=fmt, max_line_width=100)
        print_(f"\n{title}\n{text}")

    print_(f"quadcog tour: backend {model.backend!r}; default vehicle (AscTec Hummingbird) with "
           f"r_G = {p[R_G].tolist()} m, level hover")
    show("hover trim U = [m g, m g y_G, -m g x_G, 0] (N, N m):", U)
    show("dynamics(x, U, p): x_dot at the trim (zero):", model.dynamics(x, U, p))
    show("mass_matrix(p): M", model.mass_matrix(p))
    show("gravity(x, p): g_G", model.gravity(x, p))
    show("decoupling(x, p): alpha = L_g L_f h (thrust enters the attitude rows when r_G != 0)",
         model.decoupling(x, p))
    show("drift(x, p): b = L_f^2 h", model.drift(x, p))
    show("regressor(x, vartheta = 0, p): Phi", model.regressor(x, np.zeros(6), p))
    A, B = model.linearization(x, U, p)
    show("eigenvalues of the hover linearization A", np.sort_complex(np.linalg.eigvals(A)))
    print_("\nNext: `make test` runs the verification; the docs site (make docs) has the rest.")

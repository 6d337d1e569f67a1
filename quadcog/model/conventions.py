"""The public contract (docs/model.md sec. 1) as the runtime sees it, and the model facts
that several modules use, each defined once and imported wherever it is needed.

The names and orders of the vectors and the signatures of the generated functions are defined
in derive/contract.py; ``make derive`` writes them into generated/manifest.json, and they are
read from there (the copy that ships with the package) when quadcog is imported.
"""
import numpy as np
import numpy.typing as npt

from quadcog.errors import ParameterError
from quadcog.model.generated_files import imported_contract
from quadcog.validate import array, fail, real

__all__ = ["CONTRACT", "STATE_NAMES", "INPUT_NAMES", "PARAM_NAMES", "OUTPUT_NAMES", "FUNCTIONS",
           "N_STATE", "N_INPUT", "N_PARAM", "ETA", "NU", "IDX", "R_G", "OUTPUT_ROWS", "B_U",
           "SMALLEST", "LARGEST", "rotation_matrix", "hover_trim"]

# The scale of every parameter in SI units: m, g, Ixx, Iyy, Izz in [SMALLEST, LARGEST], drag
# coefficients in [0, LARGEST]. Far wider than any vehicle (a Crazyflie's Ixx is 1.4e-5 kg m^2),
# and narrow enough that the model's products and inverses (1 / Izz, c v, m g r_G) stay finite.
# (quadcog.model.parameters, which checks them, exports them too.)
SMALLEST, LARGEST = 1e-9, 1e6

CONTRACT = imported_contract()
STATE_NAMES = CONTRACT.vectors["x"]
INPUT_NAMES = CONTRACT.vectors["U"]
PARAM_NAMES = CONTRACT.vectors["p"]
OUTPUT_NAMES = CONTRACT.outputs
# name -> (inputs ((argument, length), ...), outputs ((name, shape), ...)): the generated
# functions of generated_dir(); a Model of another folder reads that folder's.
FUNCTIONS = CONTRACT.functions

N_STATE, N_INPUT, N_PARAM = len(STATE_NAMES), len(INPUT_NAMES), len(PARAM_NAMES)
# x = [eta; nu]: the pose (position, Euler angles) and the body velocities (linear, angular)
ETA = slice(0, STATE_NAMES.index("u"))
NU = slice(STATE_NAMES.index("u"), N_STATE)

# Index helpers, so code says which entry it means.
IDX = {name: i for i, name in enumerate(PARAM_NAMES)}
R_G = slice(IDX["x_G"], IDX["z_G"] + 1)
# Rows of the state that are the feedback-linearization outputs y = [z, phi, theta, psi].
OUTPUT_ROWS = tuple(STATE_NAMES.index(name) for name in OUTPUT_NAMES)


def _read_only(a: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    a.setflags(write=False)
    return a


# tau = B_u U: thrust along body z and the three body moments (docs/model.md sec. 1.3, 2.2).
B_U = _read_only(np.vstack([np.zeros((2, 4)), np.eye(4)]))


def rotation_matrix(phi: float, theta: float, psi: float) -> npt.NDArray[np.float64]:
    """R = Rz(psi) Ry(theta) Rx(phi): body to ground axes, ZYX Euler angles.

    Parameters
    ----------
    phi : float
        Roll (rad).
    theta : float
        Pitch (rad).
    psi : float
        Yaw (rad).

    Returns
    -------
    (3, 3) numpy.ndarray
        R, rotating body-axis components into ground axes.

    Raises
    ------
    InputError
        An angle that is not a finite real number (NaN gave a matrix of NaN).
    """
    phi, theta, psi = (real(a, name, unit="rad")
                       for a, name in ((phi, "phi"), (theta, "theta"), (psi, "psi")))
    c, s = np.cos, np.sin
    return (np.array([[c(psi), -s(psi), 0.0], [s(psi), c(psi), 0.0], [0.0, 0.0, 1.0]])
            @ np.array([[c(theta), 0.0, s(theta)], [0.0, 1.0, 0.0], [-s(theta), 0.0, c(theta)]])
            @ np.array([[1.0, 0.0, 0.0], [0.0, c(phi), -s(phi)], [0.0, s(phi), c(phi)]]))


def hover_trim(p: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """The input that holds a level hover at rest with the CoG at r_G (docs/model.md sec. 3.3).

    Parameters
    ----------
    p : (14,) or (B, 14) array_like
        Parameter vector (SI units, order ``PARAM_NAMES``), or one per flight.

    Returns
    -------
    (4,) or (B, 4) numpy.ndarray
        U* = [m g, m g y_G, -m g x_G, 0] (N, N m, N m, N m).

    Raises
    ------
    ParameterError
        ``p`` is not one or a stack of parameter vectors of finite numbers with m and g in
        [SMALLEST, LARGEST] and the CoG offset within LARGEST (NaN gave NaN, 1e200 overflowed).
    """
    p = array(p, "p", error=ParameterError)
    if p.ndim not in (1, 2) or p.shape[-1] != N_PARAM:
        fail("p", f"an array of shape ({N_PARAM},) or (B, {N_PARAM})",
             f"an array of shape {p.shape}", ParameterError)
    for k, lo in (("m", SMALLEST), ("g", SMALLEST), ("x_G", -LARGEST), ("y_G", -LARGEST)):
        column = p[..., IDX[k]]
        bad = np.flatnonzero((column < lo) | (column > LARGEST))
        if bad.size:
            fail(f"p[{IDX[k]}] ({k})" if p.ndim == 1 else f"p[{bad[0]}, {IDX[k]}] ({k})",
                 f"a number in [{lo:g}, {LARGEST:g}] (SI units, docs/model.md sec. 1.4)",
                 column.flat[bad[0]], ParameterError)
    mg = p[..., IDX["m"]] * p[..., IDX["g"]]
    return np.stack([mg, mg * p[..., IDX["y_G"]], -mg * p[..., IDX["x_G"]], np.zeros_like(mg)],
                    axis=-1)

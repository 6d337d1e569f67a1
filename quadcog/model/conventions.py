"""The public contract (docs/model.md sec. 1) as the runtime sees it, and the model facts
that several modules use, each defined once and imported wherever it is needed.

The names and orders of the vectors and the signatures of the generated functions are defined
in derive/contract.py; ``make derive`` writes them into generated/manifest.json, and they are
read from there (the copy that ships with the package) when quadcog is imported.
"""
import numpy as np
import numpy.typing as npt

from quadcog.model.generated_files import imported_contract

__all__ = ["CONTRACT", "STATE_NAMES", "INPUT_NAMES", "PARAM_NAMES", "OUTPUT_NAMES", "FUNCTIONS",
           "N_STATE", "N_INPUT", "N_PARAM", "ETA", "NU", "IDX", "R_G", "OUTPUT_ROWS", "B_U",
           "rotation_matrix", "hover_trim"]

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
    """
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
    """
    p = np.asarray(p, dtype=float)
    mg = p[..., IDX["m"]] * p[..., IDX["g"]]
    return np.stack([mg, mg * p[..., IDX["y_G"]], -mg * p[..., IDX["x_G"]], np.zeros_like(mg)],
                    axis=-1)

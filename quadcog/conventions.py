"""Names, orders and model facts of the public contract (docs/model.md sec. 1), each defined
once here and imported wherever it is needed; numpy only."""
import numpy as np

STATE_NAMES = ("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r")
INPUT_NAMES = ("U1", "U2", "U3", "U4")
PARAM_NAMES = ("m", "g", "Ixx", "Iyy", "Izz", "c_x", "c_y", "c_z",
               "c_phi", "c_theta", "c_psi", "x_G", "y_G", "z_G")
OUTPUT_NAMES = ("z", "phi", "theta", "psi")

N_STATE, N_INPUT, N_PARAM = len(STATE_NAMES), len(INPUT_NAMES), len(PARAM_NAMES)

# Index helpers, so code says which entry it means.
IDX = {name: i for i, name in enumerate(PARAM_NAMES)}
R_G = slice(IDX["x_G"], IDX["z_G"] + 1)
# Rows of the state that are the feedback-linearization outputs y = [z, phi, theta, psi].
OUTPUT_ROWS = tuple(STATE_NAMES.index(name) for name in OUTPUT_NAMES)


def _read_only(a):
    a.setflags(write=False)
    return a


# tau = B_u U: thrust along body z and the three body moments (docs/model.md sec. 1.3, 2.2).
B_U = _read_only(np.vstack([np.zeros((2, 4)), np.eye(4)]))


def rotation_matrix(phi, theta, psi):
    """R = Rz(psi) Ry(theta) Rx(phi) (3, 3): body to ground axes, ZYX Euler angles in rad."""
    c, s = np.cos, np.sin
    return (np.array([[c(psi), -s(psi), 0.0], [s(psi), c(psi), 0.0], [0.0, 0.0, 1.0]])
            @ np.array([[c(theta), 0.0, s(theta)], [0.0, 1.0, 0.0], [-s(theta), 0.0, c(theta)]])
            @ np.array([[1.0, 0.0, 0.0], [0.0, c(phi), -s(phi)], [0.0, s(phi), c(phi)]]))


def hover_trim(p):
    """U* (4,) = [m g, m g y_G, -m g x_G, 0]: the input that holds a level hover at rest with
    the CoG at r_G of the parameter vector ``p`` (14,) (docs/model.md sec. 3.3)."""
    p = np.asarray(p, dtype=float)
    mg = p[IDX["m"]] * p[IDX["g"]]
    return np.array([mg, mg * p[IDX["y_G"]], -mg * p[IDX["x_G"]], 0.0])


# name -> (inputs with their lengths, outputs with their shapes): the generated functions.
FUNCTIONS = {
    "dynamics": ((("x", 12), ("U", 4), ("p", 14)), (("xdot", (12,)),)),
    "mass_matrix": ((("p", 14),), (("M", (6, 6)),)),
    "inverse_mass_matrix": ((("p", 14),), (("M_inv", (6, 6)),)),
    "coriolis": ((("x", 12), ("p", 14)), (("C", (6, 6)),)),
    "damping": ((("p", 14),), (("D", (6, 6)),)),
    "gravity": ((("x", 12), ("p", 14)), (("g_G", (6,)),)),
    "regressor": ((("x", 12), ("vartheta", 6), ("p", 14)), (("Phi", (6, 3)),)),
    "decoupling": ((("x", 12), ("p", 14)), (("alpha", (4, 4)),)),
    "drift": ((("x", 12), ("p", 14)), (("b", (4,)),)),
    "linearization": ((("x", 12), ("U", 4), ("p", 14)), (("A", (12, 12)), ("B", (12, 4)))),
    "truth_dynamics": ((("x", 12), ("U", 4), ("p", 14), ("I_products", 3), ("wrench", 6)),
                       (("xdot", (12,)),)),
}

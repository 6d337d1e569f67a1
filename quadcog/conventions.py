"""Names and orders of the public contract (MODEL.md); no dependencies, shared with derive/."""

STATE_NAMES = ("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r")
INPUT_NAMES = ("U1", "U2", "U3", "U4")
PARAM_NAMES = ("m", "g", "Ixx", "Iyy", "Izz", "c_x", "c_y", "c_z",
               "c_phi", "c_theta", "c_psi", "x_G", "y_G", "z_G")
OUTPUT_NAMES = ("z", "phi", "theta", "psi")

N_STATE, N_INPUT, N_PARAM = len(STATE_NAMES), len(INPUT_NAMES), len(PARAM_NAMES)

# Index helpers, so code says which entry it means.
IDX = {name: i for i, name in enumerate(PARAM_NAMES)}
R_G = slice(IDX["x_G"], IDX["z_G"] + 1)

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

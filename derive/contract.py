"""The public contract of the generated functions, defined here once (docs/model.md sec. 1):
the vectors (the names of their entries, in order, and their symbols) and, per function, its
arguments and outputs. ``export.py`` builds the functions from it, ``manifest.py`` writes it
into generated/manifest.json (with the output shapes), and the runtime reads it from there
(``quadcog.model.conventions``); nothing else spells it out."""
from dataclasses import dataclass

import sympy as sp

from derive import symbols as sym

# argument name -> (entry names, SymPy symbols), in order.
VECTORS = {
    "x": (("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r"), sym.state),
    "U": (("U1", "U2", "U3", "U4"), sym.U),
    "p": (("m", "g", "Ixx", "Iyy", "Izz", "c_x", "c_y", "c_z",
           "c_phi", "c_theta", "c_psi", "x_G", "y_G", "z_G"), sym.params),
    "vartheta": (tuple(f"vartheta{k}" for k in range(1, 7)), sym.vartheta),
    "I_products": (("Ixy", "Ixz", "Iyz"), sym.I_products),
    "wrench": (("F_x", "F_y", "F_z", "M_x", "M_y", "M_z"), sym.wrench),
    # The model in the ten inertial parameters (docs/model.md sec. 7): pi about O, and what
    # p holds besides (gravity, drag), so that m, r_G and I_O are given once, by pi.
    "nu_dot": (("udot", "vdot", "wdot", "pdot", "qdot", "rdot"), sym.NU_DOT),
    "pi": (("m", "mx_G", "my_G", "mz_G", "Ixx", "Ixy", "Iyy", "Ixz", "Iyz", "Izz"),
           sym.inertial),
    "g": (("g",), sp.Matrix([sym.g])),
    "c": (("c_x", "c_y", "c_z", "c_phi", "c_theta", "c_psi"), sym.drag),
    # The model on SE(3) (docs/model.md sec. 8): the state with a unit quaternion (scalar
    # first) for the Euler angles, a rotation matrix row by row, the body velocities alone.
    "xq": (("x", "y", "z", "q_w", "q_x", "q_y", "q_z", "u", "v", "w", "p", "q", "r"),
           sym.state_se3),
    "R": (("R11", "R12", "R13", "R21", "R22", "R23", "R31", "R32", "R33"), sym.R_entries),
    "nu": (("u", "v", "w", "p", "q", "r"), sym.nu),
    "quaternion": (("q_w", "q_x", "q_y", "q_z"), sym.quaternion),
}
# The outputs y = h(x) of the feedback linearization: state entries, by name.
OUTPUT_NAMES = ("z", "phi", "theta", "psi")
for _name, (_entries, _symbols) in VECTORS.items():
    assert len(_entries) == len(_symbols), _name


def output_symbols():
    """h(x) as the state's symbols, in the order of OUTPUT_NAMES."""
    names = VECTORS["x"][0]
    return [VECTORS["x"][1][names.index(n)] for n in OUTPUT_NAMES]


@dataclass(frozen=True)
class FunctionSpec:
    """One generated function: its arguments (names of VECTORS), its outputs (name and the
    attribute of the derived model that gives the expression), what it is."""
    name: str
    inputs: tuple
    outputs: tuple       # (output name, callable DerivedModel -> sympy Matrix)
    doc: str
    placeholders: object = lambda d: d.I_G_inv     # which I_G^{-1} definition applies


FUNCTIONS = (
    FunctionSpec("dynamics", ("x", "U", "p"), (("xdot", lambda d: d.xdot),),
                 "x_dot = f(x) + g(x) U, the 12-state vector field"),
    FunctionSpec("mass_matrix", ("p",), (("M", lambda d: d.body.M),),
                 "M, the 6x6 mass and inertia matrix about O"),
    FunctionSpec("inverse_mass_matrix", ("p",), (("M_inv", lambda d: d.M_inv),),
                 "M^{-1} by block elimination (Schur complement I_G)"),
    FunctionSpec("coriolis", ("x", "p"), (("C", lambda d: d.body.C),),
                 "C(nu), the skew-symmetric Coriolis-centripetal matrix"),
    FunctionSpec("damping", ("p",), (("D", lambda d: d.body.D),),
                 "D = diag(c), linear air friction"),
    FunctionSpec("gravity", ("x", "p"), (("g_G", lambda d: d.body.g_G),),
                 "g_G(eta) = -[f_G; r_G x f_G]"),
    FunctionSpec("regressor", ("x", "vartheta", "p"), (("Phi", lambda d: d.Phi),),
                 "Phi = d/dr_G [M vartheta + C nu + g_G], 6x3"),
    FunctionSpec("decoupling", ("x", "p"), (("alpha", lambda d: d.outputs.alpha),),
                 "alpha = L_g L_f h for y = [z, phi, theta, psi], 4x4"),
    FunctionSpec("drift", ("x", "p"), (("b", lambda d: d.outputs.b),),
                 "b = L_f^2 h, 4"),
    FunctionSpec("linearization", ("x", "U", "p"), (("A", lambda d: d.A), ("B", lambda d: d.B)),
                 "A = d x_dot / dx (12x12), B = d x_dot / dU (12x4)"),
    FunctionSpec("truth_dynamics", ("x", "U", "p", "I_products", "wrench"),
                 (("xdot", lambda d: d.xdot_general),),
                 "x_dot with I_O = [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]] and an "
                 "external wrench (truth model: parallel-axis I_O, disturbances)",
                 lambda d: d.I_G_inv_general),
    FunctionSpec("inertial_regressor", ("x", "nu_dot", "g"), (("Y", lambda d: d.inertial.Y),),
                 "Y = d/dpi [M nu_dot + C nu + g_G], 6x10: Y pi = M nu_dot + C nu + g_G for "
                 "pi = [m, m r_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] about O",
                 lambda d: {}),
    FunctionSpec("inertial_mass_matrix", ("pi",), (("M", lambda d: d.inertial.body.M),),
                 "M of the rigid body with inertial parameters pi, 6x6",
                 lambda d: {}),
    FunctionSpec("inertial_dynamics", ("x", "U", "pi", "g", "c"),
                 (("xdot", lambda d: d.inertial.xdot),),
                 "x_dot of the rigid body with inertial parameters pi about O, gravity g and "
                 "drag c; equals dynamics(x, U, p) at pi = [m, m r_G, Ixx, 0, Iyy, 0, 0, Izz]",
                 lambda d: d.inertial.I_G_inv),
    FunctionSpec("se3_dynamics", ("xq", "U", "pi", "g", "c", "wrench"),
                 (("xq_dot", lambda d: d.se3.xdot),),
                 "x_dot on SE(3) of the rigid body with inertial parameters pi about O: "
                 "[R(q) nu1; q (0, nu2) / 2; nu_dot], q a unit quaternion, with drag c and an "
                 "external wrench [force at O in ground axes; moment in body axes]",
                 lambda d: d.se3.I_G_inv),
    FunctionSpec("se3_regressor", ("R", "nu", "nu_dot", "g"), (("Y", lambda d: d.se3.Y),),
                 "Y = d/dpi [M nu_dot + C nu + g_G] with the attitude as a rotation matrix R "
                 "(body to ground, row by row), 6x10; at R = R(eta) it is inertial_regressor",
                 lambda d: {}),
    FunctionSpec("quaternion_rotation", ("quaternion",), (("R", lambda d: d.se3.R_q),),
                 "R(q), body to ground, of the quaternion q = [q_w, q_x, q_y, q_z] (Hamilton, "
                 "R(q) v = q v q^*), 3x3",
                 lambda d: {}),
)


def describe(functions):
    """The contract as plain data for the manifest, with each output's shape read from the
    built CasADi Functions ``functions`` ({name: casadi.Function}): a column is (n,)."""
    def shape(fn, k):
        rows, cols = fn.size_out(k)
        return [rows] if cols == 1 else [rows, cols]

    return {
        "vectors": {name: list(entries) for name, (entries, _) in VECTORS.items()},
        "outputs": list(OUTPUT_NAMES),
        "functions": {
            spec.name: {
                "inputs": [[a, len(VECTORS[a][0])] for a in spec.inputs],
                "outputs": [[o, shape(functions[spec.name], k)]
                            for k, (o, _) in enumerate(spec.outputs)],
                "doc": spec.doc,
            } for spec in FUNCTIONS},
    }

"""The symbols of the model, in the order of the public contract (docs/model.md sec. 1.2)."""
import sympy as sp

# State x = [eta1, eta2, nu1, nu2].
x, y, z = sp.symbols("x y z", real=True)
phi, theta, psi = sp.symbols("phi theta psi", real=True)
u, v, w = sp.symbols("u v w", real=True)
p, q, r = sp.symbols("p q r", real=True)
eta1 = sp.Matrix([x, y, z])
eta2 = sp.Matrix([phi, theta, psi])
nu1 = sp.Matrix([u, v, w])
nu2 = sp.Matrix([p, q, r])
eta = sp.Matrix.vstack(eta1, eta2)
nu = sp.Matrix.vstack(nu1, nu2)
state = sp.Matrix.vstack(eta, nu)

# Input U = [U1 (thrust, N), U2, U3, U4 (body moments about O, N m)].
U = sp.Matrix(sp.symbols("U1:5", real=True))

# Parameters p (14 entries, this order).
m, g = sp.symbols("m g", positive=True)
Ixx, Iyy, Izz = sp.symbols("I_xx I_yy I_zz", positive=True)
c_x, c_y, c_z, c_phi, c_theta, c_psi = sp.symbols(
    "c_x c_y c_z c_phi c_theta c_psi", nonnegative=True)
x_G, y_G, z_G = sp.symbols("x_G y_G z_G", real=True)
r_G = sp.Matrix([x_G, y_G, z_G])
params = sp.Matrix([m, g, Ixx, Iyy, Izz, c_x, c_y, c_z, c_phi, c_theta, c_psi, x_G, y_G, z_G])

# Products of inertia about O, for the truth model whose I_O changes with r_G (docs/model.md
# sec. 5); the controller's model keeps I_O diagonal.
Ixy, Ixz, Iyz = sp.symbols("I_xy I_xz I_yz", real=True)
I_products = sp.Matrix([Ixy, Ixz, Iyz])
# The full symmetric inertia about O (entries of the matrix, not negated products).
I_O_full = sp.Matrix([[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]])

# The ten inertial parameters of the rigid body about O (docs/model.md sec. 7), in the order
# of Pinocchio's Inertia.toDynamicParameters: pi = [m, h, Ixx, Ixy, Iyy, Ixz, Iyz, Izz] with
# the first moment of mass h = m r_G; m and the inertia entries are the symbols above.
h_x, h_y, h_z = sp.symbols("h_x h_y h_z", real=True)
h = sp.Matrix([h_x, h_y, h_z])
inertial = sp.Matrix([m, h_x, h_y, h_z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz])
drag = sp.Matrix([c_x, c_y, c_z, c_phi, c_theta, c_psi])

# External wrench for the truth model: force at O in ground axes (N), moment in body axes (N m).
wrench = sp.Matrix(sp.symbols("F_x F_y F_z M_x M_y M_z", real=True))

# Commanded generalized acceleration (argument of the regressor).
vartheta = sp.Matrix(sp.symbols("vartheta1:7", real=True))

# The generalized acceleration nu_dot (argument of the inertial regressor, and the unknowns
# of the Newton-Euler equations).
NU_DOT = sp.Matrix(sp.symbols("udot vdot wdot pdot qdot rdot", real=True))

# Placeholders for the inverse of the inertia about the CoG, I_G^{-1} (symmetric).
# They depend on parameters only, so derivatives with respect to the state never
# have to expand a symbolic 3x3 inverse; the exporter substitutes their definition.
_Gi = {}
for i in range(3):
    for j in range(i, 3):
        _Gi[(i, j)] = _Gi[(j, i)] = sp.Symbol(f"Gamma_{i + 1}{j + 1}", real=True)
I_G_inv = sp.Matrix(3, 3, lambda i, j: _Gi[(i, j)])
I_G_INV_SYMBOLS = tuple(_Gi[(i, j)] for i in range(3) for j in range(i, 3))


def skew(a):
    """S(a) with S(a) b = a x b."""
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])

# The attitude on SE(3) (docs/model.md sec. 8): a unit quaternion q = [q_w, q_x, q_y, q_z]
# (Hamilton, scalar first, body to ground: R(q) v = q v q^*) and the nine entries of a rotation
# matrix R (body to ground), row by row. The state on SE(3) is [eta1; q; nu1; nu2] (13).
q_w, q_x, q_y, q_z = sp.symbols("q_w q_x q_y q_z", real=True)
quaternion = sp.Matrix([q_w, q_x, q_y, q_z])
R_entries = sp.Matrix(sp.symbols("R_11 R_12 R_13 R_21 R_22 R_23 R_31 R_32 R_33", real=True))
R_matrix = sp.Matrix(3, 3, list(R_entries))
state_se3 = sp.Matrix.vstack(eta1, quaternion, nu)

"""The identities of the generated functions, defined once: each is evaluated with the
runtime (``quadcog.load()``, the compiled C when there is a compiler) at random admissible
points (``quadcog.model.sampling``). ``tests/test_identities.py`` asserts every bound, and
``python -m report.verify`` writes the same results as the report's verification table.

Each check's oracle is independent of the function it checks: a definition written out in
numpy (M, D, Euler's axioms, the hover trim), CasADi's automatic differentiation of the
exported dynamics (alpha, b, A, B), or another backend (C against CasADi's VM).
"""
from dataclasses import dataclass

import casadi as ca
import numpy as np

import quadcog
from quadcog.model.attitude import quaternion_of_euler
from quadcog.model.conventions import B_U, FUNCTIONS, IDX, OUTPUT_ROWS, hover_trim, rotation_matrix
from quadcog.model.inertial_parameters import box, inertial_arguments
from quadcog.model.sampling import random_points

SEED = 20110828


def relative_error(actual, expected):
    """max |actual - expected| / max(1, max |expected|), as tests/conftest.py assert_close."""
    actual, expected = np.asarray(actual, float), np.asarray(expected, float)
    scale = max(1.0, float(np.max(np.abs(expected))))
    return float(np.max(np.abs(actual.reshape(expected.shape) - expected))) / scale


def skew(a):
    return np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def euler_rate_map(phi, theta):
    c, s, t = np.cos, np.sin, np.tan
    return np.array([[1, s(phi) * t(theta), c(phi) * t(theta)], [0, c(phi), -s(phi)],
                     [0, s(phi) / c(theta), c(phi) / c(theta)]])


# --- the identities -----------------------------------------------------------------------------

@dataclass
class Check:
    group: str
    tex: str              # the identity, LaTeX (text mode)
    bound: float          # largest admissible error; for kind "min", the value must exceed it
    errors: object        # callable(context, point) -> error (or value, for kind "min")
    kind: str = "max"


class Context:
    """The runtime model and the CasADi functions the checks need, built once."""

    def __init__(self, model):
        self.model = model
        f = model.casadi_function("dynamics")
        x, U, p = ca.SX.sym("x", 12), ca.SX.sym("U", 4), ca.SX.sym("p", 14)
        xdot = f(x, U, p)
        y_dot = xdot[list(OUTPUT_ROWS)]
        y_ddot = ca.jtimes(y_dot, x, xdot)
        self.outputs = ca.Function("outputs", [x, U, p], [ca.jacobian(y_dot, U), y_ddot,
                                                          ca.jacobian(y_ddot, U)])
        self.jacobians = ca.Function("jacobians", [x, U, p],
                                     [ca.jacobian(xdot, x), ca.jacobian(xdot, U)])
        self.vm = {name: model.casadi_function(name) for name in FUNCTIONS}


def _lhs(model, x, v, p):
    return model.mass_matrix(p) @ v + model.coriolis(x, p) @ x[6:] + model.gravity(x, p)


def _mass_matrix_definition(c, pt):
    x, U, p, _ = pt
    m, r = p[IDX["m"]], p[IDX["x_G"]:]
    expected = np.block([[m * np.eye(3), -m * skew(r)], [m * skew(r), np.diag(p[2:5])]])
    return relative_error(c.model.mass_matrix(p), expected)


def _equations_of_motion(c, pt):
    x, U, p, _ = pt
    m = c.model
    nu_dot = m.dynamics(x, U, p)[6:]
    lhs = (m.mass_matrix(p) @ nu_dot + m.coriolis(x, p) @ x[6:] + m.damping(p) @ x[6:]
           + m.gravity(x, p))
    return relative_error(lhs, B_U @ U)


def _z_row(c, pt):
    x, U, p, _ = pt
    m = c.model
    mass, (x_G, y_G, z_G) = p[0], p[11:14]
    u, v, w, P, Q, R = x[6:]
    nu_dot = m.dynamics(x, U, p)[6:]
    _, _, wdot, pdot, qdot, _ = nu_dot
    F_z = mass * (wdot - u * Q + v * P + x_G * (R * P - qdot) + y_G * (R * Q + pdot)
                  - z_G * (Q ** 2 + P ** 2))
    lhs = m.mass_matrix(p) @ nu_dot + m.coriolis(x, p) @ x[6:]
    return relative_error(lhs[2], F_z)


def _regressor_identity(c, pt):
    x, U, p, v = pt
    m = c.model
    diff = _lhs(m, x, v, p) - _lhs(m, x, v, quadcog.with_cog(p, [0, 0, 0]))
    return relative_error(m.regressor(x, v, p) @ p[11:14], diff)


def _regressor_independent(c, pt):
    x, U, p, v = pt
    other = quadcog.with_cog(p, 0.5 * p[11:14][::-1])
    return relative_error(c.model.regressor(x, v, other), c.model.regressor(x, v, p))


def _L_G_h(c, pt):
    x, U, p, _ = pt
    return relative_error(np.array(c.outputs(x, U, p)[0]), np.zeros((4, 4)))


def _alpha(c, pt):
    x, U, p, _ = pt
    return relative_error(c.model.decoupling(x, p), np.array(c.outputs(x, U, p)[2]))


def _b(c, pt):
    x, U, p, _ = pt
    return relative_error(c.model.drift(x, p), np.array(c.outputs(x, np.zeros(4), p)[1]))


def _alpha_H(c, pt):
    x, U, p, _ = pt
    phi, theta, psi = x[3:6]
    H = np.zeros((4, 6))
    H[0, :3], H[1:, 3:] = rotation_matrix(phi, theta, psi)[2], euler_rate_map(phi, theta)
    expected = H @ c.model.inverse_mass_matrix(p) @ B_U
    return relative_error(c.model.decoupling(x, p), expected)


def _linearization(c, pt):
    x, U, p, _ = pt
    A, B = c.model.linearization(x, U, p)
    JA, JB = c.jacobians(x, U, p)
    return max(relative_error(A, np.array(JA)), relative_error(B, np.array(JB)))


def _truth_reduces(c, pt):
    x, U, p, _ = pt
    return relative_error(c.model.truth_dynamics(x, U, p, np.zeros(3), np.zeros(6)),
                          c.model.dynamics(x, U, p))


def _truth_axioms(c, pt):
    """Euler's axioms with a full I_O and an external wrench, written out in numpy."""
    x, U, p, vt = pt
    F_ground, M_body = vt[:3], 0.1 * vt[3:]
    Ixy, Ixz, Iyz = 0.1 * p[2:5] * np.sin(x[:3])
    I_O = np.array([[p[2], Ixy, Ixz], [Ixy, p[3], Iyz], [Ixz, Iyz, p[4]]])
    m, g, r, damping = p[0], p[1], p[11:14], p[5:11]
    nu1, nu2 = x[6:9], x[9:12]
    a, al = np.split(c.model.truth_dynamics(x, U, p, [Ixy, Ixz, Iyz],
                                            np.concatenate([F_ground, M_body]))[6:], 2)
    R = rotation_matrix(*x[3:6])
    f_G = R.T @ np.array([0, 0, -m * g])
    force = f_G + [0, 0, U[0]] - damping[:3] * nu1 + R.T @ F_ground
    moment = np.cross(r, f_G) + U[1:] - damping[3:] * nu2 + M_body
    v_G = nu1 + np.cross(nu2, r)
    h_O = I_O @ nu2 + m * np.cross(r, nu1)
    first = relative_error(m * (a + np.cross(al, r) + np.cross(nu2, v_G)), force)
    second = relative_error(I_O @ al + m * np.cross(r, a) + np.cross(nu2, h_O)
                            + np.cross(nu1, m * v_G), moment)
    return max(first, second)


def _phi_from_Y(c, pt):
    """Phi = m [Y_2, Y_3, Y_4]: with m and I_O held, pi depends on r_G only through m r_G."""
    x, U, p, v = pt
    Y = c.model.inertial_regressor(x, v, p[IDX["g"]])
    return relative_error(p[IDX["m"]] * Y[:, 1:4], c.model.regressor(x, v, p))


def _Y_paper(c, pt):
    x, U, p, v = pt
    pi, g, _ = inertial_arguments(p)
    return relative_error(c.model.inertial_regressor(x, v, g) @ pi, _lhs(c.model, x, v, p))


def _inertial_special_case(c, pt):
    """Through the CasADi function: the paper's pi need not be physically consistent."""
    x, U, p, _ = pt
    xdot = c.vm["inertial_dynamics"](x, U, *inertial_arguments(p))
    return relative_error(np.array(xdot).ravel(), c.model.dynamics(x, U, p))


def _hover_trim(c, pt):
    x, U, p, _ = pt
    x0 = np.zeros(12)
    x0[:3], x0[5] = x[:3], x[5]                     # any position and heading, level, at rest
    return relative_error(c.model.dynamics(x0, hover_trim(p), p), np.zeros(12))


def _zero_dynamics(c, pt):
    """On y = 0 (z = phi = theta = psi = 0, w = p = q = r = 0) with the input U* of the
    report: x_dot = [u, v, 0, 0, 0, 0, -c_x u / m, -c_y v / m, 0, 0, 0, 0]."""
    x, U, p, _ = pt
    m, g, c_x, c_y = p[IDX["m"]], p[IDX["g"]], p[IDX["c_x"]], p[IDX["c_y"]]
    x_G, y_G, z_G = p[11:14]
    x0 = np.zeros(12)
    x0[:2], x0[6:8] = x[:2], x[6:8]
    u, v = x0[6:8]
    U_star = [m * g, c_y * v * z_G + m * g * y_G, -c_x * u * z_G - m * g * x_G,
              c_x * u * y_G - c_y * v * x_G]
    expected = np.zeros(12)
    expected[:2], expected[6:8] = [u, v], [-c_x * u / m, -c_y * v / m]
    return relative_error(c.model.dynamics(x0, U_star, p), expected)


def _backends(c, pt):
    """The compiled C against CasADi's virtual machine, every function."""
    x, U, p, v = pt
    inputs = {"x": x, "U": U, "p": p, "vartheta": v, "I_products": 0.1 * p[2:5] * np.sin(x[:3]),
              "wrench": np.concatenate([v[:3], 0.1 * v[3:]]), "nu_dot": v,
              "pi": box(p[IDX["m"]], 10 * p[2:5], p[IDX["x_G"]:]),     # consistent
              "g": p[IDX["g"]:IDX["g"] + 1], "c": p[IDX["c_x"]:IDX["c_psi"] + 1]}
    q = quaternion_of_euler(*x[3:6])            # the model on SE(3), at the same attitude
    inputs.update({"xq": np.concatenate([x[:3], q, x[6:]]), "quaternion": q, "nu": x[6:],
                   "R": rotation_matrix(*x[3:6]).ravel()})
    worst = 0.0
    for name, (spec_in, _) in FUNCTIONS.items():
        args = [inputs[n] for n, _ in spec_in]
        compiled = getattr(c.model, name)(*args)
        compiled = list(compiled) if isinstance(compiled, tuple) else [compiled]
        vm = c.vm[name](*args)
        vm = list(vm) if isinstance(vm, tuple) else [vm]
        worst = max([worst] + [relative_error(a, np.array(b).reshape(np.shape(a)))
                               for a, b in zip(compiled, vm)])
    return worst


def _min_eig(c, pt):
    return float(np.linalg.eigvalsh(c.model.mass_matrix(pt[2]))[0])


CHECKS = (
    Check("Structure", r"$M = M^T$", 1e-15,
          lambda c, pt: relative_error(c.model.mass_matrix(pt[2]), c.model.mass_matrix(pt[2]).T)),
    Check("Structure", r"$M > 0$: smallest eigenvalue (kg\,m$^2$)", 0.0, _min_eig,
          "min"),
    Check("Structure", r"$M = [mI, -mS(r_G);\ mS(r_G), I_O]$", 1e-14,
          _mass_matrix_definition),
    Check("Structure", r"$M^{-1}M = I$ (\code{inverse\_mass\_matrix})", 1e-12,
          lambda c, pt: relative_error(c.model.inverse_mass_matrix(pt[2])
                                       @ c.model.mass_matrix(pt[2]), np.eye(6))),
    Check("Structure", r"$C(\nu) + C(\nu)^T = 0$", 1e-14,
          lambda c, pt: relative_error(c.model.coriolis(pt[0], pt[2])
                                       + c.model.coriolis(pt[0], pt[2]).T, np.zeros((6, 6)))),
    Check("Structure", r"$D = \operatorname{diag}(c)$", 1e-15,
          lambda c, pt: relative_error(c.model.damping(pt[2]), np.diag(pt[2][5:11]))),
    Check("Structure",
          r"$M\dot\nu + C\nu + D\nu + g_G = B_u U$, $\dot\nu$ from \code{dynamics}", 1e-11,
          _equations_of_motion),
    Check("Structure", r"$F_z$ row with $y_G(rq + \dot p)$ (item 1)", 1e-11, _z_row),
    Check("Regressor", r"$M\vartheta + C\nu + g_G - (\cdot)|_{r_G = 0} = \Phi r_G$ (item 5)",
          1e-12, _regressor_identity),
    Check("Regressor", r"$\Phi$ independent of $r_G$", 1e-13, _regressor_independent),
    Check("Output derivatives", r"$L_G h = 0$ (CasADi AD of \code{dynamics})", 1e-15, _L_G_h),
    Check("Output derivatives", r"$\alpha = \partial\ddot y/\partial U$ (AD)", 1e-10, _alpha),
    Check("Output derivatives", r"$b = \ddot y|_{U=0}$ (AD)", 1e-10, _b),
    Check("Output derivatives", r"$\alpha = H M^{-1} B_u$ (item 4)", 1e-10, _alpha_H),
    Check("Linearization", r"$A$, $B$ = AD Jacobians of \code{dynamics}", 1e-10,
          _linearization),
    Check("Truth model", r"\code{truth\_dynamics} with no products, no wrench = \code{dynamics}",
          1e-13, _truth_reduces),
    Check("Truth model", r"Euler's axioms, full $I_O$, external wrench", 1e-11, _truth_axioms),
    Check("Inertial parameters", r"$\Phi = m\,[Y_2, Y_3, Y_4]$ (columns of $m r_G$)", 1e-12,
          _phi_from_Y),
    Check("Inertial parameters", r"$Y\pi = M\vartheta + C\nu + g_G$ at $\pi = [m, m r_G, "
          r"I_{xx}, 0, I_{yy}, 0, 0, I_{zz}]$", 1e-12, _Y_paper),
    Check("Inertial parameters", r"\code{inertial\_dynamics} at that $\pi$ = \code{dynamics}",
          1e-11, _inertial_special_case),
    Check("Paper items", r"Hover trim $U^* = [mg, mgy_G, -mgx_G, 0]$ gives $\dot x = 0$ (item 7)",
          1e-12, _hover_trim),
    Check("Paper items", r"Zero dynamics on $y = 0$ with $U^*$ (item 8)", 1e-12, _zero_dynamics),
    Check("Backends", r"compiled C = CasADi virtual machine, all functions", 1e-12, _backends),
)


@dataclass
class Result:
    check: Check
    points: int
    value: float             # largest error (kind "max") or smallest value (kind "min")
    ok: bool
    skipped: str = ""


def run(n_points=200, seed=SEED, model=None):
    """Evaluate every check at ``n_points`` seeded random points; a list of Results."""
    model = model or quadcog.load()
    context = Context(model)
    points = random_points(n_points, seed)
    return [evaluate(check, context, points) for check in CHECKS]


def evaluate(check, context, points):
    """The Result of one check over ``points`` ((x, U, p, vartheta) tuples)."""
    if check.errors is _backends and context.model.backend != "c":
        return Result(check, 0, float("nan"), True, "no C compiler")
    values = [check.errors(context, pt) for pt in points]
    if check.kind == "min":
        value = min(values)
        ok = bool(np.isfinite(value) and value > check.bound)
    else:
        value = max(values)
        ok = bool(np.isfinite(value) and value <= check.bound)
    return Result(check, len(points), value, ok)

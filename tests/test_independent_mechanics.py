"""Independent check of ``quadcog``'s exported dynamics with Kane's method.

The project derives its equations of motion in ``derive/`` as a Newton-Euler model
``M nu_dot + C(nu) nu + D nu + g_G(eta) = B_u U`` with hand-built matrices (docs/model.md sec. 1.3).
This file re-derives the same physical system from scratch with
``sympy.physics.mechanics.KanesMethod`` and compares the state derivative numerically with
``quadcog.load().dynamics`` at a few hundred random, admissible points. It imports nothing
from ``derive/`` (nor from ``quadcog`` beyond the public API under test), and it shares none
of the project's intermediate objects:

* Rotation: the body frame is oriented by SymPy (``orient_body_fixed(..., 'zyx')``); the
  resulting direction cosine matrix is checked against ``Rz(psi) Ry(theta) Rx(phi)`` built by
  hand in numpy. No rotation matrix is typed into the derivation.
* Kinematics: ``eta1_dot = R nu1`` uses SymPy's DCM, and the Euler-rate relation
  ``eta2_dot = Q(eta2) nu2`` is not typed in either: the kinematic differential equations
  say that SymPy's own angular velocity of the Euler-angle orientation, resolved in the
  body frame, equals ``p a_x + q a_y + r a_z``; KanesMethod inverts that relation itself.
* Inertia: the rigid body is given its inertia ``diag(Ixx, Iyy, Izz)`` about O (point O);
  SymPy applies the parallel-axis theorem to get the central inertia (cross-checked against
  ``quadcog.inertia_about_cog``).
* Dynamics: Kane's equations (generalized active + inertia forces, projected on partial
  velocities of the mass centre and of the body), not a Newton-Euler expansion, no
  Coriolis matrix, no gravity vector ``g_G``. Forces are applied where they act: weight at
  the mass centre, thrust and linear drag at O, moments as torques on the body.

The mass matrix and forcing of the full (12-state) first-order system are lambdified once
(module-scoped fixture) and ``x_dot = solve(M_full, F_full)`` is compared with the project.

Acceptance criterion (per component of x_dot, at every point):
``|xdot_kane - xdot_quadcog| <= 1e-9 * (1 + |xdot_quadcog|)``; failures report the worst
relative error ``|a - b| / (1 + |b|)``, its component and the index of the worst point.

A negative control re-introduces the paper's z-row typo (``y_G (r q - p_dot)`` instead of
``y_G (r q + p_dot)``, docs/model.md sec. 2.1) into the Kane reference and checks that the same
comparison then fails, so the comparison is sensitive to that error.
"""
import time

import numpy as np
import pytest
import sympy as sm
import sympy.physics.mechanics as me

import quadcog

N_POINTS = 250
SEED = 20240611
RTOL = 1e-9
# Parameter order of the public contract (docs/model.md sec. 1.2), written out here on purpose.
PARAM_ORDER = ("m", "g", "Ixx", "Iyy", "Izz", "c_x", "c_y", "c_z",
               "c_phi", "c_theta", "c_psi", "x_G", "y_G", "z_G")
STATE_ORDER = ("x", "y", "z", "phi", "theta", "psi", "u", "v", "w", "p", "q", "r")


def _rot_numpy(phi, theta, psi):
    """R = Rz(psi) Ry(theta) Rx(phi), body -> ground, by hand."""
    c, s = np.cos, np.sin
    Rx = np.array([[1, 0, 0], [0, c(phi), -s(phi)], [0, s(phi), c(phi)]])
    Ry = np.array([[c(theta), 0, s(theta)], [0, 1, 0], [-s(theta), 0, c(theta)]])
    Rz = np.array([[c(psi), -s(psi), 0], [s(psi), c(psi), 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


# ----------------------------------------------------------------------------- derivation

def _derive():
    t0 = time.perf_counter()
    qs = me.dynamicsymbols("x y z phi theta psi")
    us = me.dynamicsymbols("u v w p q r")
    x, y, z, phi, theta, psi = qs
    u, v, w, p, q, r = us
    m, g, Ixx, Iyy, Izz, cx, cy, cz, cph, cth, cps, xG, yG, zG = sm.symbols(
        " ".join(PARAM_ORDER), real=True)
    params = [m, g, Ixx, Iyy, Izz, cx, cy, cz, cph, cth, cps, xG, yG, zG]
    U1, U2, U3, U4 = sm.symbols("U1:5", real=True)

    N = me.ReferenceFrame("N")
    A = me.ReferenceFrame("A")
    A.orient_body_fixed(N, (psi, theta, phi), "zyx")
    R = N.dcm(A)                                   # ground components = R * body components

    # Kinematic differential equations, from SymPy's own kinematics:
    #   translational: [x', y', z'] = R [u, v, w]
    #   rotational:    (angular velocity of the Euler-angle orientation) . a_i = nu2_i
    omega_euler = A.ang_vel_in(N).to_matrix(A)      # in terms of phi', theta', psi'
    kd = list(sm.Matrix([x.diff(), y.diff(), z.diff()]) - R * sm.Matrix([u, v, w]))
    kd += list(omega_euler - sm.Matrix([p, q, r]))

    # Velocities in terms of the generalized speeds.
    A.set_ang_vel(N, p * A.x + q * A.y + r * A.z)
    No = me.Point("No")
    No.set_vel(N, 0)
    O = No.locatenew("O", x * N.x + y * N.y + z * N.z)
    O.set_vel(N, u * A.x + v * A.y + w * A.z)
    G = O.locatenew("G", xG * A.x + yG * A.y + zG * A.z)
    G.v2pt_theory(O, N, A)

    # Inertia given about O; SymPy derives the central inertia (parallel axis).
    body = me.RigidBody("B", G, A, m, (me.inertia(A, Ixx, Iyy, Izz), O))

    loads = [
        (G, -m * g * N.z),
        (O, U1 * A.z - (cx * u * A.x + cy * v * A.y + cz * w * A.z)),
        (A, (U2 - cph * p) * A.x + (U3 - cth * q) * A.y + (U4 - cps * r) * A.z),
    ]
    kane = me.KanesMethod(N, q_ind=qs, u_ind=us, kd_eqs=kd)
    kane.kanes_equations([body], loads)

    states = list(qs) + list(us)
    inputs = [U1, U2, U3, U4]
    MM = kane.mass_matrix_full
    FF = kane.forcing_full
    assert not (MM.free_symbols | FF.free_symbols) - set(params + inputs) - {me.dynamicsymbols._t}
    fn = sm.lambdify((states, inputs, params), [MM, FF], modules="numpy", cse=True)

    # Negative control: the paper's typo flips the sign of the p_dot term of the z row.
    # Row 6+2 (speed w), column 6+3 (p_dot) of the full mass matrix is m*y_G (correct sign).
    assert sm.simplify(MM[8, 9] - m * yG) == 0, MM[8, 9]
    MM_typo = MM.copy()
    MM_typo[8, 9] = -MM[8, 9]
    fn_typo = sm.lambdify((states, inputs, params), [MM_typo, FF], modules="numpy", cse=True)

    central = body.central_inertia.to_matrix(A)
    fn_central = sm.lambdify([params], central, modules="numpy")
    fn_R = sm.lambdify([[phi, theta, psi]], R, modules="numpy")
    return dict(fn=fn, fn_typo=fn_typo, fn_central=fn_central, fn_R=fn_R,
                seconds=time.perf_counter() - t0)


@pytest.fixture(scope="module")
def kane():
    return _derive()


@pytest.fixture(scope="module")
def model():
    return quadcog.load()


# ----------------------------------------------------------------------------- sampling

def _sample_parameters(rng):
    while True:
        m = rng.uniform(0.3, 2.0)
        g = rng.uniform(9.0, 10.5)
        I = rng.uniform(0.003, 0.05, 3)
        c = rng.uniform(0.0, 0.5, 6)
        rG = rng.uniform(-0.1, 0.1, 3)
        IG = np.diag(I) - m * (rG @ rG * np.eye(3) - np.outer(rG, rG))
        if np.linalg.eigvalsh(IG)[0] > 1e-4:       # admissible with a margin; else resample
            return np.concatenate([[m, g], I, c, rG])


def _sample_state(rng):
    pos = rng.uniform(-5, 5, 3)
    ang = np.array([rng.uniform(-1.2, 1.2), rng.uniform(-1.2, 1.2), rng.uniform(-np.pi, np.pi)])
    vel = rng.uniform(-3, 3, 3)
    rate = rng.uniform(-3, 3, 3)
    return np.concatenate([pos, ang, vel, rate])


def _sample_input(rng):
    return np.concatenate([[rng.uniform(0, 20)], rng.uniform(-1, 1, 3)])


@pytest.fixture(scope="module")
def points():
    rng = np.random.default_rng(SEED)
    return [(_sample_state(rng), _sample_input(rng), _sample_parameters(rng))
            for _ in range(N_POINTS)]


def _xdot(fn, x, U, p):
    MM, FF = fn(x, U, p)
    return np.linalg.solve(np.asarray(MM, float), np.asarray(FF, float).reshape(-1))


def _compare(fn, model, points):
    """Worst per-component relative error |a-b|/(1+|b|) over all points: (err, point, comp)."""
    worst = (-1.0, -1, -1)
    for k, (x, U, p) in enumerate(points):
        ref = _xdot(fn, x, U, p)
        got = model.dynamics(x, U, p)
        rel = np.abs(ref - got) / (1.0 + np.abs(got))
        i = int(np.argmax(rel))
        if rel[i] > worst[0]:
            worst = (float(rel[i]), k, i)
    return worst


# ----------------------------------------------------------------------------- tests

def test_conventions_match_contract():
    assert tuple(quadcog.PARAM_NAMES) == PARAM_ORDER
    assert tuple(quadcog.STATE_NAMES) == STATE_ORDER


def test_orientation_matches_zyx_by_hand(kane):
    rng = np.random.default_rng(SEED + 1)
    for _ in range(20):
        ang = rng.uniform([-1.2, -1.2, -np.pi], [1.2, 1.2, np.pi])
        R_sym = np.asarray(kane["fn_R"](ang), float)
        np.testing.assert_allclose(R_sym, _rot_numpy(*ang), rtol=0, atol=1e-14)


def test_central_inertia_matches_parallel_axis(kane, points):
    for _, _, p in points[:50]:
        np.testing.assert_allclose(np.asarray(kane["fn_central"](p), float),
                                   quadcog.inertia_about_cog(p), rtol=0, atol=1e-15)


def test_dynamics_match_kane(kane, model, points):
    err, k, i = _compare(kane["fn"], model, points)
    assert err <= RTOL, (
        f"quadcog.dynamics disagrees with Kane's method: worst relative error {err:.3e} "
        f"(|a-b|/(1+|b|), tol {RTOL:g}) at point {k} of {len(points)}, "
        f"component {STATE_ORDER[i]!r}; x={points[k][0].tolist()}, U={points[k][1].tolist()}, "
        f"p={points[k][2].tolist()}")


def test_paper_z_row_typo_is_detected(kane, model, points):
    """The paper's printed sign, y_G (r q - p_dot), must make the same comparison fail."""
    err, k, i = _compare(kane["fn_typo"], model, points)
    assert err > 1e3 * RTOL, (
        f"comparison is blind to the paper's z-row sign typo: worst relative error only "
        f"{err:.3e} at point {k}, component {STATE_ORDER[i]!r}")

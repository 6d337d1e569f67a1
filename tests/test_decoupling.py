"""The linear step of the feedback-linearizing laws (quadcog.controllers.decoupling) against
independent oracles: alpha and b factored from M^-1, n and H against the generated
``decoupling`` and ``drift`` (SymPy's own derivation), the elimination against LAPACK's solve,
and each law's input against the same law solved by CasADi's QR. Each would catch a wrong
chain rule (a sign or a missing eta_dot term), an elimination that drops an update or
divides by the wrong pivot, or a law that feeds the solve the wrong right-hand side."""
from fractions import Fraction

import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.controllers.decoupling import decoupled_input, inverse_mass_matrix, linearizing_terms
from quadcog.controllers.design import admissible_estimate_radius
from quadcog.model.parameters import inertia_ratio

RNG = np.random.default_rng(33)


def _states(n, tilt_deg=75.0):
    """Random states over the Euler laws' working range (tilt below 75 deg)."""
    x = np.zeros((n, 12))
    x[:, :3] = RNG.uniform(-5, 5, (n, 3))
    x[:, 3:5] = np.radians(RNG.uniform(-tilt_deg, tilt_deg, (n, 2)))
    x[:, 5] = RNG.uniform(-np.pi, np.pi, n)
    x[:, 6:9] = RNG.uniform(-4, 4, (n, 3))
    x[:, 9:] = RNG.uniform(-3, 3, (n, 3))
    return x


def _estimates(n, vehicle=quadcog.HUMMINGBIRD):
    radius = admissible_estimate_radius(vehicle)
    r = RNG.normal(size=(n, 3))
    return r / np.linalg.norm(r, axis=1)[:, None] * radius * RNG.uniform(0, 1, (n, 1))


def test_alpha_and_b_factored_equal_the_generated_decoupling_and_drift():
    model = quadcog.load()
    ctl = quadcog.AdaptiveFeedbackLinearization()
    x, r = ca.SX.sym("x", 12), ca.SX.sym("r", 3)
    p_hat = ctl.nominal_with_cog(r)
    lin = linearizing_terms(model, x, p_hat)
    f = ca.Function("f", [x, r], [lin.alpha, lin.b, model.casadi_function("decoupling")(x, p_hat),
                                  model.casadi_function("drift")(x, p_hat)])
    worst = 0.0
    for xv, rv in zip(_states(200), _estimates(200)):
        alpha, b, alpha_gen, b_gen = (np.array(o) for o in f(xv, rv))
        scale_a = np.abs(alpha_gen).max()
        scale_b = max(np.abs(b_gen).max(), 1.0)
        worst = max(worst, np.abs(alpha - alpha_gen).max() / scale_a,
                    np.abs(b - b_gen).max() / scale_b)
    assert worst < 1e-12


def _parameters(n):
    """Random parameter vectors: masses, CoG offsets up to 8 cm, inertias about O (the nominal
    vehicle's, scaled), kept where I_G is well inside positive definite."""
    p = np.tile(np.asarray(quadcog.HUMMINGBIRD.parameters(), dtype=float), (4 * n, 1))
    p[:, 0] *= RNG.uniform(0.3, 3.0, 4 * n)
    p[:, 2:5] *= RNG.uniform(0.5, 2.0, (4 * n, 3))
    p[:, 11:14] = RNG.uniform(-0.08, 0.08, (4 * n, 3))
    kept = [row for row in p if inertia_ratio(row) > 0.05][:n]
    assert len(kept) == n
    return kept


def test_the_block_inverse_mass_matrix_inverts_the_generated_mass_matrix():
    """Against LAPACK's inverse of the generated M and the generated M^-1 (SymPy's block
    elimination): a wrong sign in a block, a transposed S G or a wrong cofactor shows."""
    model = quadcog.load()
    p = ca.SX.sym("p", 14)
    f = ca.Function("f", [p], [inverse_mass_matrix(p)])
    for pv in _parameters(200):
        M_inv = np.array(f(pv))
        lapack = np.linalg.inv(model.mass_matrix(pv))
        scale = np.abs(lapack).max()
        assert np.abs(M_inv - lapack).max() <= 1e-13 * scale, pv
        assert np.abs(M_inv - model.inverse_mass_matrix(pv)).max() <= 1e-13 * scale, pv
        # G and the off-diagonal blocks are symmetric by construction, to the bit
        assert (M_inv[3:, 3:] == M_inv[3:, 3:].T).all() and (M_inv[:3, 3:] == M_inv[3:, :3].T).all()


def test_the_block_inverse_takes_less_than_half_the_generated_ones_operations():
    """Every step of an adaptive law forms M_hat^-1 at its new r_hat: the reason for the
    blocks. Counted as the CasADi instructions of each at a symbolic CoG and mass."""
    model = quadcog.load()
    r, m = ca.SX.sym("r", 3), ca.SX.sym("m")
    p = ca.vertcat(m, ca.DM(quadcog.HUMMINGBIRD.parameters()[1:11]), r)

    def operations(expression):
        f = ca.Function("f", [r, m], [ca.cse(expression)])
        return sum(f.instruction_id(k) not in (ca.OP_CONST, ca.OP_INPUT, ca.OP_OUTPUT)
                   for k in range(f.n_instructions()))
    blocks = operations(inverse_mass_matrix(p))
    generated = operations(model.casadi_function("inverse_mass_matrix")(p))
    assert blocks < generated / 2, (blocks, generated)


def test_the_elimination_equals_lapacks_solve_over_the_working_range():
    model = quadcog.load()
    ctl = quadcog.AdaptiveFeedbackLinearization()
    x, r, rhs = ca.SX.sym("x", 12), ca.SX.sym("r", 3), ca.SX.sym("rhs", 4)
    alpha = linearizing_terms(model, x, ctl.nominal_with_cog(r)).alpha
    f = ca.Function("f", [x, r, rhs], [alpha, decoupled_input(alpha, rhs)])
    for xv, rv in zip(_states(300), _estimates(300)):
        v = RNG.normal(size=4) * [10, 50, 50, 20]
        A, U = (np.array(o) for o in f(xv, rv, v))
        want = np.linalg.solve(A, v)
        assert np.abs(U.ravel() - want).max() <= 1e-12 * np.abs(want).max(), (xv, rv)


def _exact_solve(A, b):
    """The solution of A x = b in exact rationals of the given floats, rounded once."""
    rows = [[Fraction(float(v)) for v in A[i]] + [Fraction(float(b[i]))] for i in range(len(b))]
    n = len(b)
    for k in range(n):
        pivot = max(range(k, n), key=lambda i: abs(rows[i][k]))
        rows[k], rows[pivot] = rows[pivot], rows[k]
        for i in range(n):
            if i != k:
                f = rows[i][k] / rows[k][k]
                rows[i] = [a - f * c for a, c in zip(rows[i], rows[k])]
    return np.array([float(rows[i][n] / rows[i][i]) for i in range(n)])


def test_the_elimination_is_within_a_few_ulps_of_the_exact_solution():
    """Over the working range the unpivoted elimination is as accurate as a solve can be in
    doubles (measured: median 8e-17, largest 5e-16 relative; CasADi's QR: 9e-16 and 1.3e-13),
    so giving up pivoting costs no accuracy there."""
    model = quadcog.load()
    ctl = quadcog.AdaptiveFeedbackLinearization()
    x, r, rhs = ca.SX.sym("x", 12), ca.SX.sym("r", 3), ca.SX.sym("rhs", 4)
    alpha = model.casadi_function("decoupling")(x, ctl.nominal_with_cog(r))
    f = ca.Function("f", [x, r, rhs], [alpha, decoupled_input(alpha, rhs)])
    worst = 0.0
    for xv, rv in zip(_states(100, tilt_deg=40.0), _estimates(100)):
        v = RNG.normal(size=4) * [10, 50, 50, 20]
        A, U = (np.array(o) for o in f(xv, rv, v))
        exact = _exact_solve(A, v)
        worst = max(worst, np.abs(U.ravel() - exact).max() / np.abs(exact).max())
    assert worst < 2e-15


@pytest.mark.parametrize("seed", range(5))
def test_the_elimination_solves_any_system_with_nonzero_leading_minors(seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(4, 4)) + np.diag(rng.uniform(2, 5, 4) * rng.choice([-1, 1], 4))
    b = rng.normal(size=4)
    U = np.array(ca.evalf(decoupled_input(ca.SX(ca.DM(A)), ca.SX(ca.DM(b))))).ravel()
    np.testing.assert_allclose(A @ U, b, rtol=0, atol=1e-13)
    np.testing.assert_allclose(U, np.linalg.solve(A, b), rtol=1e-12)


def test_a_zero_pivot_gives_a_non_finite_input_not_a_number_that_looks_right():
    # thrust no longer reaches z (a 90 deg tilt): the z row's thrust gain is 0
    A = np.diag([0.0, 140.0, 140.0, 80.0])
    A[0, 1] = 0.5
    U = np.array(ca.evalf(decoupled_input(ca.SX(ca.DM(A)), ca.SX(ca.DM([1.0, 0, 0, 0])))))
    assert not np.isfinite(U).all()


def _qr_input(ctl, x, ref, p, integral=None):
    """The law's U solved by CasADi's QR on the generated alpha and b at parameters p."""
    model = ctl.model.casadi_function
    e, e_dot, y_ddot_d = ctl.output_errors(x, ref, p)
    v = ctl.commanded_acceleration(e, e_dot, y_ddot_d)
    if integral is not None:
        v = v - ca.vertcat(0, ca.DM(ctl.ki) * integral)
    return ca.solve(model("decoupling")(x, p), v - model("drift")(x, p))


def _agree(f, states, estimates, what):
    traj = quadcog.Circle()
    for k, (xv, ev) in enumerate(zip(states, estimates)):
        U, want = (np.array(o).ravel() for o in f(xv, traj(0.1 * k), ev))
        assert np.isfinite(want).all()
        assert np.abs(U - want).max() <= 1e-9 * max(np.abs(want).max(), 1.0), (what, k)


@pytest.mark.parametrize("name", ["fl", "fl_integral", "adaptive"])
def test_each_law_gives_the_input_of_its_qr_solved_form(name):
    """The law's U against the same law whose solve is CasADi's QR on the generated alpha and
    b: a law that passes the wrong right-hand side or the wrong estimate shows here."""
    ctl = quadcog.make_controller(name)
    x, ref, c = ca.SX.sym("x", 12), ca.SX.sym("ref", 14), ca.SX.sym("c", ctl.n_state)
    if name == "adaptive":
        want = _qr_input(ctl, x, ref, ctl.nominal_with_cog(c))
        estimates = _estimates(40)
    else:
        want = _qr_input(ctl, x, ref, ca.DM(ctl.nominal),
                         c if name == "fl_integral" else None)
        estimates = RNG.normal(size=(40, ctl.n_state)) * 0.1
    f = ca.Function("f", [x, ref, c], [ctl.function()(0.0, x, ref, c)[0], want])
    _agree(f, _states(40, tilt_deg=40.0), estimates, name)


@pytest.mark.parametrize("name", ["composite", "payload_adaptive"])
def test_the_estimating_laws_parts_give_the_input_of_the_qr_solved_form(name):
    ctl = quadcog.make_controller(name)
    x, ref, r = ca.SX.sym("x", 12), ca.SX.sym("ref", 14), ca.SX.sym("r", 3)
    if name == "payload_adaptive":
        m = ctl.nominal[0]
        U = ctl.parts(x, ref, m * 1.2, r)[0]
        want = _qr_input(ctl, x, ref, ctl.estimated_parameters(m * 1.2, r))
    else:
        U = ctl.parts(x, ref, r)[0]
        want = _qr_input(ctl, x, ref, ctl.nominal_with_cog(r))
    f = ca.Function("f", [x, ref, r], [U, want])
    _agree(f, _states(40, tilt_deg=40.0), _estimates(40), name)

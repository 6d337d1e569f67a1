"""The two controllers beyond the paper: the composite adaptive law (filtered identity, least
squares, projection) and feedback linearization with integral action; the yaw-last allocation."""
import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog import HUMMINGBIRD, Disturbance, simulate
from quadcog.controllers import CompositeAdaptive, FeedbackLinearizationIntegral
from quadcog.controllers.allocation import prioritized_input
from quadcog.controllers.composite import unpack_covariance
from quadcog.sim.plant import Actuation, plant_step_function


@pytest.fixture(scope="module")
def composite():
    return CompositeAdaptive()


def _filtered_flight(model, ctl, r, dt, duration=0.4):
    """Open loop (a chosen input, no controller): the truth plant with CoG r and the
    composite's filter states integrated alongside (Euler, as the simulator does).
    Returns (z, Y, M(r) nu) per step."""
    xs, Us, cs = ca.SX.sym("x", 12), ca.SX.sym("U", 4), ca.SX.sym("c", ctl.n_state)
    z, Y, zd, Pd = ctl.filtered_regression(xs, Us, cs[3:9], ca.reshape(cs[9:27], 6, 3))
    f = ca.Function("f", [xs, Us, cs], [z, Y, ca.vertcat(zd, ca.vec(Pd))])
    plant = plant_step_function(model, Actuation.of(HUMMINGBIRD))
    p = HUMMINGBIRD.with_cog(r).parameters()
    M = model.mass_matrix(p)
    x = np.zeros(12)
    x[6:12] = [0.3, -0.2, 0.1, 0.2, -0.15, 0.1]
    c = ctl.initial_state()
    out = []
    for k in range(int(round(duration / dt))):
        t = k * dt
        U = np.array([6.8, 0.004 * np.sin(5 * t), -0.005 * np.cos(3 * t), 0.002 * np.sin(7 * t)])
        zk, Yk, cd = (np.array(a) for a in f(x, U, c))
        out.append((zk.ravel(), Yk, M @ x[6:12]))
        c[3:27] += dt * cd.ravel()
        x = np.array(plant(x, [], U, p, np.zeros(10), np.zeros(3), np.zeros(6), dt)[0]).ravel()
    return [np.array(a) for a in zip(*out)]


def test_filtered_identity_against_numerical_integration(model, composite):
    """z = Y r for the plant's true r_G (the oracle), once the filter's start-up term
    exp(-lam t) has died out, up to the O(dt) error of the Euler-integrated filter: the
    residual halves when dt halves. Second way: filtering a finite-difference derivative of
    M(r) nu gives what the filter computes from M nu alone (no acceleration)."""
    r = np.array([0.03, -0.02, 0.015])
    residual = {}
    for dt in (1e-3, 5e-4):
        z, Y, momentum = _filtered_flight(model, composite, r, dt)
        res = z[-1] - Y[-1] @ r
        residual[dt] = max(np.linalg.norm(res[rows]) / np.linalg.norm(z[-1][rows])
                           for rows in (slice(0, 3), slice(3, 6)))     # force, moment rows
    assert residual[1e-3] < 4e-2        # O(dt): the filters are Euler-integrated
    assert 0.35 < residual[5e-4] / residual[1e-3] < 0.65
    dt, lam = 5e-4, composite.filter_rate
    deriv = np.gradient(momentum, dt, axis=0)
    filt_deriv, filt_mom = np.zeros(6), momentum[0].copy()
    for k in range(len(momentum)):
        filt_deriv += dt * lam * (deriv[k] - filt_deriv)
        filt_mom += dt * lam * (momentum[k] - filt_mom)
    assert np.allclose(filt_deriv, lam * (momentum[-1] - filt_mom),
                       atol=2e-2 * np.max(np.abs(filt_deriv)))


def test_composite_estimate_converges_fast_with_true_r_as_oracle(composite):
    """A [6, 6, 0] cm CoG step at hover: the x_G, y_G estimates are within 5 % of the truth
    within 1 s (the paper's law needs many seconds), the covariance stays in (0, k0 I]."""
    r = np.array([0.06, 0.06, 0.0])
    res = simulate(composite, "hover", duration=2.5, cog=[(0.5, tuple(r), 0.0)])
    assert not res.metrics.diverged
    after = res.t >= 1.5
    assert np.all(np.abs(res.r_hat[after, :2] - r[:2]) <= 0.05 * r[:2])
    paper = simulate(quadcog.AdaptiveFeedbackLinearization(), "hover", duration=2.5,
                     cog=[(0.5, tuple(r), 0.0)])
    assert np.max(np.abs(paper.r_hat[-1, :2] - r[:2])) > 0.2 * r[0]     # the contrast
    assert res.metrics.max_position_error < 0.7 * paper.metrics.max_position_error


def test_covariance_update_bounded_and_positive(composite):
    """P_dot = beta P (I - P/k0) - P Y^T G Y P keeps P <= k0 I and positive definite: a direct
    check on the law's output at random states with a random P inside the bound."""
    rng = np.random.default_rng(3)
    law = composite.function()
    k0, dt = composite.covariance_bound, 1e-3
    for _ in range(20):
        c = composite.initial_state()
        A = rng.normal(size=(3, 3))
        P = A @ A.T
        P *= 0.999 * k0 / np.linalg.eigvalsh(P)[-1]
        c[27:33] = P[np.triu_indices(3)]
        c[3:27] = rng.normal(size=24)
        c[33] = 1.0                          # past the warm-up: the data term is on
        x = np.r_[rng.normal(scale=0.3, size=12)]
        ref = np.zeros(14)
        _, c_dot = law(0.0, x, ref, c)
        P_next = unpack_covariance(c[27:33] + dt * np.array(c_dot).ravel()[27:33])
        eig = np.linalg.eigvalsh(P_next)
        assert eig[0] > 0 and eig[-1] <= k0 * (1 + 1e-9)


def test_projection_keeps_the_estimate_in_the_ball(composite):
    c = composite.initial_state()
    c[:3] = [0.2, 0.0, 0.0]
    projected = np.array(composite.project(ca.DM(c))).ravel()
    assert np.isclose(np.linalg.norm(projected[:3]), composite.projection_radius)
    assert np.array_equal(projected[3:], c[3:])


def test_fl_integral_removes_a_constant_moment_disturbance():
    """A constant roll and pitch moment (as a CoG offset makes): plain FL holds a standing
    position error, the integrator removes it."""
    dist = [Disturbance(t=0.5, duration=100.0, force=(0, 0, 0), moment=(0.15, -0.1, 0.0))]
    runs = {kind: simulate(ctl, "hover", duration=8.0, disturbances=dist)
            for kind, ctl in (("fl", quadcog.FeedbackLinearization()),
                              ("fl_integral", FeedbackLinearizationIntegral()))}
    assert runs["fl"].metrics.rms_position_error_tail > 0.2
    assert runs["fl_integral"].metrics.rms_position_error_tail < 0.005


def test_fl_integral_poles_are_placed():
    """Each attitude row: s^3 + kd s^2 + kp s + ki has the FL poles and the integral pole."""
    ctl = FeedbackLinearizationIntegral(poles_attitude=(-9.0, -11.0), integral_pole=-3.0)
    roots = np.sort(np.roots([1.0, ctl.kd[1], ctl.kp[1], ctl.ki[0]]).real)
    assert np.allclose(roots, [-11.0, -9.0, -3.0])


def _thrust_interval(inv, U_rp, lo, hi):
    """[lo_T, hi_T]: the U1 for which U1 with the moment U_rp (roll, pitch, yaw) keeps every
    rotor within the limits, by numpy (empty when lo_T > hi_T)."""
    a, r = inv[:, 0], inv[:, 1:] @ U_rp
    return np.max((lo - r) / a), np.min((hi - r) / a)


def test_allocation_gives_up_yaw_first_and_a_thrust_beyond_the_rotors_to_roll_pitch():
    Us = ca.SX.sym("U", 4)
    alloc = ca.Function("alloc", [Us], [prioritized_input(Us, HUMMINGBIRD)])
    inv = np.linalg.inv(HUMMINGBIRD.mixer())
    lo, hi = HUMMINGBIRD.min_rotor_thrust, HUMMINGBIRD.max_rotor_thrust
    rng = np.random.default_rng(0)
    seen = set()
    for k in range(400):
        # thrusts from below zero to beyond the rotors' total (a payload too heavy to lift)
        U = np.r_[rng.uniform(-5.0, 4 * hi + 10.0), rng.normal(scale=0.5 if k % 2 else 3.0,
                                                               size=2), rng.normal(scale=0.1)]
        Ua = np.array(alloc(U)).ravel()
        f = inv @ Ua
        assert np.all(f >= lo - 1e-9) and np.all(f <= hi + 1e-9)
        if np.all((inv @ U >= lo) & (inv @ U <= hi)):
            assert np.allclose(Ua, U)                       # feasible: untouched
            seen.add("feasible")
            continue
        s = np.linalg.norm(Ua[1:3]) / np.linalg.norm(U[1:3])
        assert np.allclose(Ua[1:3], s * U[1:3]) and s <= 1 + 1e-12   # direction kept
        if np.all((inv[:, 0] * U[0] >= lo) & (inv[:, 0] * U[0] <= hi)):
            # the thrust alone fits: it is kept, roll-pitch scaled as far as it allows
            assert Ua[0] == U[0]
            more = inv @ np.r_[U[0], min(1.0, 1.001 * s) * U[1:3], 0.0]
            assert s == pytest.approx(1.0, abs=1e-9) or np.any(more < lo - 1e-12) or \
                np.any(more > hi + 1e-12)
            seen.add("thrust kept")
        else:
            # beyond the rotors' range: roll-pitch first (full when some thrust carries it,
            # else no larger scale fits), then the thrust nearest to U1 that carries it
            full = _thrust_interval(inv, np.r_[U[1:3], 0.0], lo, hi)
            if full[0] <= full[1]:
                assert s == pytest.approx(1.0, abs=1e-9)
            else:
                wider = _thrust_interval(inv, np.r_[1.001 * s * U[1:3], 0.0], lo, hi)
                assert wider[0] > wider[1]
                seen.add("roll-pitch scaled")
            t_lo, t_hi = _thrust_interval(inv, np.r_[Ua[1:3], 0.0], lo, hi)
            assert Ua[0] == pytest.approx(min(max(U[0], t_lo), t_hi), abs=1e-9)
            assert Ua[0] != U[0]
            seen.add("thrust moved")
        # yaw last: same sign, no larger, and as large as the limits leave
        assert abs(Ua[3]) <= abs(U[3]) + 1e-12 and Ua[3] * U[3] >= 0
        if abs(Ua[3]) < abs(U[3]) - 1e-9:
            more = inv @ np.r_[Ua[:3], Ua[3] + 1e-3 * np.sign(U[3])]
            assert np.any(more < lo - 1e-12) or np.any(more > hi + 1e-12)
            seen.add("yaw gave way")
    assert seen == {"feasible", "roll-pitch scaled", "thrust moved", "thrust kept",
                    "yaw gave way"}, seen

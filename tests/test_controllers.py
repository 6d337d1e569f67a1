"""The three controllers: design checks, convergence, and the adaptive law against a
hand computation of -Gamma Phi^T B^T P e_s in numpy."""
from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog import AdaptiveFeedbackLinearization, CascadePD, CogProfile, FeedbackLinearization, simulate
from quadcog.model.conventions import B_U


@pytest.fixture(scope="module")
def controllers():
    return {"pd": CascadePD(), "fl": FeedbackLinearization(),
            "adaptive": AdaptiveFeedbackLinearization()}


def test_pd_closed_loop_eigenvalues_are_the_chosen_poles(model):
    poles = dict(poles_z=(-2.0, -3.5), poles_psi=(-3.0, -6.0),
                 poles_x=(-1.0, -1.7, -9.0, -13.0), poles_y=(-1.2, -2.1, -8.0, -11.0))
    pd = CascadePD(**poles)
    p = pd.nominal
    A, B = model.linearization(np.zeros(12), [p[0] * p[1], 0, 0, 0], p)
    eig = np.sort(np.linalg.eigvals(A - B @ pd.K).real)
    chosen = np.sort(np.concatenate([np.array(v) for v in poles.values()]))
    assert_close(eig, chosen, 1e-8, "closed-loop eigenvalues")
    # the cascade reading of the gains: U3 = -k3 (theta - theta_d) - k4 q
    assert pd.gains["x"][2] > 0 and pd.gains["y"][2] > 0


def test_bad_poles_rejected():
    with pytest.raises(quadcog.InputError, match=r"poles_x\[1\]: expected a finite pole with "
                                                 r"negative real part, got 2.0"):
        CascadePD(poles_x=(-1.0, 2.0, -3.0, -4.0))
    with pytest.raises(quadcog.InputError, match=r"poles_attitude\[0\]: expected a finite pole"):
        FeedbackLinearization(poles_attitude=(1.0, -2.0))
    with pytest.raises(quadcog.InputError, match="gamma: expected a positive number, got -1"):
        AdaptiveFeedbackLinearization(gamma=-1)


@pytest.mark.parametrize("name", ["pd", "fl", "adaptive"])
@pytest.mark.parametrize("trajectory", ["hover", "circle"])
def test_balanced_tracking_converges(controllers, name, trajectory):
    """From a 0.5 m, 10 deg-yaw offset start, the balanced vehicle settles under 5 cm."""
    traj = quadcog.Hover() if trajectory == "hover" else quadcog.Circle()
    x0 = np.zeros(12)
    x0[:3] = traj(0.0)[:3] + [0.3, -0.3, 0.3]
    x0[5] = np.radians(10)
    res = simulate(controllers[name], traj, duration=15.0, x0=x0)
    m = res.metrics
    assert not m.diverged, m
    assert m.rms_position_error_tail < 0.05, m
    assert m.max_position_error >= 0.5, "the start offset was not seen"
    e = np.linalg.norm(res.x[:, :3] - res.ref[:, :3], axis=1)
    assert np.all(e[res.t >= 10.0] < 0.05), f"error after settling: {e[res.t >= 10].max()}"


def _tilt(a, psi, g, max_tilt):
    c, s = np.cos(psi), np.sin(psi)
    ax, ay = c * a[0] + s * a[1], -s * a[0] + c * a[1]
    lift = g + a[2]
    theta = np.arctan2(ax, lift)
    phi = np.arctan2(-ay, np.hypot(ax, lift))
    return np.clip([phi, theta], -max_tilt, max_tilt)


def test_adaptive_update_by_hand(model, controllers):
    """r_hat_dot = -Gamma Phi^T B^T P e_s and alpha_hat U + b_hat = v, all rebuilt in numpy
    from docs/model.md sec. 3.2 at 200 random states and estimates (hover reference)."""
    ctl = controllers["adaptive"]
    law = ctl.compiled()
    rng = np.random.default_rng(7)
    ref = quadcog.Hover(position=(0.2, -0.1, 1.0), yaw=0.3)(0.0)
    # the error model rebuilt from the gains; the controller's P must solve its Lyapunov
    # equation with it (a P from a wrong A or Q fails here)
    A = np.block([[np.zeros((4, 4)), np.eye(4)], [-np.diag(ctl.kp), -np.diag(ctl.kd)]])
    P = ctl.P
    assert_close(A.T @ P + P @ A, -np.eye(8), 1e-10, "Lyapunov equation of the controller's P")
    g, m = ctl.nominal[1], ctl.nominal[0]
    drag = np.array([ctl.nominal[5] / m, ctl.nominal[6] / m, 0.0])
    for k in range(200):
        x = np.zeros(12)
        x[:3] = ref[:3] + rng.uniform(-0.5, 0.5, 3)
        x[3:6] = rng.uniform(-0.3, 0.3, 3)
        x[6:12] = rng.uniform(-1, 1, 6)
        r_hat = rng.uniform(-0.05, 0.05, 3)
        law.inputs[0][0] = 0.0
        law.inputs[1][:] = x
        law.inputs[2][:] = ref
        law.inputs[3][:] = r_hat
        U, r_dot = (o.copy() for o in law())
        p_hat = quadcog.with_cog(ctl.nominal, r_hat)
        phi, th, psi = x[3:6]
        R3 = np.array([-np.sin(th), np.sin(phi) * np.cos(th), np.cos(phi) * np.cos(th)])
        Q = np.array([[1, np.sin(phi) * np.tan(th), np.cos(phi) * np.tan(th)],
                      [0, np.cos(phi), -np.sin(phi)],
                      [0, np.sin(phi) / np.cos(th), np.cos(phi) / np.cos(th)]])
        H = np.zeros((4, 6))
        H[0, :3], H[1:, 3:] = R3, Q
        cp, sp_, cs, ss = np.cos(phi), np.sin(phi), np.cos(psi), np.sin(psi)
        R = np.array([[cs * np.cos(th), cs * np.sin(th) * sp_ - ss * cp, cs * np.sin(th) * cp + ss * sp_],
                      [ss * np.cos(th), ss * np.sin(th) * sp_ + cs * cp, ss * np.sin(th) * cp - cs * sp_],
                      [-np.sin(th), np.cos(th) * sp_, np.cos(th) * cp]])
        v_ground = R @ x[6:9]
        kp = np.array([ctl.kp_pos, ctl.kp_pos, ctl.kp[0]])
        kd = np.array([ctl.kd_pos, ctl.kd_pos, ctl.kd[0]])
        a_cmd = ref[6:9] + kp * (ref[:3] - x[:3]) + kd * (ref[3:6] - v_ground) + drag * v_ground
        phi_d, th_d = _tilt(a_cmd, psi, g, ctl.max_tilt)
        psi_dot = (Q @ x[9:12])[2]
        h = 1e-6   # hover reference: the commanded tilt moves only through the heading
        rates = (_tilt(a_cmd, psi + h, g, ctl.max_tilt) - _tilt(a_cmd, psi - h, g, ctl.max_tilt)) / (2 * h) * psi_dot
        y_dot = H @ x[6:12]
        e = np.array([x[2] - ref[2], phi - phi_d, th - th_d,
                      np.arctan2(np.sin(psi - ref[12]), np.cos(psi - ref[12]))])
        e_dot = y_dot - np.array([ref[5], rates[0], rates[1], ref[13]])
        v = -ctl.kp * e - ctl.kd * e_dot
        assert_close(model.decoupling(x, p_hat) @ U + model.drift(x, p_hat), v, 1e-7,
                     "alpha_hat U + b_hat = v", k)
        M_hat = model.mass_matrix(p_hat)
        n_hat = (model.coriolis(x, p_hat) + model.damping(p_hat)) @ x[6:12] + model.gravity(x, p_hat)
        nu_dot_star = np.linalg.solve(M_hat, B_U @ U - n_hat)
        Phi = model.regressor(x, nu_dot_star, p_hat)
        B = np.vstack([np.zeros((4, 6)), H @ np.linalg.inv(M_hat)])
        e_s = np.concatenate([e, e_dot])
        expected = -ctl.gamma * (Phi.T @ B.T @ P @ e_s)
        assert_close(r_dot, expected, 1e-7, "r_hat_dot", k)


def test_error_dynamics_identity(model, controllers):
    """docs/model.md sec. 3.2: y_ddot - v = H M^{-1} Phi(nu, eta, nu_dot_star) (r_hat - r) exactly."""
    ctl = controllers["adaptive"]
    rng = np.random.default_rng(8)
    for k in range(200):
        x = np.zeros(12)
        x[3:6] = rng.uniform(-0.3, 0.3, 3)
        x[6:12] = rng.uniform(-1, 1, 6)
        r_true, r_hat = rng.uniform(-0.05, 0.05, (2, 3))
        p_true = quadcog.with_cog(ctl.nominal, r_true)
        p_hat = quadcog.with_cog(ctl.nominal, r_hat)
        U = rng.uniform([5, -0.3, -0.3, -0.1], [8, 0.3, 0.3, 0.1])
        y_ddot = model.decoupling(x, p_true) @ U + model.drift(x, p_true)
        v = model.decoupling(x, p_hat) @ U + model.drift(x, p_hat)
        M_hat = model.mass_matrix(p_hat)
        n_hat = (model.coriolis(x, p_hat) + model.damping(p_hat)) @ x[6:12] + model.gravity(x, p_hat)
        nu_dot_star = np.linalg.solve(M_hat, B_U @ U - n_hat)
        Phi = model.regressor(x, nu_dot_star, p_hat)
        # H M^{-1} = alpha M B_u^+ ... computed directly instead:
        phi, th = x[3], x[4]
        H = np.zeros((4, 6))
        H[0, :3] = [-np.sin(th), np.sin(phi) * np.cos(th), np.cos(phi) * np.cos(th)]
        H[1:, 3:] = [[1, np.sin(phi) * np.tan(th), np.cos(phi) * np.tan(th)],
                     [0, np.cos(phi), -np.sin(phi)],
                     [0, np.sin(phi) / np.cos(th), np.cos(phi) / np.cos(th)]]
        rhs = H @ np.linalg.solve(model.mass_matrix(p_true), Phi @ (r_hat - r_true))
        assert_close(y_ddot - v, rhs, 1e-9, "y_ddot - v", k)


def test_projection_keeps_estimate_in_ball():
    """With a tiny projection radius the estimate stays on the ball; off, it leaves it."""
    cog = CogProfile.step(0.5, (0.06, 0.06, 0.0))
    on = simulate(AdaptiveFeedbackLinearization(projection_radius=0.02), "hover", duration=4.0,
                  cog=cog)
    off = simulate(AdaptiveFeedbackLinearization(projection_radius=None), "hover", duration=4.0,
                   cog=cog)
    norm_on = np.linalg.norm(on.r_hat, axis=1).max()
    assert norm_on <= 0.02 * (1 + 1e-12), norm_on
    assert np.linalg.norm(off.r_hat, axis=1).max() > 0.03


def test_controller_python_call_matches_compiled(controllers):
    rng = np.random.default_rng(3)
    for name, ctl in controllers.items():
        law = ctl.compiled()
        for _ in range(20):
            x = np.concatenate([rng.uniform(-1, 1, 3), rng.uniform(-0.3, 0.3, 3), rng.uniform(-1, 1, 6)])
            ref = quadcog.Circle()(rng.uniform(0, 10))
            c = rng.uniform(-0.05, 0.05, ctl.n_state)
            U, c_dot = ctl(0.0, x, ref, c)
            law.inputs[1][:], law.inputs[2][:] = x, ref
            if ctl.n_state:
                law.inputs[3][:] = c
            out = law()
            assert_close(out[0], U, 1e-12, f"{name} U")
            if ctl.n_state:
                assert_close(out[1], c_dot, 1e-12, f"{name} c_dot")

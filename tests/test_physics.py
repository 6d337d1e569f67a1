"""Physics of the truth model and the references, against oracles written here: the
parallel-axis theorem, the direction of gravity and drag in the plant, the yaw reaction of the
rotors, numerical differentiation of the reference positions, and tracking that needs the
reference jerk fed forward."""
import casadi as ca
from conftest import assert_close
import numpy as np
import pytest

from quadcog import HUMMINGBIRD, Circle, FeedbackLinearization, Figure8, Helix, TruthOptions, simulate
from quadcog.sim.plant import truth_arguments


def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


@pytest.mark.parametrize("r", [(0.03, -0.02, 0.01), (0.06, 0.06, 0.0), (0.0, 0.0, 0.05)])
def test_parallel_axis_inertia(r):
    """I_O = I_G - m S(r)^2 (Steiner) for a body whose inertia about its CoG is I_G, the CoG at
    r from O; without the option I_O is the vehicle's diagonal."""
    v = HUMMINGBIRD.with_cog(r)
    p = v.parameters()
    m, I_G = v.m, np.diag([v.Ixx, v.Iyy, v.Izz])
    expected = I_G - m * _skew(np.array(r)) @ _skew(np.array(r))

    def inertia(options):
        p_eff, products = truth_arguments(ca.SX(ca.DM(p)), options)
        d = np.array(ca.DM(p_eff)).ravel()[2:5]
        ixy, ixz, iyz = np.array(ca.DM(products)).ravel()
        return np.array([[d[0], ixy, ixz], [ixy, d[1], iyz], [ixz, iyz, d[2]]])

    assert_close(inertia(TruthOptions(parallel_axis=True)), expected, 1e-15, "I_O")
    assert_close(inertia(TruthOptions()), I_G, 0, "I_O without the option")


def _one_step(U, x=None, vehicle=HUMMINGBIRD, dt=1e-3):
    """The plant's state after one step of a constant input (Python path)."""
    x0 = np.zeros(12) if x is None else np.asarray(x, float)
    x0[2] += 1.0
    res = simulate(lambda t, x, ref, c: np.asarray(U, float), "hover", duration=dt, dt=dt,
                   vehicle=vehicle, x0=x0, path="python", check_dt=False)
    return res.x[-1], x0


def test_gravity_pulls_down():
    """No thrust, at rest, level, no drag: the vehicle falls with g (z up):
    z(dt) = z0 - g dt^2 / 2, w(dt) = -g dt."""
    dt = 0.01
    x, x0 = _one_step([0, 0, 0, 0], dt=dt, vehicle=HUMMINGBIRD.replace(c_z=0.0))
    g = HUMMINGBIRD.g
    assert_close(x[[2, 8]], [x0[2] - g * dt ** 2 / 2, -g * dt], 1e-9, "free fall")


def test_drag_opposes_the_velocity():
    """In hover thrust, moving at u = 2 m/s: drag c_x decelerates, u_dot = -c_x u / m."""
    v0 = np.zeros(12)
    v0[6] = 2.0
    dt = 1e-3
    x, _ = _one_step([HUMMINGBIRD.m * HUMMINGBIRD.g, 0, 0, 0], x=v0, dt=dt)
    expected = 2.0 * np.exp(-HUMMINGBIRD.c_x / HUMMINGBIRD.m * dt)
    assert_close(x[6], expected, 1e-12, "u after one step")


def test_yaw_reaction_of_the_rotors():
    """Rotors 1 and 3 of the Hummingbird turn clockwise seen from above: speeding them up (and
    slowing 2 and 4 by as much) turns the body counter-clockwise, r_dot = 4 k df / Izz > 0."""
    df = 0.1
    f = np.full(4, HUMMINGBIRD.m * HUMMINGBIRD.g / 4) + np.array([df, -df, df, -df])
    dt = 1e-3
    x, _ = _one_step(HUMMINGBIRD.mixer() @ f, dt=dt)
    r_dot = 4 * HUMMINGBIRD.moment_constant * df / HUMMINGBIRD.Izz
    assert x[11] > 0
    assert_close(x[11] / dt, r_dot, 1e-3, "yaw acceleration")     # drag: c_psi r is 1e-6


def _finite_differences(traj, t, h=1e-2):
    """(v, a, j) (3,) by 4th-order central differences of the position only."""
    p = lambda s: traj.sample([s])[0, :3]
    pm3, pm2, pm1, p0, pp1, pp2, pp3 = (p(t + k * h) for k in range(-3, 4))
    v = (-pp2 + 8 * pp1 - 8 * pm1 + pm2) / (12 * h)
    a = (-pp2 + 16 * pp1 - 30 * p0 + 16 * pm1 - pm2) / (12 * h ** 2)
    j = (-pp3 + 8 * pp2 - 13 * pp1 + 13 * pm1 - 8 * pm2 + pm3) / (8 * h ** 3)
    return v, a, j


@pytest.mark.parametrize("traj", [
    Circle(center=(0.5, -0.2, 1.0), radius=1.3, period=7.0),
    Figure8(center=(0.0, 0.3, 1.2), size=1.5, period=9.0),
    Helix(center=(0.0, 0.0, 0.5), radius=0.8, period=6.0, climb_rate=0.3),
], ids=["circle", "figure8", "helix"])
def test_reference_derivatives(traj):
    """Velocity, acceleration and jerk of each reference against numerical differentiation of
    its position (truncation of order h^4 = 1e-8 times the higher derivatives, rounding about
    1e-16 |p| / h^3 = 1e-10)."""
    for t in (0.0, 1.3, 4.7, 8.1):
        row = traj.sample([t])[0]
        v, a, j = _finite_differences(traj, t)
        assert_close(row[3:6], v, 1e-6, f"velocity at t = {t}")
        assert_close(row[6:9], a, 1e-6, f"acceleration at t = {t}")
        assert_close(row[9:12], j, 1e-6, f"jerk at t = {t}")


def test_tracking_needs_the_jerk_feed_forward():
    """Started on a fast figure-8 (1.5 m, 6 s), feedback linearization tracks it with 1.5 cm
    RMS error (measured), because the commanded attitude's rate comes from the reference jerk;
    with the jerk dropped from that rate the attitude lags and the RMS error is 15 cm."""
    res = simulate(FeedbackLinearization(), Figure8(size=1.5, period=6.0), duration=6.0)
    assert res.metrics.rms_position_error < 0.03, res.metrics

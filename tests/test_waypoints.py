"""Minimum-snap waypoints: through every point, at rest at both ends, derivatives exact
(against numerical differentiation), smoother than any other curve with the same constraints;
the reference check flags what the vehicle cannot follow."""
import re
import warnings

import numpy as np
import pytest

import quadcog
from quadcog.errors import InputError
from quadcog.trajectories.feasibility import check_reference, reference_limits
from quadcog.trajectories.waypoints import MinimumSnap, allocate_times

POINTS = [[0, 0, 1], [1, 0, 1], [1, 1, 1.5], [0, 1, 1], [0.3, 0.2, 1.2]]


@pytest.fixture(scope="module")
def path():
    return MinimumSnap(POINTS, max_speed=1.0, max_acceleration=1.0)


def test_passes_through_the_waypoints_at_rest_at_the_ends(path):
    ref = path.sample(path.times)
    assert np.allclose(ref[:, :3], POINTS, atol=1e-12)
    assert np.allclose(ref[[0, -1], 3:12], 0, atol=1e-12)
    before, after = path.sample([-1.0]), path.sample([path.times[-1] + 2])
    assert np.allclose(before[0, :3], POINTS[0]) and np.allclose(after[0, :3], POINTS[-1])
    assert np.allclose(before[0, 3:12], 0) and np.allclose(after[0, 3:12], 0)


def test_derivatives_are_exact(path):
    """Velocity, acceleration and jerk against central differences of the sampled position
    (and of each other), inside the segments and across the joins."""
    h = 1e-4
    t = np.linspace(path.times[0] + 0.01, path.times[-1] - 0.01, 157)
    t = np.concatenate([t, path.times[1:-1]])               # the joins too
    for k, (lo, hi) in enumerate([(0, 3), (3, 6), (6, 9)]):
        num = (path.sample(t + h)[:, lo:hi] - path.sample(t - h)[:, lo:hi]) / (2 * h)
        exact = path.sample(t)[:, hi:hi + 3]
        assert np.abs(num - exact).max() < 1e-6 * max(1, np.abs(exact).max()), k


def test_joins_are_smooth_up_to_the_sixth_derivative(path):
    """Snap is continuous at the joins (it is what the optimum makes continuous); the
    snap of each piece, differentiated from the polynomial coefficients."""
    c = path.coefficients
    T = np.diff(path.times)
    for i in range(len(T) - 1):
        for order in range(1, 7):
            k = np.arange(order, 8)
            f = np.array([np.prod(np.arange(j - order + 1, j + 1)) for j in k])
            left = (f * T[i] ** (k - order)) @ c[i, order:]
            right = c[i + 1, order] * np.prod(np.arange(1, order + 1))
            assert np.allclose(left, right, atol=1e-8 * max(1, np.abs(left).max())), (i, order)


def test_equals_the_textbook_quadratic_program(path):
    """Minimum snap as Mellinger and Kumar (2011) pose it: minimize the sum over segments of
    the integral of the squared snap over degree-7 pieces, subject to the waypoints, rest at
    both ends and continuity of derivatives 1..3 only at the joins, solved as one KKT system.
    The module solves instead the C^6 septic-spline conditions; both must give one curve."""
    T = np.diff(path.times)
    n = len(T)

    def row(tau, order):
        return np.array([np.prod(np.arange(k - order + 1, k + 1)) * tau ** (k - order)
                         if k >= order else 0.0 for k in range(8)])

    H = np.zeros((8 * n, 8 * n))
    for s_, Ts in enumerate(T):
        for a in range(4, 8):
            for b in range(4, 8):
                ca = a * (a - 1) * (a - 2) * (a - 3)
                cb = b * (b - 1) * (b - 2) * (b - 3)
                H[8 * s_ + a, 8 * s_ + b] = ca * cb * Ts ** (a + b - 7) / (a + b - 7)
    rows, rhs = [], []

    def add(entries, value):
        r = np.zeros(8 * n)
        for seg, vec in entries:
            r[8 * seg:8 * seg + 8] += vec
        rows.append(r)
        rhs.append(value)

    pts = np.asarray(POINTS, float)
    for s_ in range(n):
        add([(s_, row(0, 0))], pts[s_])
        add([(s_, row(T[s_], 0))], pts[s_ + 1])
    for o in (1, 2, 3):
        add([(0, row(0, o))], np.zeros(3))
        add([(n - 1, row(T[-1], o))], np.zeros(3))
    for s_ in range(n - 1):
        for o in (1, 2, 3):
            add([(s_, row(T[s_], o)), (s_ + 1, -row(0, o))], np.zeros(3))
    A, b = np.array(rows), np.array(rhs)
    kkt = np.block([[2 * H, A.T], [A, np.zeros((len(A), len(A)))]])
    sol = np.linalg.solve(kkt, np.vstack([np.zeros((8 * n, 3)), b]))[:8 * n]
    assert np.allclose(sol.reshape(n, 8, 3), path.coefficients, rtol=1e-7, atol=1e-7)


def test_time_allocation_is_the_trapezoid_rule():
    # 4 m at 1 m/s and 1 m/s^2: reaches the speed (4 >= 1): 4/1 + 1/1 = 5 s;
    # 0.25 m does not: 2 sqrt(0.25 / 1) = 1 s
    T = allocate_times(np.array([[0, 0, 0], [4, 0, 0], [4, 0.25, 0]]), 1.0, 1.0)
    assert np.allclose(T, [5.0, 1.0])


@pytest.mark.parametrize("kwargs, words", [
    (dict(waypoints=[[0, 0, 1]]), ["waypoints", "at least 2"]),
    (dict(waypoints=[[0, 0, 1], [1, 0, np.nan]]), ["waypoints"]),
    (dict(waypoints=[[0, 0, 1], [1, 0, 1]], times=[0, 0]), ["times", "increasing"]),
    (dict(waypoints=[[0, 0, 1], [1, 0, 1]], max_speed=0), ["max_speed", "positive"]),
])
def test_bad_waypoints_are_named(kwargs, words):
    with pytest.raises(InputError) as e:
        MinimumSnap(**kwargs)
    for w in words:
        assert w in str(e.value)


def test_reference_limits_of_the_hummingbird():
    """By hand for the "+" layout: 4 rotors at f_max over m; full differential thrust of the
    two rotors on the roll axis (one at f_max, the other at 0) at the arm length, over Ixx,
    gives alpha (about 146 rad/s^2), and omega = sqrt(2 alpha pi / 4)."""
    v = quadcog.HUMMINGBIRD
    f = v.max_rotor_thrust
    assert f == pytest.approx(6.0, rel=1e-3)
    lim = reference_limits(v)
    assert lim.max_specific_thrust == pytest.approx(4 * f / 0.68)
    assert lim.max_rate == pytest.approx(np.sqrt(2 * (0.17 * f / 0.007) * np.pi / 4))


def test_a_step_in_a_user_reference_warns_and_is_in_the_metrics():
    """The issue's case: a waypoint step finite-differenced into ~1e6 m/s^2 and ~5e8 m/s^3."""
    step = lambda t: [0.0, 0.0, 1.0] if t < 0.5 else [1.0, 0.0, 1.0]
    with pytest.warns(quadcog.errors.ReferenceWarning, match="jerk") as w:
        res = quadcog.simulate(quadcog.FeedbackLinearization(), step, duration=1.0)
    when = float(re.search(r"from t = ([0-9.]+) s", str(w[0].message)).group(1))
    assert 0.49 <= when <= 0.5                       # the finite-difference stencil sees it early
    ref = res.metrics.reference
    assert not ref["feasible"]
    assert ref["max_jerk"] == pytest.approx(5e8, rel=0.01)          # 1 m / (2 h^3), h = 1 ms
    assert ref["max_acceleration"] == pytest.approx(1e6, rel=0.01)  # 1 m / h^2


def test_a_feasible_reference_is_quiet(path):
    with warnings.catch_warnings():
        warnings.simplefilter("error", quadcog.errors.ReferenceWarning)
        res = quadcog.simulate(quadcog.FeedbackLinearization(), path, duration=2.0)
    assert res.metrics.reference["feasible"]
    chk = check_reference(res.t, res.ref, quadcog.HUMMINGBIRD)
    assert chk.max_acceleration < 2.0


def test_the_checks_flag_each_limit():
    v = quadcog.HUMMINGBIRD
    t = np.array([0.0])
    ref = np.zeros((1, 14))
    ref[0, 8] = -12.0                               # fall faster than g: rotors cannot pull
    assert "pull" in check_reference(t, ref, v).reason
    ref[0, 8], ref[0, 6] = 0.0, 12 * 9.81           # 85+ deg of tilt
    assert "tilt" in check_reference(t, ref, v).reason
    ref[0, 6], ref[0, 8] = 0.0, 30.0                # more than 24 N / 0.68 kg up
    assert "thrust" in check_reference(t, ref, v).reason
    ref[0, 8], ref[0, 9] = 0.0, 200.0               # 200 m/s^3 across g: 20 rad/s > 15.1
    assert "jerk" in check_reference(t, ref, v).reason
    ref[0, 9] = 100.0
    assert check_reference(t, ref, v).feasible

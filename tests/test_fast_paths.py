"""The shortcuts of the single flight's set-up and results against the general forms they
stand for: each would be wrong in a way these catch (a sparse output read as dense, a hover
check that misses a bad row, CoG rows of unsorted times, a position error off in its bits, a
row fill that skips or repeats wrong rows, output arrays that overlap)."""
import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.codegen.fastcall import evaluate
from quadcog.numerics import fill_rows, repeated_row, row_distances, row_norms
from quadcog.sim.flight import _outputs
from quadcog.sim.schedule import Schedule
from quadcog.sim.timeline import CogProfile
from quadcog.trajectories.feasibility import check_reference


def test_evaluate_matches_a_plain_call_with_sparse_and_matrix_arguments():
    x, M = ca.SX.sym("x", 3), ca.SX.sym("M", 2, 2)
    jac = ca.jacobian(ca.vertcat(x[0] * x[1], ca.sin(x[2]), M[0, 1] * x[0]), x)  # sparse
    f = ca.Function("f", [x, M], [jac, M @ M, ca.sumsqr(x)])
    rng = np.random.default_rng(3)
    for _ in range(3):                         # kept buffers: later calls see new inputs
        xv, Mv = rng.normal(size=3), rng.normal(size=(2, 2))
        got = evaluate(f, xv, Mv)
        want = [np.array(o) for o in f(xv, Mv)]
        assert f.nnz_out(0) < 9
        assert np.array_equal(got[0], want[0])
        assert np.array_equal(got[1], want[1])
        assert got[2].shape == (1,) and got[2][0] == want[2].item()


def test_hover_is_the_one_constant_trajectory_and_its_check_equals_the_full_one():
    assert quadcog.Hover.constant and not quadcog.Circle.constant
    t = np.arange(2001) * 1e-3
    ref = quadcog.Hover(position=(1.0, -2.0, 3.0), yaw=0.4).sample(t)
    assert (ref == ref[0]).all() and ref[0, 12] == 0.4
    full = check_reference(t, ref, quadcog.HUMMINGBIRD)
    assert check_reference(t, ref, quadcog.HUMMINGBIRD, constant=True) == full
    # the shortcut is only taken when asked: a bad row in a non-constant reference is found
    ref[1500, 6] = 1e3
    bad = check_reference(t, ref, quadcog.HUMMINGBIRD)
    assert not bad.feasible and bad.first_violation_t == pytest.approx(1.5)


def test_a_sampled_reference_equals_its_parts_side_by_side():
    t = np.linspace(0.0, 7.0, 701)
    for trajectory in (quadcog.Circle(), quadcog.Figure8(), quadcog.Helix(), quadcog.Hover()):
        p, v, a, j = trajectory._pvaj(t)
        want = np.hstack([np.broadcast_to(part, (t.size, 3)) for part in (p, v, a, j)]
                         + [np.full((t.size, 1), trajectory.yaw), np.zeros((t.size, 1))])
        assert trajectory.sample(t).tobytes() == want.tobytes(), trajectory


def test_cog_rows_are_the_same_for_times_in_and_out_of_order():
    profile = CogProfile([(0.5, (0.02, -0.01, 0.0), 0.0), (1.0, (0.0, 0.03, 0.01), 0.4)])
    t = np.linspace(0.0, 2.0, 401)
    r = profile.sample(t)
    assert np.array_equal(r[t < 0.5], np.zeros(((t < 0.5).sum(), 3)))
    assert np.allclose(r[(t >= 0.5) & (t < 1.0)], (0.02, -0.01, 0.0), atol=0, rtol=0)
    assert np.array_equal(r[t >= 1.4], np.tile((0.0, 0.03, 0.01), ((t >= 1.4).sum(), 1)))
    mid = np.flatnonzero(np.isclose(t, 1.2))[0]
    assert r[mid] == pytest.approx([0.01, 0.01, 0.005])
    order = np.random.default_rng(0).permutation(t.size)
    assert np.array_equal(profile.sample(t[order]), r[order])
    assert profile.sample(np.array([])).shape == (0, 3)


def test_row_distances_round_as_the_norms_of_the_differences():
    rng = np.random.default_rng(1)
    a = rng.normal(size=(500, 15)) * rng.choice([1e-3, 1.0, 1e200], size=(500, 1))
    b = rng.normal(size=(500, 14))
    assert row_distances(a, b).tobytes() == row_norms(a[:, :3] - b[:, :3]).tobytes()
    assert np.isinf(row_distances(a, b)).any()       # 1e200 squared overflows, quietly


def test_a_flight_reports_the_position_errors_its_samples_have():
    res = quadcog.simulate(quadcog.CascadePD(), trajectory="circle", duration=1.0,
                           cog=[(0.2, (0.03, 0.0, 0.0), 0.0)])
    e = np.sqrt(((res.x[:, :3] - res.ref[:, :3]) ** 2).sum(axis=1))
    rms = np.sqrt(np.mean(e ** 2))
    assert res.metrics.rms_position_error == pytest.approx(rms, rel=1e-12)
    assert res.metrics.final_position_error == pytest.approx(e[-1], rel=1e-12)


def test_fastcall_refuses_a_sparse_matrix_output_by_name():
    """A sparse matrix output has no view of its shape: a typed error naming it, not numpy's
    reshape error; ``evaluate`` gives it dense."""
    from quadcog.codegen.fastcall import FastCall
    from quadcog.errors import InputError
    x = ca.SX.sym("x", 2)
    f = ca.Function("f", [x], [ca.diag(x)], ["x"], ["D"])
    with pytest.raises(InputError, match=r"'f' output 0 \(D\) is a sparse 2x2"):
        FastCall(f)
    v = ca.SX(3, 1)                       # a structural zero in the middle: its 2 nonzeros
    v[0], v[2] = x[0], x[1]               # would pass for the 3-vector
    with pytest.raises(InputError, match=r"'c' output 0 \(v\) is a sparse 3x1"):
        FastCall(ca.Function("c", [x], [v], ["x"], ["v"]))
    assert np.array_equal(evaluate(f, [1.0, 2.0])[0], np.diag([1.0, 2.0]))
    call = FastCall(ca.Function("g", [x], [ca.densify(ca.diag(x))]))
    call.inputs[0][:] = [1.0, 2.0]
    assert np.array_equal(call()[0], np.diag([1.0, 2.0]))


@pytest.mark.parametrize("n", [0, 1, 2, 3, 5, 8, 1000, 20001])
def test_filled_rows_equal_numpys_broadcast_for_every_length(n):
    rng = np.random.default_rng(n)
    for k in (1, 3, 14):
        row = rng.normal(size=k) * np.array([1e300, -0.0, 5e-324, 1.0] * 4)[:k]
        want = np.empty((n, k))
        want[:] = row
        assert repeated_row(row, n).tobytes() == want.tobytes()
        out = np.full((n + 4, k), np.nan)
        fill_rows(out[2:n + 2], row)         # a view: the rows around it untouched
        assert np.isnan(out[:2]).all() and np.isnan(out[n + 2:]).all()
        assert out[2:n + 2].tobytes() == want.tobytes()


def test_the_schedules_cog_rows_equal_the_broadcast_sum():
    cog = CogProfile([(0.5, (0.02, -0.01, 0.0), 0.0), (1.0, (0.0, 0.03, 0.01), 0.4)])
    s = Schedule.build(quadcog.Hover(), 2.0, 1e-3, cog)
    r = np.array([0.01, -0.0, -0.02])
    assert s.r_G(r).tobytes() == (r[None, :] + s.cog).tobytes()
    assert s.r_G(r) is not s.r_G(r)         # a new array each time: _result adds to it in place


def test_a_flights_outputs_are_disjoint_views_of_the_right_shapes():
    X, U, e, codes = _outputs(7, 15)
    assert X.shape == (8, 15) and U.shape == (8, 4) and e.shape == (8,) and codes.shape == (7,)
    for i, a in enumerate((X, U, e, codes)):
        a[...] = i
        assert a.flags.c_contiguous and a.dtype == np.float64
    assert (X == 0).all() and (U == 1).all() and (e == 2).all() and (codes == 3).all()


class _Parts(quadcog.trajectories.analytic.Trajectory):
    """A constant position (a broadcast view, the row shortcut) and a velocity that varies."""

    def __init__(self, position, speed_at):
        self.position, self.speed_at = position, speed_at

    def _pvaj(self, t):
        p = np.broadcast_to(np.asarray(self.position, float), (t.size, 3))
        v = np.zeros((t.size, 3))
        v[:, 1] = [self.speed_at(x) for x in t]
        zero = np.broadcast_to(np.zeros(3), (t.size, 3))
        return p, v, zero, zero


@pytest.mark.parametrize("position, speed_at, where", [
    ((0.0, 2e300, 1.0), lambda t: 1.0, "y at t = 0.0 s is 2e+300"),
    ((0.0, 0.0, 1.0), lambda t: np.nan if t >= 0.3 else t, "vy at t = 0.3 s is nan"),
    ((0.0, 0.0, 1.0), lambda t: -1e13 if t >= 0.5 else t, "vy at t = 0.5 s is -10000000000000.0")])
def test_a_bad_entry_in_the_constant_row_or_a_varying_column_is_refused(position, speed_at,
                                                                      where):
    with pytest.raises(quadcog.InputError, match=where.replace("+", r"\+")):
        _Parts(position, speed_at).sample(np.arange(10) / 10)
    good = _Parts((0.0, 0.0, 1.0), lambda t: t).sample(np.arange(10) / 10)
    assert good[7, 4] == pytest.approx(0.7) and (good[:, 1] == 0.0).all()

"""The simulator: the two execution paths agree, batches agree with single flights, user
controllers run, divergence is detected and named, bad input is refused."""
from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog import (
    AdaptiveFeedbackLinearization,
    CascadePD,
    CogProfile,
    Disturbance,
    FeedbackLinearization,
    Limits,
    TruthOptions,
    simulate,
    simulate_batch,
)
from quadcog.vehicles.vehicle import HUMMINGBIRD

COG = CogProfile([(0.3, (0.03, -0.02, 0.005), 0.0), (1.0, (0.05, 0.01, 0.0), 0.5)])
PULSE = [Disturbance(t=0.6, duration=0.2, force=(0.5, -0.3, 0.2), moment=(0.01, 0.0, -0.005))]


@pytest.mark.parametrize("controller", [CascadePD, FeedbackLinearization,
                                        AdaptiveFeedbackLinearization])
@pytest.mark.parametrize("truth", [TruthOptions(), TruthOptions(True, True, True)])
def test_paths_agree(controller, truth):
    ctl = controller()
    kw = dict(trajectory=quadcog.Circle(), duration=2.0, cog=COG, disturbances=PULSE, truth=truth,
              vehicle=HUMMINGBIRD.replace(max_rotor_thrust=3.0))
    a = simulate(ctl, path="python", **kw)
    b = simulate(ctl, path="compiled", **kw)
    assert a.x.shape == b.x.shape == (2001, 12)
    assert_close(a.x, b.x, 1e-9, "state")
    assert_close(a.U, b.U, 1e-9, "input")
    assert_close(a.r_hat, b.r_hat, 1e-9, "r_hat")
    assert_close(a.r_G, b.r_G, 0, "r_G")


def test_cog_profile_and_disturbance_act():
    ctl = FeedbackLinearization()
    calm = simulate(ctl, "hover", duration=2.0)
    hit = simulate(ctl, "hover", duration=2.0, disturbances=PULSE)
    assert calm.metrics.max_position_error < 1e-9
    assert hit.metrics.max_position_error > 1e-3
    res = simulate(ctl, "hover", duration=2.0, cog=COG)
    assert_close(res.r_G[res.t < 0.3], np.zeros((300, 3)), 0, "r_G before the first change")
    assert_close(res.r_G[np.searchsorted(res.t, 0.5)], [0.03, -0.02, 0.005], 0, "step")
    assert_close(res.r_G[np.searchsorted(res.t, 1.25)], [0.04, -0.005, 0.0025], 1e-12, "ramp")
    assert_close(res.r_G[-1], [0.05, 0.01, 0.0], 1e-15, "after the ramp")


def test_truth_options_change_the_flight():
    ctl = CascadePD()
    kw = dict(trajectory="hover", duration=1.0, cog=CogProfile.step(0.1, (0.08, 0.0, 0.0)))
    base = simulate(ctl, **kw)
    pa = simulate(ctl, truth=TruthOptions(parallel_axis=True), **kw)
    weak = HUMMINGBIRD.replace(max_rotor_thrust=2.0)
    sat = simulate(ctl, vehicle=weak, truth=TruthOptions(rotor_saturation=True), **kw)
    assert np.max(np.abs(base.x - pa.x)) > 1e-4
    f = np.linalg.solve(HUMMINGBIRD.mixer(), sat.U.T)
    assert f.min() >= -1e-12 and f.max() <= 2.0 + 1e-12
    n = min(len(base.t), len(sat.t))
    assert np.max(np.abs(base.x[:n] - sat.x[:n])) > 1e-4
    f_base = np.linalg.solve(HUMMINGBIRD.mixer(), base.U.T)
    assert f_base.max() > 2.0, "the saturation test did not saturate"


def test_parallel_axis_is_neutral_at_zero_offset():
    ctl = FeedbackLinearization()
    a = simulate(ctl, "circle", duration=1.0)
    b = simulate(ctl, "circle", duration=1.0, truth=TruthOptions(parallel_axis=True))
    assert_close(a.x, b.x, 1e-12, "parallel axis with r_G = 0")


def test_user_python_controller():
    """A user's controller has the built-ins' protocol: ctrl(t, x, ref, c) -> U or (U, c_dot)."""
    p = quadcog.default_parameters()
    m, g = p[0], p[1]

    def hover_pd(t, x, ref, c):   # a user's own attitude and altitude PD, no position loop
        return np.array([m * g - 3.0 * (x[2] - ref[2]) - 2.0 * x[8],
                         -0.05 * x[3] - 0.01 * x[9], -0.05 * x[4] - 0.01 * x[10],
                         -0.02 * x[5] - 0.01 * x[11]])

    x0 = np.zeros(12)
    x0[2], x0[3] = 1.2, 0.1
    res = simulate(hover_pd, quadcog.Hover(position=(0, 0, 1.5)), duration=5.0, path="python",
                   x0=x0)
    assert not res.diverged
    assert abs(res.x[-1, 2] - 1.5) < 0.02 and abs(res.x[-1, 3]) < 0.01     # it saw the reference
    assert res.controller == "hover_pd"

    class Ramp:                   # a state: c_dot = 2 per second, from c0 = 0.5
        n_state, estimates_cog, name = 3, True, "ramp"

        def initial_state(self):
            return np.full(3, 0.5)

        def __call__(self, t, x, ref, c):
            return hover_pd(t, x, ref, c), np.full(3, 2.0)

    res = simulate(Ramp(), "hover", duration=0.5, path="python")
    assert_close(res.r_hat[-1], np.full(3, 1.5), 1e-12, "user controller state")
    with pytest.raises(quadcog.InputError, match="path='python'"):
        simulate(hover_pd, "hover", duration=1.0)
    with pytest.raises(quadcog.InputError, match=r"controller output at t = 0.0 s: expected "
                                                 r"an array of shape \(4,\), got shape \(3,\)"):
        simulate(lambda t, x, ref, c: np.zeros(3), "hover", duration=1.0, path="python")


class _User:
    """A user's controller with a state of 2, built from keyword overrides."""
    n_state = 2

    def __init__(self, **methods):
        self.__dict__.update(methods)

    def initial_state(self):
        return np.zeros(2)

    def __call__(self, t, x, ref, c):
        return np.zeros(4), np.ones(2)


@pytest.mark.parametrize("controller, message", [
    (lambda t, x: np.zeros(4), r"controller raised TypeError at t = 0.0 s: .* \(a Python "
                               r"controller is called as ctrl\(t, x, ref, c\)\)"),
    (_User(n_state="2"), r"controller.n_state: expected an integer in \[0, 10000\], got '2'"),
    (_User(initial_state=lambda: 1 / 0), r"controller.initial_state\(\) raised "
                                         r"ZeroDivisionError at the start"),
    (_User(initial_state=lambda: [1.0, 2.0, 3.0]),
     r"controller.initial_state\(\): expected an array of shape \(2,\), got shape \(3,\)"),
    (_User(project_numpy=lambda c: 1 / 0), r"controller.project_numpy raised ZeroDivisionError "
                                          r"at t = 0.001 s"),
    (_User(project_numpy=lambda c: c * np.nan), r"controller.project_numpy output at t = 0.001 "
                                               r"s: expected 2 finite numbers, got \[nan, nan\]"),
    (lambda t, x, ref, c: (np.zeros(4), np.zeros(3)),
     r"controller output c_dot at t = 0.0 s: expected an array of shape \(0,\)"),
], ids=["old protocol", "n_state", "initial_state raises", "initial_state shape",
        "project raises", "project nan", "c_dot shape"])
def test_user_controller_faults_are_named(controller, message):
    """Whatever a user's controller does wrong comes back as an InputError naming the part and
    the time, never a raw traceback and never a NaN in the result."""
    with pytest.raises(quadcog.InputError, match=message):
        simulate(controller, "hover", duration=0.01, path="python")


@pytest.mark.parametrize("path", ["python", "compiled"])
def test_divergence_detected_and_named(path):
    cog = CogProfile.step(0.2, (0.06, 0.06, 0.0))
    res = simulate(AdaptiveFeedbackLinearization(gamma=0.2, projection_radius=None), "hover", duration=10.0, cog=cog,
                   path=path)
    m = res.metrics
    assert m.diverged and 0.2 < m.diverged_at < 10.0
    assert m.diverged_cause in (quadcog.DivergenceCause.TILT,
                                quadcog.DivergenceCause.POSITION_ERROR)
    assert m.diverged_reason == m.diverged_cause.describe(quadcog.Limits())
    assert m.rms_position_error_tail == np.inf
    assert np.isfinite(res.x).all() and np.isfinite(res.U).all()
    assert res.t[-1] == pytest.approx(m.diverged_at)
    assert res.t.size < 10001


def test_divergence_non_finite_and_position():
    with pytest.raises(quadcog.InputError, match=r"controller output at t = 0.0 s: expected 4 "
                                                 r"finite numbers, got \[nan, 0.0, 0.0, 0.0\]"):
        simulate(lambda t, x, ref, c: np.array([np.nan, 0, 0, 0]), "hover", duration=1.0,
                 path="python")
    crazy = simulate(lambda t, x, ref, c: np.array([1e200, 0, 0, 0]), "hover", duration=1.0,
                     path="python")
    assert crazy.metrics.diverged_cause == quadcog.DivergenceCause.NON_FINITE
    assert crazy.metrics.diverged_reason.startswith("non-finite state")
    assert crazy.metrics.diverged_at == 0.001
    assert np.isfinite(crazy.x).all() and np.isfinite(crazy.U).all()
    rocket = simulate(lambda t, x, ref, c: np.array([40.0, 0, 0, 0]), "hover", duration=5.0,
                      path="python")
    assert rocket.metrics.diverged_reason == "position error over 10 m"
    assert rocket.metrics.as_dict()["diverged_cause"] == "position_error"
    # the metrics count the samples before the divergence: the error was under the limit
    assert rocket.metrics.max_position_error <= 10.0 < np.linalg.norm(rocket.x[-1, :3]
                                                                       - rocket.ref[-1, :3])


def test_euler_singularity_named():
    flip = lambda t, x, ref, c: np.array([6.0, 0.0, 0.2, 0.0])
    with pytest.raises(quadcog.EulerSingularityError, match="reached pi/2"):
        simulate(flip, "hover", duration=3.0, path="python",
                 limits=Limits(max_tilt=np.radians(100)))
    res = simulate(flip, "hover", duration=3.0, path="python")
    assert res.metrics.diverged_reason == "|phi| or |theta| over 85 deg"


def test_batch_agrees_with_single_flights():
    ctl = AdaptiveFeedbackLinearization()
    vehicles = [HUMMINGBIRD.with_cog(r) for r in
                [(0.0, 0.0, 0.0), (0.03, 0.0, 0.0), (0.0, -0.04, 0.01), (0.05, 0.05, 0.0)]]
    batch = simulate_batch(ctl, vehicles, "circle", duration=3.0, threads=2)
    serial = simulate_batch(ctl, vehicles, "circle", duration=3.0, threads=1)
    for b, v in enumerate(vehicles):
        single = simulate(ctl, "circle", duration=3.0, vehicle=v).metrics
        assert batch.rms_position_error[b] == pytest.approx(single.rms_position_error, rel=1e-9)
        assert batch.max_position_error[b] == pytest.approx(single.max_position_error, rel=1e-9)
        assert batch.rms_position_error_tail[b] == pytest.approx(single.rms_position_error_tail,
                                                                 rel=1e-9)
        assert serial.rms_position_error[b] == batch.rms_position_error[b]
    assert not batch.diverged.any()


def test_batch_reports_divergence():
    ctl = AdaptiveFeedbackLinearization(gamma=0.2, projection_radius=None)
    vehicles = [HUMMINGBIRD, HUMMINGBIRD.with_cog((0.06, 0.06, 0.0))]
    res = simulate_batch(ctl, vehicles, "hover", duration=5.0, cog_shape=lambda t: float(t >= 0.2))
    single = simulate(ctl, "hover", duration=5.0, cog=CogProfile.step(0.2, (0.06, 0.06, 0.0)))
    assert list(res.diverged) == [False, True]
    assert res.diverged_at[1] == pytest.approx(single.metrics.diverged_at)


@pytest.mark.parametrize("kwargs, message", [
    (dict(dt=0.0), r"dt: expected a positive number \(s\), got 0.0"),
    (dict(dt=-1e-3), "dt: expected a positive number"),
    (dict(duration=-1.0), "duration: expected a positive number"),
    (dict(dt=0.5, duration=2.0), r"dt = 0.5 s is too large: .* RK4 needs dt < "),
    (dict(x0=np.zeros(5)), r"x0: expected an array of shape \(12,\), got shape \(5,\)"),
    (dict(x0=np.full(12, np.nan)), r"x0\[0\]: expected a finite number, got nan"),
    (dict(vehicle=np.ones(14)), "vehicle: expected a quadcog Vehicle"),
    (dict(trajectory="spiral"), "trajectory: expected one of 'hover', .*, got 'spiral'"),
    (dict(path="fast"), "path: expected one of 'compiled', 'python', got 'fast'"),
    (dict(cog=[(1.0, (0.02, 0, 0), 0.0), (0.5, (0.0, 0, 0), 0.0)]), "expected changes in time order"),
    (dict(cog=[(0.5, (0.2, 0.0, 0.3), 0.0)]), "cog change 0"),
])
def test_bad_input(kwargs, message):
    with pytest.raises(quadcog.InputError, match=message):
        simulate(FeedbackLinearization(), **{"trajectory": "hover", "duration": 2.0, **kwargs})


def test_bad_trajectory_and_disturbance_values():
    with pytest.raises(quadcog.InputError, match="circle radius: expected a positive number, "
                                                 "got -1"):
        quadcog.Circle(radius=-1)
    with pytest.raises(quadcog.InputError, match="disturbance duration: expected a positive "
                                                 "number"):
        Disturbance(t=1.0, duration=0.0)
    with pytest.raises(quadcog.InputError, match=r"hover position: expected 3 finite numbers "
                                                 r"\(m\), got shape \(2,\)"):
        quadcog.Hover(position=(0, 0))


def test_callable_trajectory_derivatives():
    traj = quadcog.FromCallable(lambda t: np.array([np.sin(t), 0.0, 1.0 + 0.1 * t]))
    ref = traj.sample([0.3, 1.0])
    assert_close(ref[:, 3], np.cos([0.3, 1.0]), 1e-6, "velocity")
    assert_close(ref[:, 6], -np.sin([0.3, 1.0]), 1e-5, "acceleration")
    assert_close(ref[:, 9], -np.cos([0.3, 1.0]), 1e-4, "jerk")
    res = simulate(FeedbackLinearization(), traj, duration=2.0)
    assert res.metrics.rms_position_error_tail < 0.05


def test_result_plot_and_progress(tmp_path):
    seen = []
    res = simulate(AdaptiveFeedbackLinearization(), "hover", duration=2.0,
                   cog=CogProfile.step(0.5, (0.03, 0.0, 0.0)), progress=seen.append)
    assert seen and seen[-1] == 1.0 and all(b >= a for a, b in zip(seen, seen[1:]))
    out = tmp_path / "flight.png"
    res.plot(out)
    assert out.stat().st_size > 10_000


def test_config_defaults_are_read_at_call_time():
    """One place for the defaults: changing quadcog.config.defaults changes dt, the divergence
    limits and the tail of the metrics wherever they are not given."""
    from quadcog import config
    from quadcog.sim.result import position_metrics
    t = np.linspace(0.0, 1.0, 11)
    ref = np.zeros((11, 14))
    x = np.zeros((11, 12))
    x[:, 0] = t                       # error grows linearly: e = t
    try:
        config.defaults["metrics.tail_fraction"] = 0.5
        config.defaults["limits.max_position_error"] = 3.0
        config.defaults["limits.max_tilt_deg"] = 30.0
        tail = position_metrics(t, x, ref, 1.0)["rms_position_error_tail"]
        assert np.isclose(tail, np.sqrt(np.mean(t[5:] ** 2)))
        assert quadcog.Limits().max_position_error == 3.0
        assert np.isclose(quadcog.Limits().max_tilt, np.radians(30.0))
        config.defaults["simulate.dt"] = 0.01
        res = simulate(quadcog.FeedbackLinearization(), "hover", duration=0.5)
        assert np.allclose(np.diff(res.t), 0.01)
    finally:
        config.reset_defaults()
    assert np.isclose(position_metrics(t, x, ref, 1.0)["rms_position_error_tail"],
                      np.sqrt(np.mean(t[8:] ** 2)))

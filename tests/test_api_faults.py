"""Issue 10's API reproducers: controllers, trajectories, CoG profiles and disturbances given
arguments of the wrong kind end in an InputError naming the argument, the value and what was
expected."""
import numpy as np
import pytest

import quadcog
from quadcog import (
    AdaptiveFeedbackLinearization,
    CascadePD,
    Circle,
    CogProfile,
    Disturbance,
    FeedbackLinearization,
    FromCallable,
    Hover,
)

NAN = float("nan")


@pytest.mark.parametrize("build, message", [
    (lambda: FeedbackLinearization(max_tilt=NAN),
     r"^max_tilt: expected a number in \(0.0, 1.57\d*\] \(rad\), got nan$"),
    (lambda: FeedbackLinearization(max_tilt=-0.5), r"^max_tilt: .* got -0.5$"),
    (lambda: CascadePD(max_tilt="abc"), r"^max_tilt: .* got 'abc'$"),
    (lambda: FeedbackLinearization(poles_attitude=(NAN, -2)),
     r"^poles_attitude\[0\]: expected a finite pole with negative real part, got nan$"),
    (lambda: FeedbackLinearization(poles_z="ab"), r"^poles_z: expected 2 finite poles"),
    (lambda: FeedbackLinearization(poles_z=(-1 + 1j, -1 + 2j)), r"^poles_z: expected 2 finite "
                                                                r"poles .*conjugate pairs"),
    (lambda: FeedbackLinearization(poles_z=(True, -2)), r"^poles_z\[0\]: expected a real or "
                                                        r"complex number, got True$"),
    (lambda: CascadePD(poles_x=(-3, -3, -3, -3)),
     r"^poles_x: expected poles that can be placed on a single-input chain"),
    (lambda: CascadePD(poles_x=(-1 + 1j, -1 - 1j, -3, -4)), r"^poles_x: expected 4 real"),
    (lambda: CascadePD(poles_z=(-1e300, -2e300)),
     r"^poles_z: expected poles that can be placed on a single-input chain \(poles_z: the "
     r"solution has an entry of about 10\^600"),
    (lambda: AdaptiveFeedbackLinearization(gamma=[0.01, 0.01]),
     r"^gamma: expected a positive number or 3 positive numbers .*, got shape \(2,\)"),
    (lambda: AdaptiveFeedbackLinearization(gamma="fast"), r"^gamma: expected a positive number"),
    (lambda: AdaptiveFeedbackLinearization(projection_radius="abc"),
     r"^projection_radius: expected a positive number \(m\), got 'abc'$"),
    (lambda: AdaptiveFeedbackLinearization(Q=-np.eye(8)), r"^Q: expected a symmetric positive "
                                                          r"definite 8x8 matrix"),
    (lambda: AdaptiveFeedbackLinearization(Q=np.eye(7)), r"^Q: expected an array of shape "
                                                         r"\(8, 8\), got shape \(7, 7\)"),
    (lambda: Circle(period=5e-324), r"^circle period: expected a period of at least"),
    (lambda: Hover(yaw=float("inf")), r"^hover yaw: expected a finite real number \(rad\), "
                                      r"got inf$"),
    (lambda: Hover(position="abc"), r"^hover position: expected 3 finite numbers"),
    (lambda: Circle(radius=1e300).sample([0.0]),
     r"x at t = 0.0 s is 1e\+300; expected finite values within \+-1e\+12"),
    (lambda: FromCallable(lambda t: "abc").sample([0.0]),
     r"^trajectory callable <lambda>\(t = 0.0\): expected a position"),
    (lambda: FromCallable(lambda t: [1.0, 2.0 + 1j, 3.0]).sample([0.0]),
     r"<lambda>\(t = 0.0\)\[1\]: expected a real number, got \(2\+1j\)"),
    (lambda: FromCallable(lambda t: [np.inf, 0, 1]).sample([0.0]),
     r"<lambda>\(t = 0.0\)\[0\]: expected a finite number, got inf"),
    (lambda: FromCallable(lambda t: {}[t]).sample([0.0]), r"raised KeyError"),
    (lambda: CogProfile("abc"), r"^cog: expected a CogProfile or a list"),
    (lambda: CogProfile([(0.5, "abc")]),
     r"^cog change 0: r: expected 3 finite numbers \(m\), got 'abc'"),
    (lambda: quadcog.sim.timeline.wrench_table([None], [0.0]), r"^disturbances\[0\]: expected a "
                                                           r"Disturbance"),
    (lambda: Disturbance(t=0.0, duration=1.0, force=(1e300, 0, 0)),
     r"^disturbance force: expected entries within \+-1e\+06"),
    (lambda: Disturbance(t=True, duration=1.0), r"^disturbance t: expected a number >= 0 \(s\), "
                                                r"got True$"),
    (lambda: quadcog.Limits(max_tilt="x"), r"^Limits.max_tilt: expected a number in \(0.0, "
                                           r"3.14\d*\] \(rad\), got 'x'$"),
    (lambda: quadcog.Limits(max_position_error=NAN), r"^Limits.max_position_error: expected a "
                                                     r"positive number \(m\), got nan$"),
])
def test_bad_arguments(build, message):
    with pytest.raises(quadcog.InputError, match=message) as e:
        build()
    assert "np." not in str(e.value) and "array(" not in str(e.value)


def test_good_arguments_of_numpy_types():
    ctl = FeedbackLinearization(max_tilt=np.float32(0.5), poles_z=np.array([-3.0, -4.0]))
    assert ctl.max_tilt == pytest.approx(0.5) and ctl.kp[0] == pytest.approx(12.0)
    pair = FeedbackLinearization(poles_z=(-2 + 1j, -2 - 1j))
    assert pair.kp[0] == pytest.approx(5.0) and pair.kd[0] == pytest.approx(4.0)   # s^2+4s+5
    adaptive = AdaptiveFeedbackLinearization(gamma=np.array([0.01, 0.02, 0.03]))
    assert adaptive.gamma.tolist() == [0.01, 0.02, 0.03]
    ref = Circle(period=np.int64(8)).sample([0.0])
    assert ref.shape == (1, 14) and ref[0, 0] == pytest.approx(1.0)

"""PX4 in the loop, one short lockstep flight: PX4 (built in quadcog's cache by
`make px4-build`; never built here) arms, takes off to 1.5 m, holds 5 s, lands and disarms on
quadcog's X500; the truth climbs to the mission's height, holds it level, comes back to the
ground near the start; PX4's own ULog is written and reads back, in the plant's frame, as
the altitude the truth flew. Skips without the build."""
import numpy as np
import pytest

from quadcog.errors import Px4Error

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def flight(tmp_path_factory):
    pytest.importorskip("pymavlink")
    from quadcog.px4.tree import cached_build
    try:
        built = cached_build()
    except Px4Error as e:
        pytest.skip(f"no PX4 tree ({e}); set-up: make px4-build")
    if built is None:
        pytest.skip("PX4 is not built in quadcog's cache; set-up: make px4-build")
    from quadcog.px4 import fly, scenario_path
    out = tmp_path_factory.mktemp("px4") / "hover"
    return fly(scenario_path("px4-hover"), out=out, allow_build=False,
               overrides=("duration=5.0", "trajectory.position=[0.0, 0.0, 1.5]")), out


def test_px4_arms_takes_off_holds_lands(flight):
    f, _ = flight
    r = f.recording
    assert not f.partial, r.reason
    assert r.armed_at is not None and r.disarmed_at is not None and r.disarmed_at > r.armed_at
    texts = " ".join(s for _, s in r.statustext)
    assert "Takeoff detected" in texts and "Landing detected" in texts
    x = f.result.x
    assert abs(x[:, 2].max() - 1.5) < 0.25               # climbed to the mission's height
    airborne = x[:, 2] > 1.2
    assert np.degrees(np.abs(x[airborne, 3:5])).max() < 10.0    # level while holding
    assert x[-1, 2] == 0.0 and np.hypot(*x[-1, :2]) < 1.0      # back on the ground
    assert f.speed > 1.0                                  # faster than real time, loaded or not


def test_px4_ulog_reads_back_in_the_plants_frame(flight):
    f, out = flight
    from quadcog.logs import read_log
    assert (out / "px4.ulg").is_file() and (out / "metrics.json").is_file()
    log = read_log(out / "px4.ulg")
    z_est = log.signal("position")[:, 2]
    assert abs(z_est.max() - f.result.x[:, 2].max()) < 0.2   # PX4's EKF2 against the truth


def test_px4_setpoint_reads_back_as_the_hold_point(flight):
    """The position setpoint PX4's position controller tracked (its ULog's
    vehicle_local_position_setpoint, moved from EKF2's origin to the plant's, at the plant's
    times) is the mission's hold point over home, 1.5 m up (up to PX4's own error of home's
    altitude, from the barometer), and the truth holds within centimetres of it; the
    side-by-side table measures PX4's error against it."""
    f, out = flight
    from quadcog.px4.compare import setpoint_reference
    sp = setpoint_reference(out / "px4.ulg", f.result.t)
    assert sp.shape == (f.result.t.size, 3)
    holding = (f.result.x[:, 2] > 1.0) & np.isfinite(sp).all(axis=1)
    assert holding.sum() > 3000                            # > 3 s of samples at 1 ms
    assert np.allclose(np.median(sp[holding], axis=0), (0.0, 0.0, 1.5), atol=0.2)
    assert np.allclose(np.median(sp[holding, :2], axis=0), 0.0, atol=0.05)   # EKF2's origin
    x = f.result.x[holding, :3]
    assert np.median(np.linalg.norm(x - sp[holding], axis=1)) < 0.1

"""PX4 in the loop, identification on the ULogs PX4's own logger wrote: the X500 picks up a
0.3 kg parcel off-centre in flight; `quadcog.identify` on PX4's log (after the pickup) against
a flight without the parcel finds the whole body's CoG shift within 2 mm and its mass within
3 % of what the plant flew, and on a second flight without the parcel no shift. Two short
flights; skips without `make px4-build`."""
import numpy as np
import pytest

from quadcog.errors import Px4Error

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def flights():
    pytest.importorskip("pymavlink")
    from quadcog.px4.tree import cached_build
    try:
        built = cached_build()
    except Px4Error as e:
        pytest.skip(f"no PX4 tree ({e}); set-up: make px4-build")
    if built is None:
        pytest.skip("PX4 is not built in quadcog's cache; set-up: make px4-build")
    from quadcog.px4 import fly, scenario_path
    short = ("duration=22.0", "payload[0].t=10.0")
    run = lambda extra, seed: fly(scenario_path("px4-payload"), allow_build=False,  # noqa: E731
                                  overrides=short + extra + (f"sensing.seed={seed}",))
    return run((), 1), run(("payload=[]",), 2), run(("payload=[]",), 3)


def test_shift_and_mass_of_a_parcel_picked_up_in_flight(flights):
    from quadcog.px4.identify import identify_flight
    with_parcel, baseline, _ = flights
    assert not with_parcel.partial and not baseline.partial
    r = identify_flight(with_parcel, baseline)
    # the plant's truth: 0.3 kg at (8, 4) cm on a 2 kg airframe -> (10.4, 5.2) mm, 2.3 kg
    assert np.allclose(r.true_shift[:2], (0.3 * 0.08 / 2.3, 0.3 * 0.04 / 2.3), atol=1e-5)
    found = np.array(r.identification.r_G[:2])
    assert np.abs(found - np.array(r.true_shift[:2])).max() < 0.002
    assert abs(r.identification.mass - 2.3) / 2.3 < 0.03
    assert r.identification.mass_change == pytest.approx(0.3, abs=0.069)


def test_no_shift_where_nothing_changed(flights):
    from quadcog.px4.identify import identify_flight
    _, baseline, again = flights
    r = identify_flight(again, baseline)
    assert np.abs(r.identification.r_G[:2]).max() < 0.002
    assert abs(r.identification.mass - 2.0) / 2.0 < 0.03

"""simulate_batch refuses bad arguments before any flight, with a typed error that names the
argument (a wrong kind used to reach numpy or CasADi, or run with a nonsense thread count)."""
import pytest

import quadcog
from quadcog import HUMMINGBIRD, CascadePD, simulate_batch

BAD = [
    ({"threads": "two"}, "threads"),
    ({"threads": 0}, "threads"),
    ({"threads": 2.0}, "threads"),
    ({"threads": True}, "threads"),
    ({"vehicles": []}, "vehicles"),
    ({"vehicles": "abc"}, "vehicles"),
    ({"vehicles": [None]}, "vehicles"),
    ({"truth": "abc"}, "truth"),
    ({"limits": "abc"}, "limits"),
    ({"progress": 5}, "progress"),
    ({"cog_shape": "abc"}, "cog_shape"),
    ({"cog_shape": lambda t: "x"}, "cog_shape"),
    ({"cog_shape": lambda t: float("nan")}, "cog_shape"),
    ({"controller": "pd"}, "controller"),
    ({"duration": -1.0}, "duration"),
]


@pytest.mark.parametrize("change,name", BAD, ids=[f"{n}-{i}" for i, (_, n) in enumerate(BAD)])
def test_bad_batch_argument_names_it(change, name):
    args = dict(controller=CascadePD(), vehicles=[HUMMINGBIRD.with_cog((0.01, 0.0, 0.0))],
                duration=0.01)
    args.update(change)
    with pytest.raises(quadcog.InputError, match=name):
        simulate_batch(**args)


@pytest.mark.parametrize("cog", [float("nan"), "abc", 3, {"t": 1.0}])
def test_simulate_refuses_a_cog_of_the_wrong_kind(cog):
    # found by the property suite: a NaN float reached list() and raised a raw TypeError
    with pytest.raises(quadcog.InputError, match="cog"):
        quadcog.simulate(CascadePD(), "hover", duration=0.01, cog=cog)

"""A CogChange made directly is checked as the CogProfile checks its changes: CogChange(b"abc",
"xyz") was kept as is (r = (97.0, 98.0, 99.0) m from bytes, a string time), and failed, or
flew, only later."""
import numpy as np
import pytest

from quadcog import CogChange, CogProfile, InputError


@pytest.mark.parametrize("args, where", [
    (("abc", (0.0, 0.0, 0.0)), "t"), ((b"1", (0.0, 0.0, 0.0)), "t"),
    ((-1.0, (0.0, 0.0, 0.0)), "t"), ((float("nan"), (0.0, 0.0, 0.0)), "t"),
    ((1.0, b"abc"), "r"), ((1.0, "xyz"), "r"), ((1.0, memoryview(b"abc")), "r"),
    ((1.0, 0.5), "r"), ((1.0, (0.0, float("inf"), 0.0)), "r"), ((1.0, {"a": 1}), "r"),
    ((1.0, (0.0, 0.0, 0.0), -0.5), "ramp"), ((1.0, (0.0, 0.0, 0.0), 1j), "ramp"),
    ((1e308, (0.0, 0.0, 0.0), 1e308), "ramp"),
])
def test_a_change_that_is_not_one_is_refused_when_made(args, where):
    with pytest.raises(InputError, match=rf"^CogChange: {where}(\[\d\])?: expected"):
        CogChange(*args)


def test_a_change_is_kept_in_plain_floats():
    c = CogChange(np.float32(0.5), np.array([0.01, 0.0, -0.02]), np.int64(1))
    assert c == CogChange(0.5, (0.01, 0.0, -0.02), 1.0)
    assert all(type(v) is float for v in (c.t, c.ramp, *c.r))
    assert CogProfile([c]).changes == [c]


def test_the_profile_names_its_change():
    with pytest.raises(InputError, match=r"^cog change 1: r: expected 3 finite numbers"):
        CogProfile([(0.5, (0.01, 0.0, 0.0)), (1.0, "abc")])
    with pytest.raises(InputError, match=r"^cog change 0: expected a table with keys t, r"):
        CogProfile([{"t": 1.0, "r": (0.0, 0.0, 0.0), "rmp": 1.0}])

"""The shared checks of quadcog.validate and the admissibility margin of quadcog.model.parameters."""
import numpy as np
import pytest

import quadcog
from quadcog import validate as v
from quadcog.model.conventions import IDX
from quadcog.model.parameters import MARGIN, admissible_radius, inertia_ratio, is_admissible

BASE = quadcog.HUMMINGBIRD.parameters()


@pytest.mark.parametrize("value", [3, 3.0, np.int64(3), np.int8(3), np.uint16(3), np.float32(3),
                                   np.float64(3), np.array(3.0)])
def test_real_accepts_every_real_number_type(value):
    out = v.real(value, "duration")
    assert type(out) is float and out == 3.0


@pytest.mark.parametrize("value, shown", [
    (True, "True"), (np.bool_(False), "False"), ("1", "'1'"), (b"1", "b'1'"), (None, "None"),
    (1 + 2j, "(1+2j)"), (np.complex128(1), "(1+0j)"), (10 ** 400, "an integer of 401 digits"),
    (-(10 ** 400), "an integer of 401 digits"), (float("nan"), "nan"), (np.float64("-inf"), "-inf"),
    ([1.0], "[1.0]"), ({}, "a table"), (np.array([1.0, 2.0]), "[1.0, 2.0]")])
def test_real_refuses_what_is_not_a_finite_real_number(value, shown):
    with pytest.raises(quadcog.InputError) as e:
        v.real(value, "duration")
    assert str(e.value) == f"duration: expected a finite real number, got {shown}"


def test_bounds_and_plain_numbers_in_messages():
    assert v.positive(np.float64(1e-9), "dt") == 1e-9
    assert v.nonnegative(0, "ramp") == 0.0
    for bad in (0.0, -1e-300, np.float64(-1.5)):
        with pytest.raises(quadcog.InputError, match=r"^dt: expected a positive number \(s\), "
                                                     r"got -?[0-9.e+-]+$") as e:
            v.positive(bad, "dt", unit="s")
        assert "np." not in str(e.value) and "float64" not in str(e.value)
    with pytest.raises(quadcog.InputError, match=r"ramp: expected a number >= 0, got -1.0"):
        v.nonnegative(-1.0, "ramp")
    with pytest.raises(quadcog.InputError, match=r"x: expected a number in \[0, 1\), got 1"):
        v.real(1, "x", lo=0, hi=1, hi_open=True)
    assert v.real(0, "x", lo=0, hi=1, hi_open=True) == 0.0
    with pytest.raises(quadcog.InputError, match=r"x: expected a number > 0.5, got 0.5"):
        v.real(0.5, "x", lo=0.5, lo_open=True)


def test_error_class_is_the_callers():
    class MyError(quadcog.InputError):
        pass
    with pytest.raises(MyError, match="^f.toml: key 'dt': expected a positive number"):
        v.positive("fast", "f.toml: key 'dt'", error=MyError)


def test_integer_and_flag():
    assert v.integer(np.int32(2), "threads", lo=1) == 2
    for bad in ("two", 2.0, True, None, 0):
        with pytest.raises(quadcog.InputError, match="threads: expected an integer >= 1"):
            v.integer(bad, "threads", lo=1)
    assert v.flag(np.bool_(True), "parallel_axis") is True
    for bad in (1, 0, "true", None):
        with pytest.raises(quadcog.InputError, match="parallel_axis: expected true or false"):
            v.flag(bad, "parallel_axis")


@pytest.mark.parametrize("value, shown", [({}, "a table"), (["hover"], "['hover']"),
                                          ("Hover", "'Hover'"), (1, "1"), (None, "None")])
def test_choice_refuses_unhashable_and_near_misses(value, shown):
    with pytest.raises(quadcog.InputError) as e:
        v.choice(value, "trajectory.kind", ("hover", "circle"))
    assert str(e.value) == f"trajectory.kind: expected one of 'hover', 'circle', got {shown}"
    assert v.choice("circle", "kind", ("hover", "circle")) == "circle"
    with pytest.raises(quadcog.InputError):
        v.choice(1, "flag", (True, False))      # 1 == True in Python, but not here


def test_arrays():
    a = v.array([[1, 2], [3, 4.5]], "M", (2, 2))
    assert a.dtype == float and a.tolist() == [[1.0, 2.0], [3.0, 4.5]]
    assert v.array(np.zeros((5, 14), dtype=np.int16), "params", (None, 14)).shape == (5, 14)
    assert v.vector(np.ones((3, 1)), "r", 3).shape == (3,)
    cases = [
        (([[1, 2], [3]], "M", (2, 2)), "M: expected an array of shape (2, 2) (a rectangular "
                                       "array; the rows differ in length), got [[1, 2], [3]]"),
        (([1, True, 3], "r", (3,)), "r[1]: expected a real number, got True"),
        (([0.0, "a", 1.0], "r", (3,)), "r[1]: expected a real number, got 'a'"),
        (([[0.0, None]], "r", None), "r[0, 1]: expected a real number, got None"),
        (([1, 10 ** 400, 0], "r", (3,)), "r[1]: expected a number within the float range, "
                                         "got an integer of 401 digits"),
        ((np.array([1 + 1j, 0, 0]), "r", (3,)), "r: expected an array of shape (3,) of real "
                                                "numbers, not complex numbers, got "
                                                "[(1+1j), 0j, 0j]"),
        ((np.array([True, False, True]), "r", (3,)), "r: expected an array of shape (3,) of "
                                                     "real numbers, not booleans, got "
                                                     "[True, False, True]"),
        (("abc", "r", (3,)), "r: expected an array of shape (3,), got 'abc'"),
        ((np.zeros((2, 13)), "params", (None, 14)), "params: expected an array of shape "
                                                    "(any, 14), got shape (2, 13)"),
        (([1.0, np.nan, 3.0], "r", (3,)), "r[1]: expected a finite number, got nan"),
        ((np.array([[0, 0], [0, np.inf]]), "M", (2, 2)), "M[1, 1]: expected a finite "
                                                         "number, got inf"),
    ]
    for args, message in cases:
        with pytest.raises(quadcog.InputError) as e:
            v.array(*args)
        assert str(e.value) == message
    with pytest.raises(quadcog.InputError, match=r"r: expected an array of shape \(3,\), "
                                                 r"got shape \(4,\)"):
        v.vector(np.zeros(4), "r", 3)


def test_step_count_bound():
    assert v.step_count(20.0, 1e-3, 10 ** 7) == 20000
    with pytest.raises(quadcog.InputError) as e:
        v.step_count(20.0, 1e-9, 10 ** 7)
    msg = str(e.value)
    # 2e10 steps at BYTES_PER_STEP each, in TiB (independent arithmetic)
    tib = 2e10 * v.BYTES_PER_STEP / 2 ** 40
    assert "duration / dt = 20.0 s / 1e-09 s gives 2e+10 steps" in msg
    assert f"about {tib:.3g} TiB" in msg and "at most 10,000,000 steps" in msg
    for duration, dt in ((1.0, 5e-324), (1e20, 1e-3)):
        with pytest.raises(quadcog.InputError, match="expected at most 10,000,000 steps"):
            v.step_count(duration, dt, 10 ** 7, "a.toml")


def test_inertia_ratio_against_the_principal_moments():
    """For an offset along x, I_G = diag(Ixx, Iyy - m x^2, Izz - m x^2) (parallel axis), so
    the ratio is min over the axes of (I_i - m x^2) / I_i."""
    m, Iyy, Izz = BASE[IDX["m"]], BASE[IDX["Iyy"]], BASE[IDX["Izz"]]
    for x in (0.0, 0.03, 0.08, 0.1, 0.12):
        p = BASE.copy()
        p[IDX["x_G"]] = x
        expected = min(1.0, (Iyy - m * x * x) / Iyy, (Izz - m * x * x) / Izz)
        assert inertia_ratio(p) == pytest.approx(expected, rel=1e-12, abs=1e-15)


def test_admissibility_margin_at_the_rim(model):
    # 1 ulp inside the rim (issue 10): used to be accepted, and dynamics returned NaN
    for key in ("x_G", "z_G"):
        with pytest.raises(quadcog.ParameterError, match=r"keeps only .* of I_O in its weakest "
                                                         r"direction \(expected >= 0.01"):
            quadcog.default_parameters(**{key: 0.10145993123917846})
    rho = admissible_radius(BASE)
    assert rho == pytest.approx(np.sqrt((1 - MARGIN) * 0.007 / 0.68), rel=1e-12)
    rng = np.random.default_rng(4)
    for u in rng.normal(size=(50, 3)):
        u /= np.linalg.norm(u)
        p = quadcog.with_cog(BASE, 0.999 * rho * u)
        assert is_admissible(p)
        p = quadcog.check_parameters(p)
        # on the admissible side, M^-1 (block elimination) is accurate: compare with LAPACK
        M, M_inv = model.mass_matrix(p), model.inverse_mass_matrix(p)
        assert np.abs(M_inv @ M - np.eye(6)).max() < 1e-9
        x = np.zeros(12)
        assert np.isfinite(model.dynamics(x, [6.0, 0, 0, 0], p)).all()
    # along the weakest axis (x or y for this vehicle), just beyond the radius: refused
    assert not is_admissible(quadcog.with_cog(BASE, (1.001 * rho, 0, 0)))
    with pytest.raises(quadcog.ParameterError):
        quadcog.default_parameters(y_G=1.001 * rho)


@pytest.mark.parametrize("override, message", [
    ({"y_G": 1e308}, "r_G = .* too far"), ({"x_G": -1e200}, "r_G = .* too far"),
    ({"Izz": 5e-324}, r"Izz = 5e-324 is out of scale: expected a number in \[1e-09, 1e\+06\]"),
    ({"c_y": 1e308}, r"c_y = 1e\+308 is out of scale: expected a number in \[0, 1e\+06\]")])
def test_extreme_parameters_are_typed_errors(override, message):
    with pytest.raises(quadcog.ParameterError, match=message):
        quadcog.default_parameters(**override)
    quadcog.default_parameters(Ixx=1.4e-5, Iyy=1.4e-5, Izz=2.2e-5, m=0.027)   # a Crazyflie


@pytest.mark.parametrize("value", ["abc", True, 1 + 0j, 10 ** 400, None],
                         ids=["str", "bool", "complex", "huge-int", "None"])
def test_parameter_values_of_the_wrong_kind(value):
    with pytest.raises(quadcog.ParameterError, match="^m: expected a finite real number"):
        quadcog.default_parameters(m=value)
    p = BASE.astype(object)
    p[0] = value
    with pytest.raises(quadcog.ParameterError,
                       match=r"^p\[0\]: expected a (real number|number within the float range)"):
        quadcog.check_parameters(list(p))


@pytest.mark.parametrize("kwargs", [dict(duration=20.0, dt=1e-9), dict(duration=1e20),
                                    dict(duration=1.0, dt=5e-324)])
def test_simulate_refuses_absurd_step_counts_before_allocating(kwargs):
    with pytest.raises(quadcog.InputError, match="expected at most 10,000,000 steps"):
        quadcog.simulate(quadcog.FeedbackLinearization(), "hover", **kwargs)


def test_simulate_time_arguments_of_the_wrong_kind():
    ctl = quadcog.FeedbackLinearization()
    with pytest.raises(quadcog.InputError, match=r"^duration: expected a positive number \(s\), "
                                                 r"got True$"):
        quadcog.simulate(ctl, "hover", duration=True)
    res = quadcog.simulate(ctl, "hover", duration=np.int64(1), dt=np.float32(0.001))
    assert res.t[-1] == pytest.approx(1.0, abs=1e-6)

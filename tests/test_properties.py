"""Property tests of bad input (hypothesis, derandomized): mutated shipped scenarios and public
API calls with hostile arguments must end in a quadcog error or in a result whose arrays are
finite (a divergence is flagged in the metrics). Any other exception fails the test."""
import copy
import datetime
import tempfile
import tomllib

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
import numpy as np
import pytest

import quadcog
from quadcog.errors import QuadcogError
from quadcog.scenarios.lookup import scenario_names, scenario_path
from quadcog.scenarios.scenario import parse

# hypothesis caches under .hypothesis/ even without a database: keep the checkout clean
set_hypothesis_home_dir(tempfile.mkdtemp(prefix="quadcog-hypothesis-"))
SETTINGS = dict(derandomize=True, database=None, deadline=None, print_blob=True,
                suppress_health_check=list(HealthCheck))

NUMBERS = st.sampled_from([0, -1, 1, 2, 10 ** 400, -(10 ** 400), 0.0, -0.0, 1e-9, 5e-324, 1e20,
                           1e308, -1e308, float("nan"), float("inf"), -float("inf"), 0.05, 3.0])
TOML_SCALARS = st.one_of(NUMBERS, st.booleans(), st.text(max_size=4),
                         st.just(datetime.date(2020, 1, 1)),
                         st.floats(allow_nan=True, allow_infinity=True), st.integers())
TOML_VALUES = st.recursive(TOML_SCALARS, lambda inner: st.one_of(
    st.lists(inner, max_size=4), st.dictionaries(st.text(max_size=3), inner, max_size=3)),
    max_leaves=6)
HOSTILE = st.one_of(TOML_VALUES, st.just(None), st.complex_numbers(), st.just(np.float64("nan")),
                    st.just(np.array([1.0, 2.0])), st.just(np.int64(1)), st.just(object()))

SHIPPED = {name: tomllib.loads(scenario_path(name).read_text()) for name in scenario_names()}


def _paths(value, prefix=()):
    """Every key path of a parsed TOML document (tables and arrays)."""
    out = [prefix] if prefix else []
    if isinstance(value, dict):
        for k, v in value.items():
            out += _paths(v, prefix + (k,))
    elif isinstance(value, list):
        for i, v in enumerate(value):
            out += _paths(v, prefix + (i,))
    return out


def _set(doc, path, value, delete=False):
    target = doc
    for k in path[:-1]:
        target = target[k]
    if delete and isinstance(target, dict):
        del target[path[-1]]
    else:
        target[path[-1]] = value


@pytest.mark.slow
@settings(max_examples=250, **SETTINGS)
@given(st.sampled_from(sorted(SHIPPED)), st.data())
def test_mutated_scenarios_parse_or_give_scenario_errors(name, data):
    doc = copy.deepcopy(SHIPPED[name])
    for _ in range(data.draw(st.integers(1, 3))):
        paths = _paths(doc)
        path = data.draw(st.sampled_from(paths)) if paths else ("extra",)
        op = data.draw(st.sampled_from(["set", "delete", "add"]))
        if op == "add":
            path = path[:-1] + (data.draw(st.text(min_size=1, max_size=4)),)
        try:
            _set(doc, path, data.draw(TOML_VALUES), delete=op == "delete")
        except (TypeError, IndexError, KeyError):     # the parent is no longer a container
            pass
    try:
        parse(doc, f"{name}.toml")
    except QuadcogError:
        pass


def _finite_result(res):
    for a in (res.t, res.x, res.U, res.ref, res.r_hat, res.r_G):
        assert np.isfinite(a).all(), "non-finite output not flagged"


@settings(max_examples=300, **SETTINGS)
@given(st.sampled_from(["real", "positive", "nonnegative", "integer", "flag", "vector",
                        "params", "default_parameters", "fl", "pd", "adaptive", "circle",
                        "hover", "cog", "disturbance"]), HOSTILE, HOSTILE)
def test_api_calls_with_hostile_arguments(kind, a, b):
    v = quadcog.validate
    calls = {
        "real": lambda: v.real(a, "a"), "positive": lambda: v.positive(a, "a"),
        "nonnegative": lambda: v.nonnegative(a, "a"), "integer": lambda: v.integer(a, "a"),
        "flag": lambda: v.flag(a, "a"), "vector": lambda: v.vector(a, "a", 3),
        "params": lambda: quadcog.check_parameters(a),
        "default_parameters": lambda: quadcog.default_parameters(x_G=a, m=b)
        if not isinstance(b, (int, float)) else quadcog.default_parameters(x_G=a),
        "fl": lambda: quadcog.FeedbackLinearization(max_tilt=a, poles_z=b),
        "pd": lambda: quadcog.CascadePD(poles_x=a, max_tilt=b),
        "adaptive": lambda: quadcog.AdaptiveFeedbackLinearization(gamma=a, projection_radius=b),
        "circle": lambda: quadcog.Circle(radius=a, period=b).sample([0.0, 1.0]),
        "hover": lambda: quadcog.Hover(position=a, yaw=b).sample([0.0]),
        "cog": lambda: quadcog.CogProfile([(a, b, 0.0)]).sample([0.0, 1.0]),
        "disturbance": lambda: quadcog.sim.timeline.wrench_table([(a, 1.0, b)], [0.0]),
    }
    try:
        out = calls[kind]()
    except QuadcogError:
        return
    for x in (out if isinstance(out, tuple) else (out,)):
        if isinstance(x, np.ndarray) and x.dtype.kind == "f":
            assert np.isfinite(x).all()


CTL = None


@settings(max_examples=60, **SETTINGS)
@given(st.data())
def test_simulate_with_hostile_arguments(data):
    global CTL
    CTL = CTL or quadcog.FeedbackLinearization()
    good = dict(trajectory="hover", duration=0.05, dt=1e-3)
    kwargs = dict(good)
    for key in data.draw(st.sets(st.sampled_from(
            ["trajectory", "duration", "dt", "cog", "disturbances", "x0", "path", "limits",
             "truth", "progress", "vehicle"]), min_size=1, max_size=3)):
        kwargs[key] = data.draw(st.one_of(HOSTILE, st.sampled_from(
            ["circle", "python", [(0.01, (0.01, 0, 0), 0.0)], np.zeros(12), 1e20, 5e-324])))
    try:
        res = quadcog.simulate(CTL, **kwargs)
    except QuadcogError:
        return
    _finite_result(res)

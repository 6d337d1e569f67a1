"""Seventh hostile pass (issue 33), the public Python API: the model's helpers and ``out=``,
controller settings beyond the float range, aerobatic timescales, quadcog.config.defaults.

Each hostile value must give a typed quadcog error (never a raw exception, a NaN or an inf)."""
import re

import numpy as np
import pytest

import quadcog
from quadcog import config
from quadcog.errors import InputError, QuadcogError
from quadcog.trajectories.aerobatic import BankedCircle, Flip

P = quadcog.HUMMINGBIRD.parameters()
X0, U0 = np.zeros(12), quadcog.hover_trim(P)


def _refused(call, *names):
    """``call()`` raises a QuadcogError whose message names each of ``names``."""
    with pytest.raises(QuadcogError) as info:
        call()
    for name in names:
        assert name in str(info.value), str(info.value)


HOSTILE_ANGLES = [np.nan, np.inf, "a", None, [1.0, 2.0], 1j]


@pytest.mark.parametrize("k", range(3))
@pytest.mark.parametrize("value", HOSTILE_ANGLES, ids=repr)
def test_rotation_matrix_refuses_non_angles(k, value):
    angles = [0.1, 0.2, 0.3]
    angles[k] = value
    _refused(lambda: quadcog.rotation_matrix(*angles), ("phi", "theta", "psi")[k])


def _with(index, value):
    p = P.astype(object).copy()
    p[index] = value
    return p.tolist()


PARAMETER_HELPERS = {
    "hover_trim": lambda p: quadcog.hover_trim(p),
    "inertia_about_cog": lambda p: quadcog.inertia_about_cog(p),
    "with_cog": lambda p: quadcog.with_cog(p, [0.0, 0.0, 0.0]),
}
HOSTILE_P = {"nan mass": _with(0, np.nan), "inf mass": _with(0, np.inf), "str": "abc",
             "short": P[:5], "none": None, "huge mass": _with(0, 1e200)}


@pytest.mark.parametrize("helper", PARAMETER_HELPERS)
@pytest.mark.parametrize("case", HOSTILE_P)
def test_parameter_helpers_refuse_hostile_p(helper, case):
    if helper != "hover_trim" and case == "huge mass":
        pytest.skip("a finite p copied or a finite I_G (r_G = 0): the model refuses its scale")
    _refused(lambda: PARAMETER_HELPERS[helper](HOSTILE_P[case]), "p")


@pytest.mark.parametrize("r", [[np.nan, 0, 0], "abc", [0, 0], None])
def test_with_cog_refuses_hostile_r(r):
    _refused(lambda: quadcog.with_cog(P, r), "r_G")


def test_inertia_about_cog_refuses_overflow():
    _refused(lambda: quadcog.inertia_about_cog(quadcog.with_cog(P, [1e200, 0.0, 0.0])),
             "overflows")


MODEL = quadcog.load()
OUT_CALLS = {
    "dynamics": lambda out: MODEL.dynamics(X0, U0, P, out=out),
    "mass_matrix": lambda out: MODEL.mass_matrix(P, out=out),
    "linearization": lambda out: MODEL.linearization(X0, U0, P, out=out),
}
_ro = np.zeros(12)
_ro.setflags(write=False)
HOSTILE_OUT = {"list": [0.0] * 12, "int array": np.zeros(12, dtype=int), "read-only": _ro,
               "complex": np.zeros(12, dtype=complex), "str": "abc", "short tuple": (np.zeros(1),)}


@pytest.mark.parametrize("method", OUT_CALLS)
@pytest.mark.parametrize("case", HOSTILE_OUT)
def test_model_out_refused(method, case):
    _refused(lambda: OUT_CALLS[method](HOSTILE_OUT[case]), "out")


@pytest.mark.parametrize("method", ["call", "fast", "casadi_function"])
@pytest.mark.parametrize("name", [["dynamics"], {}, 3, None])
def test_model_function_names_refused(method, name):
    _refused(lambda: getattr(MODEL, method)(name), "name")


@pytest.mark.parametrize("folder", [3, "", None.__class__, ["generated"]])
def test_load_refuses_non_paths(folder):
    _refused(lambda: quadcog.load(folder), "folder")


GAINS = [("composite", k) for k in ("filter_rate", "ls_gain", "forgetting", "covariance_bound",
                                    "force_weight")]
GAINS += [("payload_adaptive", k) for k in ("filter_rate", "ls_gain", "forgetting",
                                            "covariance_bound", "force_weight", "gamma")]
GAINS += [("geometric", k) for k in ("filter_rate", "ls_gain", "forgetting",
                                     "covariance_bound", "force_weight", "rate_filter")]
GAINS += [("adaptive", "projection_radius"), ("fl_integral", "integral_limit")]


@pytest.mark.parametrize("kind, key", GAINS)
@pytest.mark.parametrize("value", [1e308, 1e12])
def test_controller_settings_beyond_scale_refused(kind, key, value):
    # these were accepted, then the law was not finite (blaming the state), an
    # OverflowError, or an overflow of row_weight to inf
    _refused(lambda: quadcog.make_controller(kind, **{key: value}), key)


@pytest.mark.parametrize("value", [-1e12, -1e308])
def test_integral_pole_beyond_scale_refused(value):
    _refused(lambda: quadcog.make_controller("fl_integral", integral_pole=value),
             "integral_pole")


POLES = [("fl", "poles_z", 2), ("fl", "poles_attitude", 2), ("fl", "poles_psi", 2),
         ("fl", "poles_position", 2), ("geometric", "poles_position", 2),
         ("geometric", "poles_attitude", 2)]   # pd places exactly and checks the eigenvalues


@pytest.mark.parametrize("kind, key, n", POLES)
@pytest.mark.parametrize("scale", [-1e200, -1e12, -1e-300])
def test_poles_beyond_scale_refused(kind, key, n, scale):
    # fl poles_z = [-1e200, -2e200] gave kp = inf silently; -1e-300 a gain of 0
    poles = [scale * (1 + k) for k in range(n)]
    _refused(lambda: quadcog.make_controller(kind, **{key: poles}), key)


@pytest.mark.parametrize("make", [lambda: Flip(duration=1e308), lambda: BankedCircle(ramp=1e308),
                                  lambda: Flip(duration=1e-300),
                                  lambda: BankedCircle(ramp=1e-300)])
def test_aerobatic_timescales_no_raw_overflow(make):
    try:             # refused when made (a reference past REFERENCE_LIMIT) or when sampled
        ref = make().sample(np.linspace(0.0, 5.0, 11))
    except QuadcogError:
        return
    assert np.isfinite(ref).all()


CONTROLLER = quadcog.make_controller("pd")
USES = {
    "simulate": lambda: quadcog.simulate(CONTROLLER, duration=0.05),
    "batch": lambda: quadcog.simulate_batch(CONTROLLER, [quadcog.HUMMINGBIRD], duration=0.05,
                                            threads=1),
    "Limits": lambda: quadcog.Limits(),
}
DEFAULTS = {
    "limits.max_tilt_deg": ["a", None, np.nan, -5.0, 1e308],
    "limits.max_position_error": [np.nan, -1.0, "a"],
    "metrics.tail_fraction": [np.nan, -1.0, 0, 2.5, "a", None],
    "simulate.max_steps": [np.nan, "a", None, 0],
    "simulate.dt": ["a", None, np.nan],
}
CASES = [(key, value, use) for key, values in DEFAULTS.items() for value in values
         for use in USES if not (use == "Limits" and not key.startswith("limits."))]


@pytest.fixture
def restore_defaults():
    yield
    config.reset_defaults()


@pytest.mark.parametrize("key, value, use", CASES, ids=lambda v: repr(v)[:20])
def test_hostile_config_defaults_named(restore_defaults, key, value, use):
    config.defaults[key] = value
    _refused(USES[use], key)


@pytest.mark.parametrize("use", ["simulate", "batch"])
def test_deleted_config_default_named(restore_defaults, use):
    del config.defaults["simulate.dt"]
    _refused(USES[use], "simulate.dt")


@pytest.mark.parametrize("key", ["simulate.dt", "limits.max_tilt_deg", "metrics.tail_fraction",
                                 "simulate.max_steps", "run.sample_period"])
def test_every_reader_of_a_default_checks_it(restore_defaults, key):
    """The check is in quadcog.config.get, which every reader goes through: a scenario file's
    reader took simulate.dt and the limits from the dict directly (a NaN step was read)."""
    from quadcog.scenarios.scenario import load_scenario
    config.defaults[key] = float("nan")
    with pytest.raises(InputError, match=re.escape(f"quadcog.config.defaults[{key!r}]")):
        config.get(key)
    if key not in ("run.sample_period", "metrics.tail_fraction"):     # read by a run, not at load
        with pytest.raises(InputError, match=re.escape(f"quadcog.config.defaults[{key!r}]")):
            load_scenario("fig6")

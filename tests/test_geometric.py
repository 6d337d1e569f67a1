"""The truth on SE(3), the aerobatic references and the geometric adaptive law
(docs/tour/geometric.md), against oracles written here: a torque-free spin and free fall
(closed form), the Euler-angle truth where both are valid, numerical differentiation of the
references, the hover trim formula (docs/model.md sec. 3.3), and the flights themselves."""
import dataclasses

from conftest import assert_close
import numpy as np
import pytest

import quadcog
from quadcog.controllers.geometric import GeometricAdaptive
from quadcog.controllers.registry import controller_settings, make_controller
from quadcog.errors import EulerSingularityError, InputError, ScenarioError
from quadcog.model.conventions import IDX, hover_trim, rotation_matrix
from quadcog.scenarios.scenario import load_scenario, parse
from quadcog.sim.plant import Actuation, TruthOptions, plant_step_function
from quadcog.trajectories.aerobatic import BankedCircle, Flip
from quadcog.trajectories.feasibility import check_reference
from quadcog.vehicles.vehicle import HUMMINGBIRD


def _no_drag():
    p = HUMMINGBIRD.parameters().copy()
    p[IDX["c_x"]:IDX["c_psi"] + 1] = 0.0
    return p


@pytest.mark.parametrize("axis", [0, 1])
def test_quaternion_truth_spins_through_the_pole_in_closed_form(model, axis):
    """Torque-free spin about a principal axis (roll or pitch) at 2 rev/s with no thrust: the
    attitude is R(0) exp(w t S(e)) and O falls freely, through 90 degrees of pitch and
    upside down; the Euler truth's state is not finite there (Q(eta) is singular)."""
    options = TruthOptions(quaternion=True)
    step = plant_step_function(model, Actuation.of(HUMMINGBIRD, options))
    w, dt, n = 4 * np.pi, 1e-3, 1000
    x = np.zeros(12)
    x[2], x[9 + axis] = 10.0, w
    p, args = _no_drag(), (np.zeros(0), np.zeros(4))
    for k in range(1, n + 1):
        x = np.array(step(x, *args, p, np.zeros(10), np.zeros(3), np.zeros(6), dt)[0]).ravel()
        if k % 125 == 0:
            t = k * dt
            a = w * t
            c, s = np.cos(a), np.sin(a)
            R = (np.array([[1, 0, 0], [0, c, -s], [0, s, c]]) if axis == 0
                 else np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]]))
            assert_close(rotation_matrix(*x[3:6]), R, 1e-9, "R", t)
            assert_close(x[:3], [0, 0, 10 - 9.81 * t**2 / 2], 1e-9, "free fall", t)
            assert_close(x[9:], np.eye(3)[axis] * w, 1e-12, "body rates", t)


def test_quaternion_truth_is_the_euler_truth_on_the_chart():
    """A circle with a CoG step, flown by the composite law on both truths: the same flight
    (RK4 in two coordinates: differences of the order of its truncation error)."""
    ctl = make_controller("composite")
    cog = quadcog.CogProfile([(1.0, (0.03, 0.02, 0.0), 0.0)])
    runs = [quadcog.simulate(ctl, "circle", duration=6.0, cog=cog, truth=TruthOptions(
        motor_lag=True, rotor_saturation=True, quaternion=q)) for q in (False, True)]
    assert_close(runs[1].x, runs[0].x, 1e-9, "states")


def test_truth_quaternion_key_is_a_flag():
    base = {"name": "t", "controller": "geometric", "duration": 1.0}
    assert parse({**base, "truth": {"quaternion": True}}).truth.quaternion
    with pytest.raises(ScenarioError, match="quaternion"):
        parse({**base, "truth": {"quaternion": "yes"}})


@pytest.mark.parametrize("trajectory", [Flip(), BankedCircle()])
def test_references_are_their_own_derivatives(trajectory):
    """v, a, j are the derivatives of p, v, a (central differences, h = 1e-5 s)."""
    t = np.linspace(0.3, 7.7, 37)
    h = 1e-5
    d = (trajectory.sample(t + h) - trajectory.sample(t - h)) / (2 * h)
    ref = trajectory.sample(t)
    for lo, name in ((0, "v"), (3, "a"), (6, "j")):
        assert_close(d[:, lo:lo + 3], ref[:, lo + 3:lo + 6], 1e-5, name)


def test_flip_is_upside_down_at_its_top_and_the_circle_banked():
    f = Flip()
    top = f(f.start + f.duration / 2)
    assert_close(top[:3], f.bottom + [0, 0, 2 * f.radius], 1e-12, "top")
    # the thrust vector a + g e3 points down: 2 pi 35/16 / T rad/s over the top
    assert top[8] + 9.81 == pytest.approx(9.81 - f.radius * (2 * np.pi * 35 / 16 / 3) ** 2)
    assert top[8] + 9.81 < 0
    c = BankedCircle()
    row = c(5.0)
    assert np.degrees(np.arctan2(np.hypot(*row[6:8]), row[8] + c.g)) == pytest.approx(60.0)
    assert np.linalg.norm(row[3:6]) == pytest.approx(c.radius * c.rate)


def test_aerobatic_settings_are_checked():
    with pytest.raises(InputError, match="flip radius"):
        Flip(radius=0.0)
    with pytest.raises(InputError, match="banked_circle bank_deg"):
        BankedCircle(bank_deg=90.0)
    with pytest.raises(InputError, match="flip bottom"):
        Flip(bottom=(0.0, 1.0))


def test_feasibility_lets_a_flip_fly_upside_down_only_past_90_deg():
    f = Flip()
    t = np.arange(0.0, 8.0, 0.01)
    assert "pull down" not in (check_reference(t, f.sample(t), HUMMINGBIRD, max_tilt=np.pi)
                               .reason or "")
    assert "pull down" in check_reference(t, f.sample(t), HUMMINGBIRD, max_tilt=1.0).reason


def test_registered_with_its_own_settings():
    assert isinstance(make_controller("geometric"), GeometricAdaptive)
    settings = controller_settings("geometric")
    assert {"poles_position", "poles_attitude", "rate_filter", "mass_bounds"} <= set(settings)
    assert not {"poles_z", "poles_psi", "max_tilt", "gamma"} & set(settings)
    with pytest.raises(InputError, match="mass_bounds"):
        GeometricAdaptive(mass_bounds=(1.2, 3.0))
    with pytest.raises(InputError, match="rate_filter"):
        GeometricAdaptive(rate_filter=-1.0)


@pytest.mark.parametrize("r_hat", [(0.0, 0.0, 0.0), (0.03, -0.02, 0.01)])
def test_hover_input_is_the_trim(r_hat):
    """At rest on a hover reference, level, the law believing r_hat: U is the hover trim
    [m g, m g y_G, -m g x_G, 0] of docs/model.md sec. 3.3 (a formula, not the regressor)."""
    ctl = GeometricAdaptive()
    c = ctl.initial_state()
    c[ctl.STATE_SLICES["r_hat"]] = r_hat
    x, ref = np.zeros(12), np.zeros(14)
    x[2] = ref[2] = 1.0
    U, _ = ctl(0.0, x, ref, c)
    p = ctl.nominal.copy()
    p[IDX["x_G"]:IDX["z_G"] + 1] = r_hat
    assert_close(U, hover_trim(p), 1e-12, "U at hover")


@pytest.fixture(scope="module")
def flights():
    out = {}
    for name in ("flip", "banked-circle"):
        res = load_scenario(name).run()
        out[name] = res
    return out


@pytest.mark.filterwarnings("ignore::quadcog.errors.ReferenceWarning")
def test_flip_flown_through_the_pole_with_the_cog_learnt(flights):
    res = flights["flip"]
    m = res.metrics
    assert not m.diverged and m.max_position_error < 0.25
    tilt = np.degrees(np.arccos(np.cos(res.x[:, 3]) * np.cos(res.x[:, 4])))
    assert tilt.max() > 179.0                     # upside down
    assert np.abs(res.r_hat[-1] - res.r_G[-1]).max() < 1e-3
    assert m.final_position_error < 1e-3


def test_banked_circle_flown_with_the_cog_learnt(flights):
    res = flights["banked-circle"]
    m = res.metrics
    assert not m.diverged and m.max_position_error < 0.25
    tilt = np.degrees(np.arccos(np.cos(res.x[:, 3]) * np.cos(res.x[:, 4])))
    assert tilt[res.t > 3.0].min() > 50.0          # 60 deg, less the CoG step's transient
    assert np.abs(res.r_hat[-1] - res.r_G[-1]).max() < 2e-3


@pytest.mark.filterwarnings("ignore::quadcog.errors.ReferenceWarning")
def test_the_euler_truth_cannot_fly_the_flip():
    sc = load_scenario("flip")
    sc = dataclasses.replace(sc, truth=dataclasses.replace(sc.truth, quaternion=False))
    with pytest.raises(EulerSingularityError, match="pi/2"):
        sc.run()

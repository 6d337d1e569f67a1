"""The payload law (quadcog.controllers.payload_adaptive): the filtered identity on a flight,
the projection onto the physically consistent set, and the closed loop carrying a parcel.

Oracles: the identity is checked against the truth's own parameters along a flight of the
truth plant (truth_dynamics in the 14-entry p, a different derivation from the inertial
regressor the law uses), from t = 0 of a moving start; the projection against the
pseudo-inertia's eigenvalues (numpy) and the tangent-cone and Lyapunov inequalities written
out here; the closed loop against the truth's mass.
"""
import dataclasses
import tempfile

import casadi as ca
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
import numpy as np
import pytest

import quadcog
from quadcog.controllers.payload_adaptive import PayloadAdaptive, consistency_excess
from quadcog.model.conventions import NU
from quadcog.model.inertial_parameters import check_physically_consistent, pseudo_inertia
from quadcog.scenarios.scenario import load_scenario
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD

set_hypothesis_home_dir(tempfile.mkdtemp(prefix="quadcog-hypothesis-"))   # not in the tree

# The parcel (issue 20): mass +30 %, CoG 3 cm off axis on the Hummingbird, scaled by the arm
# on the Crazyflie. The Crazyflie preset's rotors (0.0879 N each, thrust to weight 1.33) cannot
# hold it: 1.3 m g / 4 = 0.086 N a rotor before any moment. Its rotors here give 0.15 N (about
# the real Crazyflie 2.0's), so that the test is about the law, not the preset's thrust.
CF = CRAZYFLIE.replace(max_rotor_thrust=0.15)
PARCELS = {"hummingbird": (HUMMINGBIRD, 0.03), "crazyflie": (CF, 0.03 * 0.046 / 0.17)}


def _parcel(vehicle, offset):
    return vehicle.replace(m=1.3 * vehicle.m, x_G=offset)


@pytest.fixture(scope="module")
def hb_law():
    return PayloadAdaptive(HUMMINGBIRD)


def _identity_residual(law, res, truth, compensate=True):
    """|z_c - Y_c theta_true| / max |z_c| along a flight, z_c and Y_c rebuilt here from the
    logged controller state with the generated inertial regressor."""
    model = quadcog.load()
    Y_fun = model.casadi_function("inertial_regressor")
    g = truth.g
    lam = law.filter_rate
    theta = np.r_[truth.m, truth.m * truth.r_G]
    C = res.controller_state
    out, scale = [], 0.0
    for k in range(0, len(res.t), 5):
        x, c = res.x[k], C[k]
        nu = x[NU]
        W = np.array(Y_fun(x, nu, g)) - np.array(Y_fun(x, np.zeros(6), g))
        zeta, Psi = c[4:10], c[10:34].reshape(4, 6).T
        A, B_int, clock = c[45:51], c[51:75].reshape(4, 6).T, c[44]
        w = W[:, 4:] @ law.inertia
        z, Y = zeta - lam * w, lam * W[:, :4] + Psi
        if compensate:
            d = lam * np.exp(-lam * clock)
            z, Y = z + d * (w - A), Y - d * (W[:, :4] + B_int)
        out.append(np.abs(z - Y @ theta).max())
        scale = max(scale, np.abs(z).max())
    return np.array(out) / scale


def test_filtered_identity_on_a_flight(hb_law):
    """z = Y_f theta with the truth's theta from t = 0 of a circle (a moving start), to the
    Euler step's accuracy; without the start compensation it is off by the start transient."""
    truth = _parcel(HUMMINGBIRD, 0.03).replace(y_G=-0.01)
    res = quadcog.simulate(hb_law, "circle", 1.0, vehicle=truth, controller_model=HUMMINGBIRD)
    assert not res.diverged
    assert np.linalg.norm(res.x[0, 6:9]) > 0.5          # the circle starts moving
    r = _identity_residual(hb_law, res, truth)
    assert r.max() < 0.02, r.max()
    raw = _identity_residual(hb_law, res, truth, compensate=False)
    assert raw[:5].max() > 0.5                          # the transient the compensation removes
    # the filters are not trivially zero: the identity holds for a moving regressor
    assert np.ptp(res.controller_state[:, 10:34], axis=0).max() > 0.1


_PROJECTION: dict = {}


def _projected_fn(law):
    th, u = ca.SX.sym("th", 4), ca.SX.sym("u", 4)
    Pv = ca.SX.sym("P", 4, 4)
    return ca.Function("proj", [th, u, Pv], [law.projected_update(th, u, Pv)])


def _on_boundary(law, a, direction, face):
    """A normalized theta on a face of K: the cone (face 0), the upper (1) or lower (2)
    mass bound with h inside the cone, or where the cone meets the upper (3) or lower (4)
    bound."""
    lo, hi = law.mass_bounds
    keep = 1.0 - law.consistency_margin
    inside = 0.999 * abs(np.sin(3 * a)) + 0.001
    a = {0: a, 1: hi, 2: lo, 3: hi, 4: lo}[face]
    d = direction / np.linalg.norm(direction)
    rim = np.sqrt(keep * a / (d @ law.cone @ d))
    b = d * rim * (inside if face in (1, 2) else 1.0)
    return np.r_[a, b]


@settings(max_examples=100, deadline=None)
@given(a=st.floats(0.55, 2.9), face=st.integers(0, 4),
       direction=st.lists(st.floats(-1, 1), min_size=3, max_size=3).filter(
           lambda v: np.linalg.norm(v) > 0.1),
       u=st.lists(st.floats(-5, 5), min_size=4, max_size=4),
       L=st.lists(st.floats(-1, 1), min_size=16, max_size=16),
       truth=st.lists(st.floats(0, 1), min_size=4, max_size=4))
def test_projection_keeps_the_consistent_set(hb_law, a, face, direction, u, L, truth):
    """On a face of K the projected update does not point out of any active face, and it
    does not increase V = theta~^T P^-1 theta~ more than the raw update for any truth in K;
    the discrete map lands in K with a positive definite pseudo-inertia."""
    law = hb_law
    if "fn" not in _PROJECTION:
        _PROJECTION["fn"] = _projected_fn(law)
    fn = _PROJECTION["fn"]
    th = _on_boundary(law, a, np.array(direction), face)
    P = np.array(L).reshape(4, 4)
    P = P @ P.T + 0.05 * np.eye(4)
    u = np.array(u)
    v = np.array(fn(th, u, P)).ravel()
    keep = 1.0 - law.consistency_margin
    lo, hi = law.mass_bounds
    normals = []
    if th[0] >= hi:
        normals.append(np.r_[1.0, 0, 0, 0])
    if th[0] <= lo:
        normals.append(np.r_[-1.0, 0, 0, 0])
    if th[1:] @ law.cone @ th[1:] - keep * th[0] >= -1e-12:
        normals.append(np.r_[-keep, 2 * law.cone @ th[1:]])
    for n in normals:
        assert n @ v <= 1e-9 * (1 + np.abs(u).max() * np.abs(P).max() * np.abs(n).max()), (n, v)
    # a truth in K: mass within the bounds, h inside the cone
    a_t = lo + (hi - lo) * truth[0]
    d = np.array(truth[1:3] + [0.3]) - 0.5
    d /= np.linalg.norm(d)
    b_t = d * np.sqrt(keep * a_t / (d @ law.cone @ d)) * truth[3]
    err = th - np.r_[a_t, b_t]
    Pinv = np.linalg.inv(P)
    assert err @ Pinv @ (v - u) <= 1e-7 * (1 + np.abs(err).max() * np.abs(u).max()
                                            * np.abs(Pinv).max())
    # the discrete projection of a state beyond the faces lands in K, consistent
    c = law.initial_state()
    c[3] = law.vehicle.m * th[0] * (1.2 if face in (1, 3) else 0.8 if face in (2, 4) else 1.0)
    c[0:3] = law.vehicle.arm_length * th[1:] / th[0] * 1.5
    c = law.project_numpy(c)
    pi = law.inertial_parameters_of(c)
    assert np.linalg.eigvalsh(pseudo_inertia(pi))[0] > 0
    check_physically_consistent(pi)
    assert consistency_excess(c[3], c[0:3], np.diag([HUMMINGBIRD.Ixx, HUMMINGBIRD.Iyy,
                                                      HUMMINGBIRD.Izz])) <= keep + 1e-12
    c_sx = np.array(ca.Function("p", [], [law.project(ca.SX(ca.DM(c)))])()["o0"]).ravel()
    assert np.allclose(c_sx, c)


def _mass_error(res, truth):
    return res.controller_state[:, 3] / truth.m - 1.0


@pytest.mark.parametrize("name", ["hummingbird", "crazyflie"])
def test_parcel_at_hover_and_round_a_circle(name):
    """Mass +30 % and the CoG off axis from t = 0: the estimated mass within 3 % by 2 s and
    after, nothing diverges, at hover and carried round a circle."""
    vehicle, offset = PARCELS[name]
    truth = _parcel(vehicle, offset)
    law = PayloadAdaptive(vehicle)
    for trajectory in ("hover", "circle"):
        res = quadcog.simulate(law, trajectory, 3.0, vehicle=truth, controller_model=vehicle)
        assert not res.diverged, (name, trajectory, res.metrics.diverged_reason)
        err = _mass_error(res, truth)
        assert np.abs(err[res.t >= 2.0]).max() <= 0.03, (name, trajectory)
        assert abs(res.r_hat[-1, 0] - offset) <= 0.05 * offset, (name, trajectory)
        # the estimate stays physically consistent all along
        I_O = np.diag([vehicle.Ixx, vehicle.Iyy, vehicle.Izz])
        assert max(consistency_excess(m, r, I_O) for m, r in
                   zip(res.controller_state[::50, 3], res.r_hat[::50])) < 0.9 + 1e-9


@pytest.mark.parametrize("name", ["hummingbird", "crazyflie"])
def test_parcel_with_realistic_truth_and_sensing(name):
    """The same with fig6-real's truth (parallel axis, rotor limits and lag) and sensing
    (noise, gyro bias, one-period delay) and its controller settings."""
    sc = load_scenario("fig6-real")
    vehicle, offset = PARCELS[name]
    truth = _parcel(vehicle, offset)
    law = PayloadAdaptive(vehicle, **sc.controller_params)
    res = quadcog.simulate(law, "circle", 3.0, vehicle=truth, controller_model=vehicle,
                           truth=sc.truth, sensing=sc.sensing)
    assert not res.diverged, res.metrics.diverged_reason
    err = _mass_error(res, truth)
    assert np.abs(err[res.t >= 2.0]).max() <= 0.03
    assert abs(res.r_hat[-1, 0] - offset) <= 0.1 * offset


def test_settings_refused():
    from quadcog.errors import InputError
    for bad in (dict(mass_bounds=(1.2, 3.0)), dict(mass_bounds=(0.5,)),
                dict(consistency_margin=1.0), dict(filter_rate=0.0), dict(gamma=-1.0)):
        with pytest.raises(InputError, match=list(bad)[0]):
            PayloadAdaptive(HUMMINGBIRD, **bad)


@pytest.mark.parametrize("scenario, extra", [
    ("parcel-hover", {}),
    # the preset's FL poles saturate the Crazyflie's rotors on pick-up (the composite law
    # diverges there too); fig6-real's stiffer attitude poles hold it
    ("parcel-crazyflie", {"poles_attitude": [-20.0, -24.0]}),
])
def test_parcel_picked_up_and_dropped(scenario, extra):
    """The shipped parcel scenarios (truth: the airframe plus a box, attached at 2 s and
    dropped at 12 s, realistic truth and sensing): the estimated mass follows the true mass
    of the whole body, within 3 % within 2 s of each event."""
    sc = load_scenario(scenario)
    sc = dataclasses.replace(sc, controller="payload_adaptive",
                             controller_params=dict(sc.controller_params, **extra))
    res = sc.run()
    assert not res.diverged, res.metrics.diverged_reason
    err = np.abs(res.controller_state[:, 3] / res.mass - 1.0)
    assert np.ptp(res.mass) > 0.05 * res.mass[0]          # the parcel was carried
    for t_event, t_next in ((2.0, 12.0), (12.0, np.inf)):
        settled = (res.t >= t_event + 2.0) & (res.t < t_next)
        assert err[settled].max() <= 0.03, (scenario, t_event, err[settled].max())


def test_consistency_excess_against_the_pseudo_inertia():
    """Below 1 exactly where the pseudo-inertia J of (m, r_G, I_O) is positive definite
    (an independent check: J's eigenvalues), and bad input named."""
    from quadcog.errors import InputError, PhysicalConsistencyError
    from quadcog.model.inertial_parameters import inertial_parameters
    rng = np.random.default_rng(7)
    I_O = np.diag([HUMMINGBIRD.Ixx, HUMMINGBIRD.Iyy, HUMMINGBIRD.Izz])
    sides = set()
    for _ in range(200):
        m, r = rng.uniform(0.1, 2.0), rng.normal(0.0, 0.05, 3)
        excess = consistency_excess(m, r, I_O)
        J = pseudo_inertia(inertial_parameters(m, r, I_O))
        if abs(excess - 1) > 1e-6:
            assert (excess < 1) == (np.linalg.eigvalsh(J)[0] > 0), (m, r, excess)
            sides.add(excess < 1)
    assert sides == {True, False}          # both sides of the rim were drawn
    with pytest.raises(PhysicalConsistencyError, match="triangle"):
        consistency_excess(1.0, [0, 0, 0.01], np.diag([1.0, 1.0, 2.0]))   # Sigma singular
    for args, name in (((-1.0, [0, 0, 0], I_O), "m"), ((1.0, [0, 0], I_O), "r_G"),
                       ((1.0, [0, 0, np.nan], I_O), "r_G"),
                       ((1.0, [0, 0, 0], [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]), "I_O")):
        with pytest.raises(InputError, match=f"consistency_excess: {name}"):
            consistency_excess(*args)

"""Payloads: rigid bodies carried, attached, moved and dropped; the truth flies the whole body.

Oracles: the box and parallel-axis formulas written here; the generated ``inertial_dynamics``
(derived in the ten inertial parameters, checked against Pinocchio in
test_inertial_pinocchio.py), integrated by an RK4 written here, against the plant's step; and
a run without payloads against the same run before payloads existed (bit for bit, through an
empty schedule).
"""
import numpy as np
import pytest

import quadcog
from quadcog.controllers.composite import CompositeAdaptive
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.errors import InputError, ParameterError, PhysicalConsistencyError, ScenarioError
from quadcog.model.conventions import IDX, R_G
from quadcog.scenarios.scenario import load_scenario, parse
from quadcog.sim.plant import Actuation, TruthOptions, plant_step_function
from quadcog.sim.timeline import PayloadEvent, PayloadProfile
from quadcog.vehicles.payload import Payload
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD

BOX = Payload(0.2, (0.03, 0.01, -0.03), (0.06, 0.05, 0.04), "parcel")


def _box_pi(m, size, r):
    """pi of a box, written out: m, m r, I about its centre + m (|r|^2 I - r r^T)."""
    a, b, c = size
    I = m / 12 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    r = np.asarray(r, float)
    I = I + m * (r @ r * np.eye(3) - np.outer(r, r))
    return np.array([m, *(m * r), I[0, 0], I[0, 1], I[1, 1], I[0, 2], I[1, 2], I[2, 2]])


def test_payload_pi_is_the_box_formula():
    assert np.allclose(BOX.inertial_parameters(), _box_pi(0.2, BOX.size, BOX.position),
                       rtol=1e-14, atol=0)
    point = Payload(0.1, (0.02, -0.01, 0.0))
    assert np.allclose(point.inertial_parameters(), _box_pi(0.1, (0, 0, 0), point.position),
                       rtol=1e-14, atol=0)
    # the products of inertia are the matrix entries: Ixy = -m x y for a point
    assert point.inertial_parameters()[5] == pytest.approx(-0.1 * 0.02 * -0.01)


def test_with_payload_adds_mass_moment_and_inertia():
    v = HUMMINGBIRD.with_cog((0.01, 0.0, 0.0)).with_payload(BOX)
    m0, r0 = 0.68, np.array([0.01, 0.0, 0.0])
    m = m0 + 0.2
    r = (m0 * r0 + 0.2 * np.array(BOX.position)) / m
    p = v.parameters()
    assert p[IDX["m"]] == pytest.approx(m, rel=1e-15)
    assert np.allclose(p[R_G], r, rtol=1e-14, atol=1e-17)
    pi = v.inertial_parameters()
    airframe = np.array([m0, *(m0 * r0), 0.007, 0, 0.007, 0, 0, 0.012])
    assert np.allclose(pi, airframe + _box_pi(0.2, BOX.size, BOX.position), rtol=1e-14)
    # the hover trim holds the whole body: U1 = m g, U3 = -m g x_G
    assert np.allclose(v.hover_input(), [m * 9.81, m * 9.81 * r[1], -m * 9.81 * r[0], 0])
    assert v.airframe == HUMMINGBIRD.with_cog((0.01, 0.0, 0.0))
    assert v.without_payload("parcel") == v.airframe
    # a loaded vehicle round-trips through its dict (scenario files, vehicle.json)
    assert quadcog.Vehicle(**v.as_dict()) == v


def test_bad_payloads_are_refused_by_name():
    with pytest.raises(ParameterError, match="payload 'p': mass"):
        Payload(-0.1, (0, 0, 0), name="p")
    with pytest.raises(ParameterError, match="size"):
        Payload(0.1, (0, 0, 0), (0.1, -0.1, 0.1))
    with pytest.raises(InputError, match="position"):
        Payload(0.1, (0, 0))
    with pytest.raises(InputError, match="two payloads are named 'parcel'"):
        HUMMINGBIRD.with_payload(BOX).with_payload(BOX)
    with pytest.raises(InputError, match="no payload named 'x'"):
        HUMMINGBIRD.without_payload("x")
    with pytest.raises(InputError, match="airframe"):
        HUMMINGBIRD.with_payload(BOX).with_parameters(HUMMINGBIRD.parameters())
    # an airframe whose CoG offset no rigid body with its I_O has (the paper's model holds
    # I_O as the CoG moves): carrying a payload makes it a body, which must be consistent
    far = HUMMINGBIRD.with_cog((0.0995, 0.0, 0.0))
    with pytest.raises(PhysicalConsistencyError, match="pseudo-inertia"):
        far.with_payload(Payload(0.01, (0, 0, 0)))


def _rk4_inertial(x, U, pi, g, c, dt):
    f = quadcog.load().casadi_function("inertial_dynamics")
    rhs = lambda s: np.array(f(s, U, pi, g, c)).ravel()
    k1 = rhs(x)
    k2 = rhs(x + dt / 2 * k1)
    k3 = rhs(x + dt / 2 * k2)
    k4 = rhs(x + dt * k3)
    return x + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


@pytest.mark.parametrize("parallel_axis", [False, True])
def test_plant_step_flies_the_whole_body(parallel_axis):
    """One plant step with a payload (products of inertia included) against RK4 of the
    generated inertial_dynamics of the whole body's pi."""
    vehicle = HUMMINGBIRD
    act = Actuation.of(vehicle, TruthOptions(parallel_axis=parallel_axis))
    step = plant_step_function(quadcog.load(), act)
    rng = np.random.default_rng(3)
    x = rng.normal(scale=0.3, size=12)
    U = np.array([8.0, 0.05, -0.03, 0.01])
    r_air = np.array([0.02, -0.01, 0.005])          # the airframe's CoG at the step
    p = vehicle.with_cog(r_air).parameters()
    load = BOX.inertial_parameters()
    x_next = np.array(step(x, [], U, p, load, np.zeros(3), np.zeros(6), 1e-3)[0]).ravel()
    # the airframe's inertia about O: stated at r = 0, moved with its CoG when parallel_axis
    I_air = np.diag([0.007, 0.007, 0.012])
    if parallel_axis:
        I_air = I_air + 0.68 * (r_air @ r_air * np.eye(3) - np.outer(r_air, r_air))
    pi_air = np.array([0.68, *(0.68 * r_air), I_air[0, 0], I_air[0, 1], I_air[1, 1],
                       I_air[0, 2], I_air[1, 2], I_air[2, 2]])
    c = p[IDX["c_x"]:IDX["c_psi"] + 1]
    expected = _rk4_inertial(x, U, pi_air + load, 9.81, c, 1e-3)
    assert np.allclose(x_next, expected, rtol=1e-12, atol=1e-14)


def test_parallel_axis_holds_the_stated_inertia_at_the_stated_cog():
    """A vehicle states I_O at its own r_G (as the controllers' model reads it): a plant step
    there with parallel_axis equals one without."""
    r0 = np.array([0.03, 0.02, 0.0])
    v = HUMMINGBIRD.with_cog(r0)
    step = lambda opts: plant_step_function(quadcog.load(), Actuation.of(v, opts))
    x = np.r_[0, 0, 1, 0.1, -0.1, 0.2, 0.1, 0, 0, 0.5, -0.2, 0.3]
    args = (x, [], [7.0, 0.01, 0.02, 0.0], v.parameters(), np.zeros(10), r0, np.zeros(6), 1e-3)
    a = np.array(step(TruthOptions(parallel_axis=True))(*args)[0])
    b = np.array(step(TruthOptions())(*args)[0])
    assert np.array_equal(a, b)


def test_attach_at_zero_is_the_loaded_vehicle_and_known_payload_holds_hover():
    events = [dict(t=0.0, action="attach", name="parcel", mass=BOX.mass,
                   position=list(BOX.position), size=list(BOX.size))]
    ctl = FeedbackLinearization()
    a = quadcog.simulate(ctl, "hover", 1.0, payloads=events)
    b = quadcog.simulate(ctl, "hover", 1.0, vehicle=HUMMINGBIRD.with_payload(BOX),
                         controller_model=HUMMINGBIRD)
    assert np.array_equal(a.x, b.x)
    assert np.allclose(a.mass, 0.88) and np.array_equal(a.r_G, b.r_G)
    assert np.allclose(a.r_G[0], HUMMINGBIRD.with_payload(BOX).parameters()[R_G], rtol=1e-14)
    # a controller that knows the whole body holds the hover: the truth's mass, CoG and
    # inertia are those the model is given (up to the products the paper's model leaves out)
    loaded = HUMMINGBIRD.with_payload(BOX)
    c = quadcog.simulate(FeedbackLinearization(loaded), "hover", 2.0, vehicle=loaded,
                         controller_model=loaded)
    assert c.metrics.max_position_error < 1e-6


def test_attach_move_drop_over_time():
    events = [PayloadEvent(1.0, "attach", "parcel", BOX.mass, BOX.position, BOX.size),
              PayloadEvent(2.0, "move", "parcel", position=(0.0, 0.03, -0.03), ramp=0.5),
              PayloadEvent(3.0, "drop", "parcel")]
    r = quadcog.simulate(CompositeAdaptive(), "hover", 3.5, payloads=events)
    at = lambda t: int(round(t / 1e-3))
    assert r.mass[at(0.5)] == 0.68 and r.mass[at(1.5)] == pytest.approx(0.88)
    assert r.mass[at(3.2)] == 0.68 and np.array_equal(r.r_G[at(3.2)], np.zeros(3))
    # half-way through the slide the parcel is half-way: r_G = m_p r_p(t) / (m + m_p)
    mid = (np.array(BOX.position) + np.array([0.0, 0.03, -0.03])) / 2
    assert np.allclose(r.r_G[at(2.25)], 0.2 * mid / 0.88, rtol=1e-12)
    assert np.allclose(r.r_G[at(1.5)], 0.2 * np.array(BOX.position) / 0.88, rtol=1e-12)
    assert not r.metrics.diverged


def test_payload_events_are_checked():
    attach = dict(t=1.0, action="attach", name="parcel", mass=0.1, position=[0, 0, 0])
    with pytest.raises(InputError, match="no payload named 'box' is on board"):
        PayloadProfile([attach, dict(t=2.0, action="drop", name="box")])
    with pytest.raises(InputError, match="already on board"):
        PayloadProfile([attach, dict(attach, t=2.0)])
    with pytest.raises(InputError, match="time order"):
        PayloadProfile([attach, dict(t=0.5, action="drop", name="parcel")])
    with pytest.raises(InputError, match="attach needs 'mass'"):
        PayloadEvent(1.0, "attach", "p", position=(0, 0, 0))
    with pytest.raises(InputError, match="only a move has a ramp"):
        PayloadEvent(1.0, "drop", "p", ramp=1.0)
    with pytest.raises(InputError, match="action"):
        PayloadEvent(1.0, "throw", "p")
    with pytest.raises(InputError, match="payloads"):
        quadcog.simulate(FeedbackLinearization(), "hover", 0.1, payloads="parcel")
    # the vehicle's own payloads are on board from the start and can be dropped
    r = quadcog.simulate(FeedbackLinearization(), "hover", 0.2,
                         vehicle=HUMMINGBIRD.with_payload(BOX), controller_model=HUMMINGBIRD,
                         payloads=[dict(t=0.1, action="drop", name="parcel")])
    assert r.mass[50] == pytest.approx(0.88) and r.mass[150] == 0.68


PARCEL_TOML = {
    "name": "parcel", "controller": "composite", "duration": 1.0,
    "payload": [{"t": 0.2, "action": "attach", "name": "parcel", "mass": 0.2,
                 "position": [0.03, 0.0, -0.03], "size": [0.06, 0.06, 0.04]},
                {"t": 0.6, "action": "drop", "name": "parcel"}],
}


def test_scenario_payload_keys():
    sc = parse(PARCEL_TOML, "parcel.toml")
    assert [e.action for e in sc.payloads] == ["attach", "drop"]
    r = sc.run()
    assert r.mass.max() == pytest.approx(0.88) and r.mass[-1] == 0.68
    bad = dict(PARCEL_TOML, payload=[dict(PARCEL_TOML["payload"][0], colour="red")])
    with pytest.raises(ScenarioError, match=r"payload\[0\]\.colour"):
        parse(bad, "parcel.toml")
    bad = dict(PARCEL_TOML, payload=[PARCEL_TOML["payload"][1]])
    with pytest.raises(ScenarioError, match="parcel.toml.*no payload named 'parcel'"):
        parse(bad, "parcel.toml")
    loaded = dict(PARCEL_TOML, payload=[], vehicle={"payloads": [
        {"mass": 0.01, "position": [0.0, 0.0, -0.01], "name": "camera"}]})
    assert parse(loaded, "x.toml").vehicle.payloads[0].name == "camera"


def test_batch_carries_the_vehicles_payloads():
    loaded = [CRAZYFLIE.with_payload(Payload(0.008, (0.01, 0.0, -0.01))).with_cog((x, 0, 0))
              for x in (0.0, 0.002)]
    ctl = FeedbackLinearization(CRAZYFLIE)
    b = quadcog.simulate_batch(ctl, loaded, "hover", 0.5, controller_model=CRAZYFLIE)
    one = [quadcog.simulate(ctl, "hover", 0.5, vehicle=v, controller_model=CRAZYFLIE)
           for v in loaded]
    assert np.allclose(b.rms_position_error, [r.metrics.rms_position_error for r in one],
                       rtol=1e-9)
    with pytest.raises(InputError, match="other payloads"):
        quadcog.simulate_batch(ctl, [loaded[0], CRAZYFLIE], "hover", 0.1,
                               controller_model=CRAZYFLIE)


def test_no_payload_keeps_the_airframe_bits():
    """Through the schedule's zero payload the truth's mass, CoG and inertia are the airframe's
    exactly (x + 0 is x), so runs without payloads keep their bits."""
    ctl = CompositeAdaptive()
    a = quadcog.simulate(ctl, "hover", 0.5, cog=[(0.1, (0.06, 0.06, 0.0))])
    b = quadcog.simulate(ctl, "hover", 0.5, cog=[(0.1, (0.06, 0.06, 0.0))],
                         payloads=[dict(t=0.4, action="attach", name="nothing", mass=1e-300,
                                        position=[0, 0, 0])])
    n = 400
    assert np.array_equal(a.x[:n + 1], b.x[:n + 1])
    assert np.array_equal(a.r_G[:n + 1], b.r_G[:n + 1])


def test_a_sweep_over_payload_mass(tmp_path):
    """A sweep key into [[payload]]: each mass is its own batch, and each row is the flight
    that simulate gives for that scenario."""
    from quadcog.sweeps.runner import sweep
    spec = {"name": "parcels", "scenario": "parcel-hover", "mode": "grid",
            "set": {"duration": 3.0, "payload[1].t": 2.5},
            "dimension": [{"key": "payload[0].mass", "values": [0.1, 0.204]}]}
    result = sweep(spec, progress=False, plots=False)
    cols = result.columns
    got = sorted(zip(cols["payload[0].mass"], cols["rms_position_error"]))
    assert len(got) == 2
    for mass, rms in got:
        sc = load_scenario(
            "parcel-hover", overrides=["duration=3.0", "payload[1].t=2.5",
                                       f"payload[0].mass={mass}"])
        assert rms == pytest.approx(sc.run().metrics.rms_position_error, rel=1e-9), mass


@pytest.mark.parametrize("position", [[True, False, False],      # was cast to [1.0, 0, 0]
                                      np.array([0.01, 0.0, 0.0]) + 1e-3j,  # imaginary part dropped
                                      "abc",                               # was a raw ValueError
                                      [0.01, [0.0, 0.0], 0.0]])            # ragged: raw ValueError
def test_a_payload_is_moved_only_to_three_real_numbers(position):
    """Payload.moved checks the position as the constructor does (validate.array)."""
    with pytest.raises(InputError, match=r"payload 'parcel': position"):
        Payload(0.1, (0.0, 0.0, 0.0), name="parcel").moved(position)

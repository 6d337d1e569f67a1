"""The controllers' defaults follow from the vehicle (quadcog.controllers.design), the X500
preset, and a short run of the targets harness (quadcog.studies.targets).

The oracles are the rules written out here from the vehicles' fields, not the module's own
functions: a pole above the rotor bandwidth, a gain not scaled with the vehicle or a
projection radius in metres of another vehicle fails them."""
import dataclasses
import math
from pathlib import Path
import tomllib

import numpy as np
import pytest

from quadcog.controllers import (
    AdaptiveFeedbackLinearization,
    CascadePD,
    CompositeAdaptive,
    FeedbackLinearization,
    FeedbackLinearizationIntegral,
)
from quadcog.controllers.design import REFERENCE, design
from quadcog.vehicles.vehicle import CRAZYFLIE, HUMMINGBIRD, PRESETS, X500

ROOT = Path(__file__).resolve().parent.parent
G = 9.81


def _pendulum(v):
    return math.sqrt(v.m * v.g * v.arm_length / min(v.Ixx, v.Iyy))


def _attitude_rate(v):
    # 10 rad/s on the Hummingbird, scaled by sqrt(m g l / I), at most a quarter of 1 / tau
    rate = 10.0 * _pendulum(v) / _pendulum(HUMMINGBIRD)
    return rate if v.motor_time_constant == 0 else min(rate, 0.25 / v.motor_time_constant)


def test_the_hummingbird_keeps_the_papers_design_exactly():
    d = design(HUMMINGBIRD)
    assert d.poles_attitude == (-10.0, -12.0) and d.poles_z == (-3.0, -4.0)
    assert d.poles_psi == (-4.0, -5.0) and d.poles_position == (-1.5, -2.0)
    assert d.poles_x == (-2.0, -2.5, -10.0, -12.0) and d.max_tilt == 0.6
    assert d.gamma == 0.01 and d.filter_rate == 20.0 and d.ls_gain == 200.0
    assert d.forgetting == 8.0 and d.warm_up == 0.25 and d.integral_pole == -4.0
    assert d.projection_radius == pytest.approx(0.95 * math.sqrt(0.007 / 0.68), rel=1e-12)
    assert d == REFERENCE
    fl = FeedbackLinearization()
    assert fl.kp.tolist() == [12.0, 120.0, 120.0, 20.0] and fl.kd.tolist() == [7.0, 22.0, 22.0, 9.0]


def test_the_papers_scenarios_write_out_the_papers_gains():
    for path in sorted((ROOT / "quadcog" / "scenarios").glob("fig*.toml")):
        params = tomllib.loads(path.read_text())["controller_params"]
        for key, value in params.items():
            if key in ("motor_lag",) or (key == "poles_attitude" and path.stem.endswith("-real")):
                continue
            ref = getattr(REFERENCE, key)
            assert (list(ref) if isinstance(ref, tuple) else ref) == value, (path.name, key)


@pytest.mark.parametrize("name", ["crazyflie", "x500"])
def test_poles_scale_with_the_pendulum_rate_below_the_rotor_bandwidth(name):
    v = PRESETS[name]
    s = _attitude_rate(v) / 10.0
    d = design(v)
    assert d.poles_attitude == pytest.approx((-10.0 * s, -12.0 * s), rel=1e-12)
    assert d.poles_position == pytest.approx((-1.5 * s, -2.0 * s), rel=1e-12)
    assert d.poles_z == pytest.approx((-3.0 * s, -4.0 * s), rel=1e-12)
    assert d.poles_x == pytest.approx((-2.0 * s, -2.5 * s, -10.0 * s, -12.0 * s), rel=1e-12)
    bandwidth = 1.0 / v.motor_time_constant
    assert max(abs(p) for p in d.poles_attitude + d.poles_x) < bandwidth / 2
    # the Crazyflie's pendulum rate would ask for 21 rad/s: the rotors (80 rad/s) cap it at 20
    if name == "crazyflie":
        assert d.poles_attitude == pytest.approx((-20.0, -24.0))


def test_slow_motors_pull_every_loop_below_their_bandwidth():
    slow = X500.replace(motor_time_constant=0.1)          # 10 rad/s rotors
    d = design(slow)
    assert abs(d.poles_attitude[0]) == pytest.approx(2.5) and abs(d.poles_attitude[1]) < 10.0
    assert all(abs(p) < 10.0 for p in d.poles_x + d.poles_z + d.poles_psi)
    ctl = FeedbackLinearization(slow)
    assert ctl.kp[1] == pytest.approx(2.5 * 3.0)          # (s + 2.5)(s + 3)
    instant = X500.replace(motor_time_constant=0.0)       # no cap: the pendulum rule alone
    assert abs(design(instant).poles_attitude[0]) == pytest.approx(_attitude_rate(instant))


@pytest.mark.parametrize("name", ["hummingbird", "crazyflie", "x500"])
def test_gamma_is_the_same_dimensionless_gain_on_every_vehicle(name):
    # the paper's law learns at hover at gamma (m g / (I kp))^2 / 2: the same on every vehicle
    v = PRESETS[name]
    d = design(v)
    kp = d.poles_attitude[0] * d.poles_attitude[1]
    dimensionless = d.gamma * (v.m * v.g / (min(v.Ixx, v.Iyy) * kp)) ** 2
    reference = 0.01 * (0.68 * G / (0.007 * 120.0)) ** 2
    assert dimensionless == pytest.approx(reference, rel=1e-12)
    assert AdaptiveFeedbackLinearization(v).gamma == pytest.approx([d.gamma] * 3)
    if name == "crazyflie":                               # 18 times smaller than 0.01
        assert d.gamma < 0.001


@pytest.mark.parametrize("name", ["crazyflie", "x500"])
def test_projection_radius_is_a_fraction_of_this_vehicles_arm(name):
    v = PRESETS[name]
    expected = min(v.arm_length, 0.95 * math.sqrt(min(v.Ixx, v.Iyy, v.Izz) / v.m))
    ctl = CompositeAdaptive(v)
    assert ctl.projection_radius == pytest.approx(expected, rel=1e-12)
    assert ctl.projection_radius <= v.arm_length
    assert ctl.projection_radius != pytest.approx(design(HUMMINGBIRD).projection_radius)


def test_max_tilt_leaves_the_weight_held_at_full_thrust():
    weak = X500.replace(max_rotor_thrust=1.2 * X500.m * G / 4)     # thrust-to-weight 1.2
    tilt = CascadePD(weak).max_tilt
    assert tilt < 0.6 and 4 * weak.max_rotor_thrust * math.cos(tilt) > weak.m * G
    assert tilt == pytest.approx(0.75 * math.acos(1 / 1.2), rel=1e-9)
    assert FeedbackLinearization(HUMMINGBIRD).max_tilt == 0.6


def test_composite_rates_follow_the_rotors():
    slow = CRAZYFLIE.replace(motor_time_constant=0.05)             # 20 rad/s rotors
    ctl = CompositeAdaptive(slow)
    assert ctl.filter_rate == pytest.approx(5.0)                   # a quarter of them
    assert ctl.ls_gain == pytest.approx(50.0) and ctl.forgetting == pytest.approx(2.0)
    assert ctl.warm_up == pytest.approx(1.0)


def test_explicit_settings_are_kept_and_for_vehicle_derives_the_rest():
    ctl = CompositeAdaptive(gamma=0.02, poles_z=(-2.0, -3.0), filter_rate=30.0)
    cf = ctl.for_vehicle(CRAZYFLIE)
    assert cf.vehicle == CRAZYFLIE and cf is not ctl
    assert cf.gamma.tolist() == [0.02] * 3 and cf.filter_rate == 30.0
    assert cf.kp[0] == pytest.approx(6.0)                          # poles_z as given
    assert cf.kp[1] == pytest.approx(480.0)                        # attitude from the Crazyflie
    assert cf.ls_gain == design(CRAZYFLIE).ls_gain
    assert cf.projection_radius == pytest.approx(design(CRAZYFLIE).projection_radius)
    # built for the Crazyflie directly: the same law
    assert cf.cache_key() == CompositeAdaptive(CRAZYFLIE, gamma=0.02, poles_z=(-2.0, -3.0),
                                               filter_rate=30.0).cache_key()
    pid = FeedbackLinearizationIntegral(integral_limit=2.0).for_vehicle(X500)
    assert pid.integral_limit == 2.0
    assert pid.integral_pole == pytest.approx(design(X500).integral_pole)


def test_x500_is_the_px4_gz_model():
    v = X500
    assert PRESETS["x500"] is v and v.m == 2.0
    assert (v.Ixx, v.Iyy, v.Izz) == pytest.approx((0.0216667, 0.0216667, 0.04), rel=1e-5)
    assert v.arm_length == pytest.approx(0.174 * math.sqrt(2))
    assert v.max_rotor_thrust == pytest.approx(8.54858e-6 * 1000.0 ** 2)
    assert 4 * v.max_rotor_thrust / (v.m * G) == pytest.approx(1.743, abs=1e-3)
    # gz's rotor_0 front right and rotor_1 back left turn ccw (d = -1), the others cw
    pos = np.array(v.rotor_positions)
    assert pos.tolist() == [[0.174, -0.174], [-0.174, 0.174], [0.174, 0.174], [-0.174, -0.174]]
    assert v.rotor_directions == (-1, -1, 1, 1)
    f = v.rotor_thrusts(v.hover_input())
    assert f == pytest.approx([v.m * G / 4] * 4)
    # more thrust on the ccw pair turns the body clockwise (negative yaw moment)
    assert (v.mixer() @ np.array([1.0, 1.0, 0.0, 0.0]))[3] < 0


def test_x500_as_a_scenario_preset(tmp_path):
    from quadcog.scenarios.scenario import load_scenario
    path = tmp_path / "x.toml"
    path.write_text('name = "x"\ncontroller = "composite"\nduration = 1.0\n'
                    '[vehicle]\npreset = "x500"\n')
    sc = load_scenario(path)
    assert sc.vehicle == X500
    ctl = sc.make_controller()
    assert ctl.kp[1] == pytest.approx(design(X500).poles_attitude[0]
                                      * design(X500).poles_attitude[1])


def test_the_reference_says_from_the_vehicle():
    import importlib.util
    spec = importlib.util.spec_from_file_location("gen_reference",
                                                  ROOT / "docs" / "gen_reference.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    page = mod.scenario_keys_page()
    part = page.split('controller = "composite"', 1)[1]
    row = next(line for line in part.splitlines() if line.startswith("| `filter_rate`"))
    assert "from the vehicle" in row
    row = next(line for line in part.splitlines() if line.startswith("| `force_weight`"))
    assert "from the vehicle" not in row and "`1`" in row
    assert '"x500"' in page


def test_targets_smoke(tmp_path):
    from quadcog.studies.targets import CASES, Case, fly, markdown_table, write_targets
    hover = next(c for c in CASES if c.name == "hover")
    short = Case("short-hover", "0.3 s", lambda v: dict(hover.flight(v), duration=0.3),
                 hover.metrics)
    rows = fly("crazyflie", "adaptive", short)
    assert [r.metric for r in rows] == ["estimate drift", "excursion"]
    assert rows[0].target == 0.02 and rows[0].holds is True and rows[0].diverged_at is None
    assert 0 <= rows[0].value < 0.02 and rows[1].holds is None
    out = write_targets(rows, tmp_path / "t")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == \
        ["targets.csv", "targets.json", "targets.md"]
    assert "| crazyflie | adaptive | short-hover | estimate drift" in markdown_table(rows)


def test_the_mass_bound_is_what_the_rotors_lift():
    """m_hi / m = 4 max_rotor_thrust / (m g) for every preset, in both mass-learning laws;
    a vehicle whose rotors cannot lift it has no default bound (typed error, named)."""
    from quadcog.controllers.geometric import GeometricAdaptive
    from quadcog.controllers.payload_adaptive import PayloadAdaptive
    from quadcog.errors import InputError
    for v in [HUMMINGBIRD, *PRESETS.values()]:
        lift = 4 * v.max_rotor_thrust / v.g                 # kg: what the rotors hold up
        assert design(v).mass_bounds == pytest.approx((0.5, lift / v.m), rel=1e-12)
    assert PayloadAdaptive(HUMMINGBIRD).mass_bounds[1] == pytest.approx(
        4 * 6.00318901352 / (0.68 * HUMMINGBIRD.g), rel=1e-12)
    assert GeometricAdaptive(HUMMINGBIRD).mass_bounds.tolist() == \
        list(PayloadAdaptive(HUMMINGBIRD).mass_bounds)
    weak = dataclasses.replace(HUMMINGBIRD, max_rotor_thrust=0.2 * HUMMINGBIRD.max_rotor_thrust)
    with pytest.raises(InputError, match="max_rotor_thrust"):
        PayloadAdaptive(weak)
    assert PayloadAdaptive(weak, mass_bounds=(0.5, 1.5)).mass_bounds[1] == 1.5

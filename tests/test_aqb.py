"""AdaptiveQuadBench (quadcog.aqb): the conversions against textbook values, the state
dictionary's check, the payload protocol's distribution, the set-up of the vendor tree; with
AdaptiveQuadBench installed, the adapter and the generator against AdaptiveQuadBench itself."""
import os
from pathlib import Path
import shutil

import numpy as np
import pytest

from quadcog.aqb import convert
from quadcog.aqb.convert import (
    motor_speeds,
    quaternion_to_matrix,
    reference_row,
    state_vector,
    vehicle_from_quad_params,
)
from quadcog.aqb.install import PATCHES, SETUP_LINE, TARBALL, installed_tree, prepare, vendor_tarball
from quadcog.aqb.protocol import AQB_QUAD_PARAMS, MotionPrimitive, aqb_vehicle, payload_trials, rmse
from quadcog.errors import InputError, PeerStateError

G = 9.81
M, K_ETA, K_M = 0.826, 7.64e-6, 7.64e-6 * 0.0140
needs_aqb = pytest.mark.skipif(installed_tree() is None,
                               reason=f"AdaptiveQuadBench not installed: {SETUP_LINE}")


def _state(**changes):
    s = {"x": np.array([0.1, -0.2, 0.3]), "v": np.zeros(3), "q": np.array([0, 0, 0, 1.0]),
         "w": np.zeros(3), "wind": np.zeros(3), "rotor_speeds": np.zeros(4),
         "ext_force": np.zeros(3), "ext_torque": np.zeros(3), "payload_mass": 0.0}
    s.update(changes)
    return s


def _flat(**changes):
    f = {"x": np.zeros(3), "x_dot": np.zeros(3), "x_ddot": np.zeros(3), "x_dddot": np.zeros(3),
         "x_ddddot": np.zeros(3), "yaw": 0.0, "yaw_dot": 0.0, "yaw_ddot": 0.0}
    f.update(changes)
    return f


# -- conversions --------------------------------------------------------------------------

def test_hover_motor_speed_is_the_textbook_one():
    """m g = 4 k omega^2 at hover: a wrong thrust constant, mixer row or square root fails."""
    v = aqb_vehicle()
    omega = motor_speeds(v, [M * G, 0, 0, 0])
    np.testing.assert_allclose(omega, np.sqrt(M * G / (4 * K_ETA)), rtol=1e-12)
    assert 514 < omega[0] < 516              # by hand: sqrt(8.103 N / 3.056e-5 N/(rad/s)^2)


def test_moments_of_the_rotor_speeds_are_rotorpys():
    """Each moment the mixer is asked for comes back through RotorPy's own rotor model
    (thrust k_eta w^2 at rotor_pos, reaction rotor_dir k_m w^2 about z): a rotor order, a sign
    of the spin directions or the moment constant wrong fails."""
    v = aqb_vehicle()
    pos = np.array(list(AQB_QUAD_PARAMS["rotor_pos"].values()))
    dirs = AQB_QUAD_PARAMS["rotor_directions"]
    for U in ([M * G, 0.05, 0, 0], [M * G, 0, -0.04, 0], [M * G, 0, 0, 0.01],
              [1.2 * M * G, 0.02, 0.03, -0.005]):
        w = motor_speeds(v, U)
        f = K_ETA * w**2
        moment = sum(np.cross(r, [0, 0, fi]) for r, fi in zip(pos, f))
        moment[2] += np.sum(dirs * K_M * w**2)
        np.testing.assert_allclose([f.sum(), *moment], U, atol=1e-12)


def test_motor_speeds_are_clipped_to_the_rotor_limits():
    v = aqb_vehicle()
    assert np.all(motor_speeds(v, [200.0, 0, 0, 0]) == pytest.approx(1000.0))
    assert np.all(motor_speeds(v, [-5.0, 0, 0, 0]) == 0.0)


def test_vehicle_of_quad_params():
    v = aqb_vehicle()
    omega_h = np.sqrt(M * G / (4 * K_ETA))
    assert (v.m, v.g, v.Ixx, v.Iyy, v.Izz) == (0.826, 9.81, 0.0047, 0.005, 0.0074)
    assert v.thrust_constant == K_ETA and v.moment_constant == pytest.approx(0.014)
    assert v.max_rotor_thrust == pytest.approx(K_ETA * 1000.0**2)
    assert v.motor_time_constant == 0.005 and v.rotor_directions == (1, -1, 1, -1)
    # the rotor drag H = -omega k_d v of four rotors at hover speed
    assert v.c_x == pytest.approx(4 * 1.19e-4 * omega_h) and v.c_z == pytest.approx(4 * 2.32e-4 * omega_h)
    assert v.arm_length == pytest.approx(0.166)


def test_vehicle_of_bad_quad_params_names_the_key():
    p = dict(AQB_QUAD_PARAMS)
    del p["k_eta"]
    with pytest.raises(InputError, match=r"quad_params\['k_eta'\]"):
        vehicle_from_quad_params(p)
    with pytest.raises(InputError, match="Ixy"):
        vehicle_from_quad_params(dict(AQB_QUAD_PARAMS, Ixy=1e-4))


def test_quaternion_is_scalar_last_and_body_to_ground():
    """A yaw of 90 deg: q = [0, 0, sin 45, cos 45] (scipy's and RotorPy's order); body x points
    along ground y, so a ground velocity along x is -y in body axes."""
    s = np.sqrt(0.5)
    x = state_vector(_state(q=np.array([0, 0, s, s]), v=np.array([1.0, 0, 0])))
    np.testing.assert_allclose(x[3:6], [0, 0, np.pi / 2], atol=1e-12)
    np.testing.assert_allclose(x[6:9], [0, -1, 0], atol=1e-12)
    x = state_vector(_state(q=np.array([np.sin(np.pi / 12), 0, 0, np.cos(np.pi / 12)])))
    np.testing.assert_allclose(x[3:6], [np.pi / 6, 0, 0], atol=1e-12)


def test_euler_angles_against_scipy():
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(3)
    for _ in range(20):
        q = rng.normal(size=4)
        R = Rotation.from_quat(q)                    # scalar last
        np.testing.assert_allclose(quaternion_to_matrix(q), R.as_matrix(), atol=1e-12)
        zyx = R.as_euler("ZYX")                      # intrinsic z-y-x: psi, theta, phi
        x = state_vector(_state(q=q, w=np.array([0.1, 0.2, 0.3])))
        np.testing.assert_allclose(x[3:6], zyx[::-1], atol=1e-9)
        np.testing.assert_allclose(x[9:12], [0.1, 0.2, 0.3])


def test_reference_row():
    ref = reference_row(_flat(x=np.array([1.0, 2, 3]), x_dot=np.array([4.0, 5, 6]),
                              x_ddot=np.array([7.0, 8, 9]), x_dddot=np.array([1.0, 1, 1]),
                              yaw=0.5, yaw_dot=0.25))
    np.testing.assert_array_equal(ref, [1, 2, 3, 4, 5, 6, 7, 8, 9, 1, 1, 1, 0.5, 0.25])
    f = _flat()
    del f["x_dddot"], f["yaw_dot"]
    assert not reference_row(f)[9:].any()


# -- the state dictionary ------------------------------------------------------------------

@pytest.mark.parametrize("key", sorted(convert.STATE_KEYS))
def test_a_missing_state_key_is_named(key):
    s = _state()
    del s[key]
    with pytest.raises(PeerStateError, match=rf"state\['{key}'\] is missing"):
        state_vector(s)


@pytest.mark.parametrize("key, value", [("x", np.zeros(2)), ("q", np.zeros(3)),
                                        ("v", np.array([np.nan, 0, 0])), ("w", "fast")])
def test_a_malformed_state_key_is_named(key, value):
    with pytest.raises(PeerStateError, match=rf"state\['{key}'\]"):
        state_vector(_state(**{key: value}))


def test_a_quaternion_of_norm_zero_is_refused():
    with pytest.raises(PeerStateError, match=r"state\['q'\].*norm"):
        state_vector(_state(q=np.zeros(4)))


def test_a_missing_flat_output_is_named():
    f = _flat()
    del f["x_dot"]
    with pytest.raises(PeerStateError, match=r"flat_output\['x_dot'\] is missing"):
        reference_row(f)


def test_the_state_is_read_without_the_disturbance_keys():
    """The truth's ext_force, ext_torque and payload_mass are neither needed nor read."""
    s = _state()
    bare = {k: s[k] for k in convert.STATE_KEYS}
    np.testing.assert_array_equal(state_vector(bare), state_vector(
        _state(ext_force=np.array([9.0, 9, 9]), ext_torque=np.array([1.0, 1, 1]), payload_mass=2.0)))


def test_the_adapter_refuses_a_state_without_q_and_ignores_the_truths_keys():
    from quadcog.aqb.adapter import QuadcogAQBController
    ctl = QuadcogAQBController(AQB_QUAD_PARAMS, "pd")
    s = _state()
    del s["q"]
    with pytest.raises(PeerStateError, match=r"state\['q'\] is missing"):
        ctl.update(0.0, s, _flat())
    a = ctl.update(0.0, _state(), _flat())["cmd_motor_speeds"]
    ctl.reset()
    b = ctl.update(0.0, _state(ext_force=np.ones(3), ext_torque=np.ones(3), payload_mass=0.4),
                   _flat())["cmd_motor_speeds"]
    np.testing.assert_array_equal(a, b)
    assert a.shape == (4,) and np.all(a > 0)


def test_the_adapter_restarts_the_law_at_an_earlier_time():
    """AdaptiveQuadBench's delay test reuses a controller: a call at an earlier time restarts
    the law's state (a law that kept its estimate across flights would fail here)."""
    from quadcog.aqb.adapter import QuadcogAQBController
    ctl = QuadcogAQBController(AQB_QUAD_PARAMS, "adaptive")
    first = ctl.update(0.0, _state(), _flat())["cmd_motor_speeds"]
    for k in range(1, 30):
        ctl.update(0.01 * k, _state(x=np.array([0.1, 0.1, -0.2])), _flat())
    assert not np.allclose(ctl.c, ctl.controller.initial_state())
    np.testing.assert_array_equal(ctl.update(0.0, _state(), _flat())["cmd_motor_speeds"], first)


# -- the protocol --------------------------------------------------------------------------

def test_the_protocols_distribution():
    trials = payload_trials(2000, seed=7)
    m = np.array([t.payload_mass for t in trials])
    r = np.array([t.payload_position for t in trials])
    goals = np.array([t.goal_position + t.goal_velocity + t.goal_acceleration for t in trials])
    n_toggles = np.array([len(t.toggle_times) for t in trials])
    assert m.min() >= 0 and m.max() <= 0.5 * 0.826
    assert abs(m.mean() - 0.25 * 0.826) < 4 * 0.5 * 0.826 / np.sqrt(12 * 2000)
    assert np.abs(r).max() <= 0.2 * 0.166 and abs(r.std() - 0.4 * 0.166 / np.sqrt(12)) < 3e-4
    assert np.abs(goals).max() <= 2 and abs(goals.std() - 4 / np.sqrt(12)) < 0.02
    assert set(n_toggles) <= {1, 2, 3, 4} and abs((n_toggles == 1).mean() - 0.25) < 0.04
    for t in trials:
        times = np.array(t.toggle_times)
        assert np.all((times >= 0.5) & (times <= 4.5)) and np.all(np.diff(times) >= 0.5)


def test_when2fail_intensities_carry_whole_vehicle_masses():
    assert {t.payload_mass for t in payload_trials(20, intensity=2)} == {2 * 0.826}
    assert {t.payload_mass for t in payload_trials(20, intensity=0)} == {0.0}
    assert payload_trials(5, intensity=2)[0].payload_events()[0].mass == pytest.approx(1.652)
    assert payload_trials(5, intensity=0)[0].payload_events() == ()
    with pytest.raises(InputError, match="intensity"):
        payload_trials(5, intensity=1.5)


def test_payload_events_alternate_attach_and_drop():
    t = next(t for t in payload_trials(50) if len(t.toggle_times) == 3)
    ev = t.payload_events()
    assert [e.action for e in ev] == ["attach", "drop", "attach"]
    assert [e.t for e in ev] == list(t.toggle_times) and ev[0].position == t.payload_position


def test_motion_primitive_meets_its_goal_from_rest():
    """End conditions of the quintic, and each derivative the finite difference of the one
    before (a wrong coefficient or a dropped factorial fails)."""
    g = MotionPrimitive((1.0, -2.0, 0.5), (0.3, 1.0, -1.5), (-2.0, 0.7, 1.1), 5.0)
    start, end = g(0.0), g(5.0)
    assert not start[:9].any()            # at rest; the jerk starts at gamma
    np.testing.assert_allclose(end[0:9], [1, -2, 0.5, 0.3, 1, -1.5, -2, 0.7, 1.1], atol=1e-12)
    t, h = np.linspace(0.2, 4.8, 9), 1e-5
    for lo in (0, 3, 6):                 # p -> v, v -> a, a -> j
        d = (g.sample(t + h)[:, lo:lo + 3] - g.sample(t - h)[:, lo:lo + 3]) / (2 * h)
        np.testing.assert_allclose(d, g.sample(t)[:, lo + 3:lo + 6], atol=1e-6)


def test_rmse_is_aqbs_cost():
    p = np.array([[0.0, 0, 0], [3.0, 4, 0]])
    assert rmse(p, np.zeros((2, 3))) == pytest.approx(np.sqrt(25 / 2))


# -- the set-up ----------------------------------------------------------------------------

@pytest.mark.skipif(not vendor_tarball().is_file(),
                    reason=f"no {TARBALL} in {vendor_tarball().parent}")
def test_prepare_patches_a_copy_and_never_the_source(tmp_path, monkeypatch):
    monkeypatch.setenv("QUADCOG_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.delenv("QUADCOG_AQB", raising=False)
    tree = prepare()
    assert tree.root.parent == tmp_path / "cache" / "aqb"
    assert tree.root.name == "8f341d69a6b072d0af228c48f3ad59cd78c8f3ff1b18095e221e55a1196e3204"
    for rel, old, new in PATCHES:
        text = (tree.root / rel).read_text()
        assert new in text and old not in text
    assert (tree.rotorpy / "pyproject.toml").is_file() and (tree.rotorpy / "rotorpy" / "simulate.py").is_file()
    assert tree.stamp()["commits"] == {"aqb": "ee7df29", "rotorpy": "6d2045d"}
    # a user's checkout: copied, patched in the cache, the user's files untouched
    user = tmp_path / "user"
    shutil.copytree(tree.aqb, user / "AdaptiveQuadBench")
    shutil.copytree(tree.rotorpy / "rotorpy", user / "rotorpy-aqb")
    shutil.copyfile(tree.rotorpy / "pyproject.toml", user / "rotorpy-aqb" / "pyproject.toml")
    for rel, old, new in PATCHES:        # undo the fixes: the user's tree is as upstream ships it
        f = user / rel.replace("rotorpy-pkg/", "")
        f.write_text(f.read_text().replace(new, old))
    before = {p: p.read_bytes() for p in user.rglob("*") if p.is_file()}
    monkeypatch.setenv("QUADCOG_AQB", str(user))
    mine = prepare()
    assert mine.root != tree.root and mine.root.parent == tree.root.parent
    assert {p: p.read_bytes() for p in user.rglob("*") if p.is_file()} == before
    assert "quadcog: no LaTeX" in (mine.aqb / "aqb/experiments/plotting_utils.py").read_text()


def test_prepare_refuses_a_tarball_that_is_not_the_vendors(tmp_path, monkeypatch):
    monkeypatch.setenv("QUADCOG_CACHE_DIR", str(tmp_path / "cache"))
    fake = tmp_path / TARBALL
    fake.write_bytes(b"not the tarball")
    with pytest.raises(InputError, match="sha256"):
        prepare(fake)
    with pytest.raises(InputError, match="layout"):
        prepare(tmp_path)


# -- against AdaptiveQuadBench itself -------------------------------------------------------

@needs_aqb
def test_the_copied_vehicle_is_aqbs():
    from aqb.quad_param.quadrotor import quad_params
    for key, value in AQB_QUAD_PARAMS.items():
        if isinstance(value, dict):
            for k, r in value.items():
                np.testing.assert_array_equal(quad_params[key][k], r)
        else:
            np.testing.assert_array_equal(quad_params[key], value)


@needs_aqb
@pytest.mark.parametrize("intensity", [None, 2.0])
def test_the_generator_draws_aqbs_trials(intensity):
    """Trial i is AdaptiveQuadBench's trial i (RandomizationConfig with its seed, its draw order
    and, for when2fail, its steps 0 .. k)."""
    from aqb.config.randomization_config import RandomizationConfig
    rc = RandomizationConfig.from_experiment_type("payload", 6, AQB_QUAD_PARAMS, 42)
    trajs = rc.create_trajectories()
    for k in ([None] if intensity is None else range(int(intensity) + 1)):
        if k is not None:
            rc.scale_ranges_with_intensity(k)
        masses, positions = rc.create_payload_disturbance()
        toggles = rc.create_disturbance_toggle_times()
    ours = payload_trials(6, seed=42, intensity=intensity)
    for t, traj, m, p, tt in zip(ours, trajs, masses, positions, toggles):
        assert t.payload_mass == m and t.payload_position == tuple(p) and t.toggle_times == tuple(tt)
        g = t.trajectory()
        for s in (0.0, 1.3, 4.99):
            f = traj.update(s)
            np.testing.assert_allclose(g(s)[0:12], np.r_[f["x"], f["x_dot"], f["x_ddot"], f["x_dddot"]],
                                       atol=1e-9)


@needs_aqb
def test_the_adapter_is_an_aqb_controller():
    from aqb.controller.controller_template import MultirotorControlTemplate
    from aqb.quad_param.quadrotor import quad_params

    from quadcog.aqb.adapter import QuadcogAQBController, register_template
    assert register_template()
    assert isinstance(QuadcogAQBController(quad_params, "pd"), MultirotorControlTemplate)


@needs_aqb
def test_the_adapter_flies_the_geometric_law():
    """AdaptiveQuadBench's factory builds quadcog's SE(3) law from its quad_params: at rest on
    the reference it commands the textbook hover speed, below the reference more thrust, and
    its estimate moves and stays finite (a wrong state layout or a law that is not stepped
    fails here)."""
    from aqb.quad_param.quadrotor import quad_params

    from quadcog.aqb.adapter import aqb_controller_factory
    ctl = aqb_controller_factory()("qc-geometric", quad_params)
    assert ctl.controller.name == "geometric" and ctl.controller.n_state > 0
    hover = ctl.update(0.0, _state(x=np.zeros(3)), _flat())["cmd_motor_speeds"]
    np.testing.assert_allclose(hover, np.sqrt(M * G / (4 * K_ETA)), rtol=1e-6)
    low = _state(x=np.array([0.0, 0.0, -0.2]))
    for k in range(1, 30):
        out = ctl.update(0.01 * k, low, _flat())
    assert np.all(np.isfinite(ctl.c)) and not np.allclose(ctl.c, ctl.controller.initial_state())
    assert out["cmd_thrust"] > M * G and ctl.failures == 0


@needs_aqb
def test_the_shipped_payload_models_flaws_are_measured_and_the_corrected_one_is_a_rigid_body():
    from aqb.quad_param.quadrotor import quad_params

    from quadcog.aqb.physics import corrected_multirotor, flaw_measures, rigid_body_inertia
    trials = payload_trials(10)
    f = flaw_measures(trials)
    assert f["inertia_error_attach"] > 0.01 and f["com_error_detach"] > 1e-4
    assert 0.5 < f["extra_torque_ratio"] <= 1.0     # the torque is (r_p - c) x m_p g: m0/M of M g |c|
    v = corrected_multirotor()(quad_params)
    I0 = v.inertia.copy()
    # textbook: a point mass mp at distance a on x; the CoM moves by mp a / M, and the inertia
    # about it grows by m0 mp a^2 / M about y and z
    mp, a = 0.3, 0.03
    v.update_payload(mp, np.array([a, 0.0, 0.0]))
    v.attach_payload()
    red = 0.826 * mp / (0.826 + mp) * a**2
    np.testing.assert_allclose(v.com, [mp * a / (0.826 + mp), 0, 0], atol=1e-15)
    np.testing.assert_allclose(v.inertia, I0 + np.diag([0, red, red]), atol=1e-15)
    np.testing.assert_allclose(rigid_body_inertia(0.826, np.zeros(3), I0, mp, [a, 0, 0])[1], v.inertia)
    v.detach_payload()
    assert np.all(v.com == 0) and np.all(v.inertia == I0)


def test_aqb_env_is_named_in_the_setup_error(monkeypatch, tmp_path):
    from quadcog.errors import MissingDependencyError
    monkeypatch.setenv("QUADCOG_AQB", str(tmp_path / "nowhere"))
    with pytest.raises(MissingDependencyError, match="QUADCOG_AQB"):
        prepare()
    assert "make aqb" in SETUP_LINE and os.environ["QUADCOG_AQB"].endswith("nowhere")
    assert Path(vendor_tarball()).name == TARBALL


# -- the published tables --------------------------------------------------------------------

@pytest.mark.parametrize("name", ["aqb", "aqb-physics", "aqb-flaws"])
def test_the_published_tables_are_the_runs(name):
    """docs/aqb.md holds the tables (and machine lines) of the files bench/publish.py copied
    from the runs into docs/measured/, never typed ones."""
    import importlib.util
    import json
    root = Path(__file__).resolve().parent.parent
    spec = importlib.util.spec_from_file_location("publish", root / "bench" / "publish.py")
    pub = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(pub)
    copy = pub.COPIES[name]
    if not copy.is_file():
        pytest.skip(f"{name} not published yet (make bench-aqb, python bench/publish.py {name})")
    data = json.loads(copy.read_text())
    page = pub.PAGES[name].read_text()
    assert pub.block(page, name) == pub.table_of(data["table"])
    assert pub.block(page, f"{name}-machine") == data["machine"]


# -- hostile input (third pass) -----------------------------------------------------------

def _params(**changes):
    import copy
    p = copy.deepcopy(AQB_QUAD_PARAMS)
    p.update(changes)
    return p


@pytest.mark.parametrize("key", ["mass", "Ixx", "k_m", "k_d", "tau_m", "rotor_speed_min",
                                 "rotor_speed_max", "Ixy"])
@pytest.mark.parametrize("value", [None, "1.0", True, np.array([1.0, 2.0]), 1 + 2j, 10**400,
                                   float("nan")])
def test_quad_params_numbers_are_checked_and_named(key, value):
    """Each number of quad_params is a real number or an InputError naming its key (was a raw
    TypeError/OverflowError for None, an array, a complex or a huge int; '1.0' and True were
    read as numbers; a NaN mass warned from sqrt)."""
    with pytest.raises(InputError, match=rf"quad_params\['{key}'\]"):
        vehicle_from_quad_params(_params(**{key: value}))


@pytest.mark.parametrize("key", ["rotor_speed_min", "rotor_speed_max"])
def test_a_negative_rotor_speed_limit_is_refused(key):
    """A negative rotor speed squared into a positive thrust limit: -1 rad/s as the maximum
    made a vehicle that cannot lift itself, without a word."""
    with pytest.raises(InputError, match=rf"quad_params\['{key}'\]"):
        vehicle_from_quad_params(_params(**{key: -1.0}))


@pytest.mark.parametrize("key, value", [
    ("rotor_directions", np.array([1.5, -1, 1, -1])),       # was truncated to 1
    ("rotor_directions", np.array([1, -1, np.nan, -1])),    # was a raw ValueError
    ("rotor_directions", "abcd"),                           # was a raw TypeError
    ("rotor_pos", [list(r) for r in AQB_QUAD_PARAMS["rotor_pos"].values()]),  # raw ValueError
    ("num_rotors", np.array([4, 4])),                       # was a raw ValueError
    ("num_rotors", 4.5)])
def test_quad_params_rotors_are_checked_and_named(key, value):
    with pytest.raises(InputError, match=rf"quad_params\['{key}'\]"):
        vehicle_from_quad_params(_params(**{key: value}))


def test_the_factory_checks_its_arguments_before_any_flight():
    from quadcog.aqb.adapter import aqb_controller_factory
    with pytest.raises(InputError, match="on_nonfinite"):      # was accepted until a call
        aqb_controller_factory(on_nonfinite="ignore")
    with pytest.raises(InputError, match="peer_factory"):      # was a raw TypeError later
        aqb_controller_factory(peer_factory=3)
    with pytest.raises(InputError, match="controller"):        # was a raw AttributeError
        aqb_controller_factory()(3, AQB_QUAD_PARAMS)


def test_a_time_gap_beyond_max_gap_is_refused_at_once():
    """A call 1e6 s after the previous one (a clock in ms, a jump) advanced the law's state
    in 1 ms Euler substeps: 1e9 evaluations, a hang. Now an InputError, nothing changed."""
    import time

    from quadcog.aqb.adapter import MAX_GAP, QuadcogAQBController
    c = QuadcogAQBController(AQB_QUAD_PARAMS, "composite")
    c.update(0.0, _state(), _flat())
    c.update(0.01, _state(), _flat())
    before = c.c.copy()
    start = time.perf_counter()
    with pytest.raises(InputError, match=r"^t: expected a time at most 1\.0 s after"):
        c.update(1e6, _state(), _flat())
    assert time.perf_counter() - start < 5.0
    np.testing.assert_array_equal(c.c, before)
    c.update(0.01 + MAX_GAP, _state(), _flat())       # the gap itself is allowed


@pytest.mark.parametrize("seed", [-1, 1.5, "42", None, 2**40, True])
def test_payload_trials_refuse_a_seed_numpy_refuses(seed):
    """Was a raw ValueError/TypeError from numpy's RandomState (None drew from the OS's
    entropy: trials that no seed repeats)."""
    with pytest.raises(InputError, match="^seed: expected an integer in"):
        payload_trials(2, seed=seed)


def test_payload_trials_check_the_vehicle_and_the_size():
    from quadcog.aqb.protocol import MAX_DRAWS
    from quadcog.errors import SizeError
    no_arm = _params()
    del no_arm["arm_length"]
    with pytest.raises(InputError, match=r"quad_params\['arm_length'\]"):   # raw KeyError
        payload_trials(2, quad_params=no_arm)
    with pytest.raises(InputError, match=r"quad_params\['mass'\]"):         # NaN payloads
        payload_trials(2, quad_params=_params(mass=float("nan")))
    with pytest.raises(SizeError, match="draws"):          # was a hang, draws linear in it
        payload_trials(2, intensity=float(MAX_DRAWS))
    with pytest.raises(SizeError, match="draws"):
        payload_trials(MAX_DRAWS + 1)

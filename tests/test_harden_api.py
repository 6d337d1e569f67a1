"""Issue 21, the public API: rigid bodies only (the triangle inequality of the principal
inertias about the CoG, written here from the textbook), strings that reach generated C
checked or escaped (the header compiled by the C compiler as the oracle), and typed errors,
never a traceback or a NaN, for hostile arguments to vehicles, layouts, controllers, the model
and the manifest."""
import json
import shutil
import subprocess
import tempfile

from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir
import numpy as np
import pytest

import quadcog
from quadcog.controllers.registry import make_controller
from quadcog.embedded import export_controller
from quadcog.embedded.c_text import comment_text
from quadcog.embedded.controller_export import render
from quadcog.errors import (
    ExportError,
    GeneratedFilesError,
    InputError,
    ParameterError,
    PhysicalConsistencyError,
    QuadcogError,
)
from quadcog.vehicles.vehicle import HUMMINGBIRD, plus_layout, x_layout

set_hypothesis_home_dir(tempfile.mkdtemp(prefix="quadcog-hypothesis-"))
SETTINGS = dict(derandomize=True, database=None, deadline=None, max_examples=60,
                suppress_health_check=list(HealthCheck))
HOSTILE = st.one_of(st.none(), st.booleans(), st.text(max_size=5), st.integers(),
                    st.just(10 ** 400), st.floats(), st.complex_numbers(),
                    st.lists(st.floats(), max_size=5), st.dictionaries(st.text(max_size=2),
                                                                      st.integers(), max_size=2),
                    st.just({1, 2}), st.just([[0.0] * 6, [0.0] * 5]))


def _textbook_rigid(m, I_O, r):
    """Whether a Vehicle with principal inertias I_O and CoG offset r is accepted: I_O is that
    of a rigid body (each principal inertia below the sum of the other two; Goldstein,
    Classical Mechanics, sec. 5.3), and the paper's model admits the offset: the inertia about
    the CoG (parallel-axis theorem, I_G = I_O - m(|r|^2 1 - r r^T)) keeps at least 1 % of I_O
    in every direction. Returns (accepted, distance to the nearest rim, relative)."""
    r = np.asarray(r, float)
    a, b, c = sorted(I_O)
    I_G = np.diag(I_O) - m * (r @ r * np.eye(3) - np.outer(r, r))
    s = np.diag(1 / np.sqrt(I_O))
    ratio = np.linalg.eigvalsh(s @ I_G @ s)[0]
    return c < a + b and ratio >= 0.01, min((a + b - c) / c, ratio - 0.01)


def test_izz_beyond_ixx_plus_iyy_is_refused_in_those_terms():
    with pytest.raises(PhysicalConsistencyError, match="triangle inequality"):
        HUMMINGBIRD.replace(Izz=0.015)       # 0.015 > 0.007 + 0.007
    HUMMINGBIRD.replace(Izz=0.0139)          # just inside


@settings(**SETTINGS)
@given(I=st.tuples(*[st.floats(1e-3, 2e-2)] * 3), r=st.tuples(*[st.floats(-0.06, 0.06)] * 3))
def test_property_vehicle_accepted_exactly_when_a_rigid_body_has_it(I, r):
    ok, margin = _textbook_rigid(0.68, I, r)
    assume(abs(margin) > 1e-6)               # not on the rim, where round-off decides
    make = lambda: HUMMINGBIRD.replace(Ixx=I[0], Iyy=I[1], Izz=I[2], x_G=r[0], y_G=r[1],
                                       z_G=r[2])
    if ok:
        assert np.isfinite(make().parameters()).all()
    else:
        with pytest.raises(ParameterError):
            make()


@pytest.mark.parametrize("field, value", [("m", 10 ** 400), ("Ixx", -(10 ** 400)),
                                          ("m", "0.68"), ("g", None), ("Izz", 1j),
                                          ("name", 5), ("rotor_positions", "abcd")])
def test_vehicle_fields_of_the_wrong_kind(field, value):
    with pytest.raises(InputError, match=field):
        HUMMINGBIRD.replace(**{field: value})


@pytest.mark.parametrize("call", [
    lambda: HUMMINGBIRD.with_cog(["a", 0, 0]), lambda: HUMMINGBIRD.rotor_thrusts("abcd"),
    lambda: HUMMINGBIRD.rotor_thrusts([np.nan, 0, 0, 0]), lambda: plus_layout(None),
    lambda: x_layout(np.inf), lambda: plus_layout(-1.0), lambda: x_layout("0.2")])
def test_vehicle_helpers_refuse_instead_of_nan(call):
    with pytest.raises(InputError):
        call()


@pytest.mark.parametrize("directions", [[[1, -1], [1, -1]], [1, [-1], 1, -1], "1-11",
                                        [1, -1, 1], [True, -1, 1, -1]])
def test_rotor_directions_of_the_wrong_shape_are_an_input_error(directions):
    with pytest.raises(InputError, match="rotor_directions"):
        HUMMINGBIRD.replace(rotor_directions=directions)


def test_rotor_speeds_of_a_finite_thrust_are_finite():
    """sqrt(f / k) overflowed to inf for f = 1e308 N (f / k beyond the float range); the
    oracle is sqrt(f) / sqrt(k) in Python's math."""
    import math
    k = HUMMINGBIRD.thrust_constant
    for f in (1e308, 1.7e308, 1.0, 1e-300):
        w = HUMMINGBIRD.rotor_speeds([f] * 4)
        assert np.isfinite(w).all()
        assert w[0] == pytest.approx(math.sqrt(f) / math.sqrt(k), rel=1e-15)


def test_rotor_thrusts_near_the_float_range_raise_rather_than_return_nan():
    with pytest.raises(InputError, match="overflow"):
        HUMMINGBIRD.rotor_thrusts([1e308, 1e308, 1e308, 1e308])
    f = HUMMINGBIRD.rotor_thrusts([1e300, 0, 0, 0])       # the mixer's first column: 1/4
    assert np.allclose(f, 0.25e300, rtol=1e-12)


def test_a_minimum_snap_out_of_range_is_named_by_its_waypoints_not_its_address():
    from quadcog.trajectories.waypoints import MinimumSnap
    traj = MinimumSnap([[0, 0, 0], [1, 0, 0], [2, 0, 0]], times=[0, 1e6 - 1, 1e6])
    with pytest.raises(InputError, match=r"MinimumSnap\(3 waypoints from 0.0 s to 1000000.0 s\)"):
        traj.sample(np.linspace(0, 1e6, 50))


@pytest.mark.parametrize("path", [None, 5, b"cf2x.urdf", [], "", 1.5, {"a": 1}])
@pytest.mark.parametrize("reader", ["from_file", "from_urdf", "from_sdf"])
def test_vehicle_files_refuse_what_is_not_a_path(reader, path):
    from quadcog.errors import VehicleFileError
    from quadcog.vehicles.vehicle import Vehicle
    with pytest.raises(VehicleFileError, match="path"):
        getattr(Vehicle, reader)(path)


def test_vehicle_files_never_open_a_fifo_or_a_device(tmp_path):
    """Opening a FIFO to read blocks until a writer comes (the reader hung for ever); a
    device never ends. The alarm turns a hang into a failure here."""
    import os
    import signal

    from quadcog.errors import VehicleFileError
    from quadcog.vehicles.vehicle import Vehicle
    fifo = tmp_path / "v.urdf"
    os.mkfifo(fifo)

    def hung(*_):
        raise AssertionError("the reader blocked on a FIFO")
    old = signal.signal(signal.SIGALRM, hung)
    signal.alarm(10)
    try:
        for path, reader in ((fifo, "from_urdf"), (fifo, "from_file"),
                             ("/dev/zero", "from_sdf")):
            with pytest.raises(VehicleFileError, match="not a regular file"):
                getattr(Vehicle, reader)(path)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


@settings(**SETTINGS)
@given(value=HOSTILE, where=st.sampled_from(["with_cog", "rotor_thrusts", "plus", "x"]))
def test_property_vehicle_helpers_error_or_finite(value, where):
    call = {"with_cog": HUMMINGBIRD.with_cog, "rotor_thrusts": HUMMINGBIRD.rotor_thrusts,
            "plus": plus_layout, "x": x_layout}[where]
    try:
        out = call(value)
    except QuadcogError:
        return
    arr = out.parameters() if hasattr(out, "parameters") else np.asarray(out, float)
    assert np.isfinite(arr).all()


@pytest.fixture(scope="module")
def fl():
    return make_controller("fl")


@pytest.mark.parametrize("x", ["abc", np.zeros(12) + 1j, set(range(12)),
                               [[0.0] * 6, [0.0] * 5], None, {"x": 1}])
def test_controller_call_with_a_bad_state(fl, x):
    with pytest.raises(InputError, match="x"):
        fl(0.0, x, np.zeros(14))


def test_controller_at_a_1e200_velocity_is_an_error_not_nan(fl):
    x = np.zeros(12)
    x[6] = 1e200
    with pytest.raises(InputError, match=r"not finite.*x\[6\] = 1e\+200"):
        fl(0.0, x, np.zeros(14))


@settings(**SETTINGS)
@given(k=st.integers(0, 11), v=st.sampled_from([1e3, 1e10, 1e100, 1e200, 1e300, -1e308]))
def test_property_controller_returns_finite_or_says_why(fl, k, v):
    x = np.zeros(12)
    x[k] = v
    try:
        U, _ = fl(0.0, x, np.zeros(14))
    except InputError:
        return
    assert np.isfinite(U).all()


@pytest.mark.parametrize("bad", [{}, "a", [1.0], None])
def test_model_dynamics_with_a_bad_entry_in_p(bad):
    model = quadcog.load()
    p = list(quadcog.default_parameters()[:13]) + [bad]
    with pytest.raises(InputError, match="p"):
        model.dynamics(np.zeros(12), np.zeros(4), p)


def test_a_manifest_lacking_a_function_is_a_generated_files_error(tmp_path):
    folder = tmp_path / "generated"
    shutil.copytree(quadcog.paths.generated_dir(), folder)
    manifest = json.loads((folder / "manifest.json").read_text())
    manifest["functions"].pop("dynamics")
    (folder / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(GeneratedFilesError, match="lists no function 'dynamics'"):
        quadcog.load(folder).dynamics(np.zeros(12), np.zeros(4), quadcog.default_parameters())


# -- strings that reach generated C -----------------------------------------------------
INJECTIONS = ["a */ b\n#error boom", "*/ int x = 1; /*", "/*/", "x\\\n#error spliced",
              "??/\n#error trigraph", "é ünïcode \u2603 \U0001F600", "\x00\x07\r\n", "*" * 500 + "/"]


def _syntax_ok(header, tmp_path):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    h = tmp_path / "quadcog_pd.h"
    h.write_text(header)
    src = tmp_path / "use.c"
    src.write_text('#include "quadcog_pd.h"\nint main(void) { return QUADCOG_PD_NC; }\n')
    res = subprocess.run([cc, "-std=c99", "-trigraphs", "-fsyntax-only", "-Wall",
                          "-Werror", str(src)], capture_output=True, text=True, cwd=tmp_path)
    return res.returncode == 0, res.stderr


@pytest.fixture(scope="module")
def pd():
    return make_controller("pd")


@pytest.mark.parametrize("command", INJECTIONS)
def test_command_cannot_close_the_comment(pd, command, tmp_path):
    header = render(pd, "float32", "pd", command)["quadcog_pd.h"]
    ok, err = _syntax_ok(header, tmp_path)
    assert ok, err              # a closed comment would expose "#error" or "int x"
    line = next(x for x in header.splitlines() if "written by `" in x)
    named = line.split("written by `", 1)[1].rsplit("` from the controllers", 1)[0]
    assert "*/" not in named and "/*" not in named


@settings(**dict(SETTINGS, max_examples=15))
@given(command=st.text(alphabet=st.sampled_from(list("*/\\?\n\r #error\"'") + ["\x00", "é"]),
                       max_size=40))
def test_property_any_command_keeps_the_header_valid_c(pd, command):
    header = render(pd, "float32", "pd", command)["quadcog_pd.h"]
    with tempfile.TemporaryDirectory() as d:
        from pathlib import Path
        ok, err = _syntax_ok(header, Path(d))
    assert ok, (command, err)


@settings(**SETTINGS)
@given(text=st.text(max_size=60))
def test_property_comment_text_is_inert(text):
    safe = comment_text(text)
    assert "*/" not in safe and "/*" not in safe and "\n" not in safe
    assert all(32 <= ord(ch) < 127 for ch in safe)


@pytest.mark.parametrize("kwargs, text", [({"name": 5}, "name"), ({"name": "a b"}, "name"),
                                          ({"name": "pd;x"}, "name"), ({"name": "é"}, "name"),
                                          ({"name": "x" * 100}, "name"),
                                          ({"out": None}, "out"), ({"command": 5}, "command")])
def test_export_arguments_are_typed_errors(kwargs, text, tmp_path):
    kwargs.setdefault("out", tmp_path)
    with pytest.raises(ExportError, match=text):
        export_controller("pd", **kwargs)
    assert not list(tmp_path.glob("quadcog_*"))


# -- --set and scheduler addresses: any text is a typed error or a valid value ---------
SET_KEYS = ["controller", "duration", "dt", "vehicle.m", "vehicle.Izz", "sensing",
            "sensing.seed", "cog[0].r", "cog[0].t", "controller_params.gamma", "trajectory",
            "trajectory.max_speed", "initial_offset"]
SET_VALUES = ["-1", "1e-300", "1e300", "nan", "[1, 2]", '["pd"]', "{seed=-1}", "{}", "[]",
              "true", "'x'", "[0, 1e-300]", "1" + "0" * 400, "{kind='waypoints', "
              "waypoints=[[0,0,1],[1,0,1]], times=[0, 1e-300]}", "{kind='waypoints', "
              "waypoints=[[0,0,1],[1,0,1]], max_speed=1e-300}"]


@settings(**dict(SETTINGS, max_examples=80))
@given(key=st.sampled_from(SET_KEYS), value=st.sampled_from(SET_VALUES))
def test_property_set_is_refused_up_front_or_flies(key, value):
    from quadcog.scenarios.scenario import load_scenario
    try:
        s = load_scenario("fig3a", [f"{key}={value}", "duration=0.05"])
        s.make_controller()
        s.trajectory(0.0)
    except QuadcogError:
        return


def test_sensing_seed_out_of_range_named_up_front():
    from quadcog.scenarios.scenario import load_scenario
    with pytest.raises(QuadcogError, match="seed"):
        load_scenario("fig3a", ["sensing={seed=-1}"])


@settings(**SETTINGS)
@given(text=st.text(alphabet=st.sampled_from(list("tcp:/[]0123456789.ahl-") + [" "]),
                    max_size=24))
def test_property_scheduler_address_parses_or_is_refused(text):
    from quadcog.errors import SchedulerError
    from quadcog.sweeps.scheduler import parse_address
    try:
        host, port = parse_address(text)
    except SchedulerError:
        return
    assert host and 1 <= port <= 65535

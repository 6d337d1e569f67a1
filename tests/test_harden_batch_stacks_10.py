"""Tenth hostile pass on the batch API and the stacks' trees (issue 33).

- ``simulate_batch`` flew a step RK4 cannot take (dt beyond the motor time constant: every
  flight "diverged"), took any number of flights (an unbounded iterator was listed without
  end), dropped the y and z of a CoGProfile cog_shape and said nothing of a disturbance after
  the end, as ``simulate`` does.
- ``fly_batch`` checked none of its arguments: raw ValueError, IndexError, AttributeError,
  an unknown kernel flown by CasADi, a start beyond the scale or diverged flown to "diverged",
  CoG increments where no rigid body is flown.
- The PX4 tree's copy into the cache raised shutil.Error on a FIFO in the user's tree and left
  its half-made copy; ``firmware_tree("")`` fell back to the tarball and a non-path raised a
  raw TypeError.
"""
import itertools
import os
from pathlib import Path
import warnings

import numpy as np
import pytest

import quadcog as q
from quadcog.errors import InputError, ParameterError, StackError
from quadcog.sim.vector_batch import fly_batch

V = q.HUMMINGBIRD
FLIGHTS = [V.with_cog([0.01, 0, 0]), V.with_cog([0, 0.01, 0])]


@pytest.fixture(scope="module")
def law():
    return q.FeedbackLinearization(V)


def test_a_batch_refuses_a_step_rk4_cannot_take_as_simulate_does(law):
    lag = q.TruthOptions(motor_lag=True)
    with pytest.raises(InputError, match=r"vehicles\[0\]: dt = 0.05 s is too large"):
        q.simulate_batch(law, FLIGHTS, duration=0.5, dt=0.05, truth=lag)


def test_each_flight_of_a_batch_has_its_step_checked_and_the_first_bad_one_named(law):
    """The flights' closed loops differ with their CoG: the rule of ``check_step_size``,
    applied here flight by flight, names the first flight dt is too large for; the batch's
    mapped check (norm bound, then eigenvalues) must name the same one, past flight 0."""
    from quadcog.sim.batch import check_step_sizes
    from quadcog.sim.plant import Actuation
    from quadcog.sim.prepare import check_step_size
    rng = np.random.default_rng(1)
    P = np.array([V.with_cog([*rng.uniform(-0.06, 0.06, 2), 0.0]).parameters()
                  for _ in range(200)])
    act = Actuation.of(V, q.TruthOptions())
    x0, ref0 = np.zeros(12), np.zeros(14)
    for dt in (0.001, 0.05):
        first = None
        for b in range(len(P)):
            try:
                check_step_size(law, x0, ref0, P[b], dt, act)
            except InputError:
                first = b
                break
        if first is None:
            check_step_sizes(law, x0, ref0, P, dt, act)
        else:
            assert first > 0
            with pytest.raises(InputError, match=rf"vehicles\[{first}\]: dt = {dt} s is too"):
                check_step_sizes(law, x0, ref0, P, dt, act)
    assert first is not None


def test_a_batch_of_more_flights_than_the_limit_is_refused_with_its_memory(law):
    with pytest.raises(InputError, match=r"vehicles: expected at most 1,000,000 flights .*"
                                         r"got 10,000,000 flights, about .* GiB"):
        q.simulate_batch(law, [V] * 10_000_000, duration=0.05)
    with pytest.raises(InputError, match="more than 1,000,000 flights"):
        q.simulate_batch(law, itertools.repeat(V), duration=0.05)


@pytest.mark.parametrize("vehicles, named", [(set(FLIGHTS), "vehicles: expected"),
                                             ([V, None], r"vehicles\[1\]: expected a quadcog "
                                                         r"Vehicle, got None")])
def test_a_batch_names_vehicles_without_an_order_or_not_vehicles(law, vehicles, named):
    with pytest.raises(InputError, match=named):
        q.simulate_batch(law, vehicles, duration=0.05)


def test_a_cog_profile_shape_off_x_is_refused_not_dropped(law):
    shape = q.CogProfile([q.CogChange(0.02, (0.0, 1.0, 0.0), 0.0)])
    with pytest.raises(InputError, match=r"cog_shape change 0: expected a shape in x alone"):
        q.simulate_batch(law, FLIGHTS, duration=0.05, cog_shape=shape)


def test_a_batch_says_a_disturbance_after_the_end_never_happens(law):
    late = [q.Disturbance(5.0, 0.02, force=(1.0, 0.0, 0.0))]
    with pytest.warns(q.QuadcogWarning, match="after the end of the run"):
        q.simulate_batch(law, FLIGHTS, duration=0.05, disturbances=late)


@pytest.mark.parametrize("change, named", [
    (dict(controller=None), "controller: expected a quadcog Controller, got None"),
    (dict(vehicles=[]), "vehicles: expected a non-empty sequence"),
    (dict(D="x"), r"D: expected an array of shape \(2, 3\)"),
    (dict(D=np.zeros((3, 0))), r"D: expected an array of shape \(2, 3\)"),
    (dict(cog_times=[(0.02,)]), r"cog_times\[0\]: expected an array of shape \(2,\)"),
    (dict(cog_times="x"), "cog_times: expected a sequence"),
    (dict(kernel="x"), "kernel: expected one of"),
    (dict(precision=None), "precision: expected one of"),
    (dict(threads=0), r"threads: expected an integer in \[1, 1024\]"),
    (dict(x0=np.full(12, 1e7)), "x0: expected 12 finite numbers within"),
    (dict(x0=np.array([0, 0, 0, 0, 1.5708] + [0] * 7)), "has already diverged"),
])
def test_fly_batch_names_a_hostile_argument(law, change, named):
    args = dict(controller=law.for_vehicle(V), vehicles=FLIGHTS, D=np.zeros((2, 3)),
                duration=0.05, cog_times=[(0.02, 0.0)])
    args.update(change)
    with pytest.raises(InputError, match=named):
        fly_batch(**args)


def test_fly_batch_refuses_increments_where_no_rigid_body_is(law):
    D = np.array([[0.0, 0.0, 0.0], [1e3, 0.0, 0.0]])
    with pytest.raises(ParameterError, match=r"vehicles\[1\] with the CoG increments D\[1\] "
                                             r"at t = 0.02 s"):
        fly_batch(law.for_vehicle(V), FLIGHTS, D, duration=0.05, cog_times=[(0.02, 0.0)])
    with warnings.catch_warnings():         # increments within reach still fly
        warnings.simplefilter("error")
        r = fly_batch(law.for_vehicle(V), FLIGHTS, np.full((2, 3), 0.005), duration=0.05,
                      cog_times=[(0.02, 0.01)])
    assert not r.diverged.any() and np.isfinite(r.rms_position_error).all()


def test_a_px4_tree_with_a_fifo_is_copied_without_it_and_without_a_leftover(tmp_path):
    from quadcog.px4 import tree
    user = tmp_path / "PX4-Autopilot"
    (user / "ROMFS").mkdir(parents=True)
    (user / "Makefile").write_text("all:\n")
    (user / "src").mkdir()
    (user / "src" / "a.c").write_text("int a;\n")
    os.mkfifo(user / "src" / "pipe")
    cache = tmp_path / "cache"
    cache.mkdir()
    copy = tree._unpack(tree.find_source(str(user)), cache)
    assert sorted(p.name for p in copy.rglob("*")) == ["Makefile", "ROMFS", "a.c", "src"]
    assert sorted(p.name for p in cache.iterdir()) == ["PX4-Autopilot"]
    assert (user / "src" / "pipe").is_fifo()


def test_a_failed_px4_tree_copy_is_a_px4_error_and_leaves_nothing(tmp_path, monkeypatch):
    import shutil

    from quadcog.errors import Px4Error
    from quadcog.px4 import tree
    user = tmp_path / "PX4-Autopilot"
    (user / "ROMFS").mkdir(parents=True)
    (user / "Makefile").write_text("all:\n")
    cache = tmp_path / "cache"
    cache.mkdir()

    def broken(src, dst, **kw):
        Path(dst).mkdir(parents=True)
        raise shutil.Error([(str(src), str(dst), "cannot read")])
    monkeypatch.setattr(tree.shutil, "copytree", broken)
    with pytest.raises(Px4Error, match="cannot copy the tree into the cache"):
        tree._unpack(tree.find_source(str(user)), cache)
    assert list(cache.iterdir()) == []


@pytest.mark.parametrize("firmware", ["", 5, b"/tmp", ["x"]])
@pytest.mark.parametrize("module", ["quadcog.crazyflie.firmware",
                                    "quadcog.embedded.crazyflie_firmware"])
def test_firmware_tree_refuses_what_is_no_path(firmware, module):
    """Both finders of the firmware (the loop's and the app build's) share locate_tree: ""
    fell back to the tarball, a non-path raised a raw TypeError."""
    import importlib
    firmware_tree = importlib.import_module(module).firmware_tree
    with pytest.raises(StackError, match="^firmware: expected None or the path of a Crazyflie "
                                         "firmware tree, got"):
        firmware_tree(firmware)


def test_a_step_longer_than_the_run_is_named_in_the_validate_grammar():
    """It said "dt = 0.001 s is longer than the duration 1e-12 s", not where and what."""
    with pytest.raises(InputError, match=r"^dt: expected a step no longer than the duration "
                                         r"\(1e-12 s\), got 0.001$"):
        q.simulate(q.CascadePD(), duration=1e-12)


def test_a_quoted_tilde_in_the_vendor_folder_is_the_home_folder(monkeypatch):
    """QUADCOG_VENDOR_DIR='~/vendor' (quoted, so the shell left the ~) was read as a folder
    named ~ in the current folder."""
    from quadcog.codegen.third_party import VENDOR_ENV, vendor_dir
    monkeypatch.setenv(VENDOR_ENV, "~/vendor")
    assert vendor_dir() == Path.home() / "vendor"

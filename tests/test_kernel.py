"""The vector batch kernel: metrics equal to the single-flight path, bits independent of threads
and of the other flights in the batch, the thread count asked for, and C that gcc vectorizes."""
import platform
import shutil
import subprocess
import threading

import numpy as np
import pytest

import quadcog
from quadcog.codegen.vector_kernel import emit_c, vector_flags
import quadcog.sim.batch as batch_module
from quadcog.sim.batch import batch_kernel
from quadcog.sim.closed_loop import monitored_step, packed
from quadcog.sim.divergence import Limits
from quadcog.sim.plant import Actuation

SHAPE = 0.3                      # s: the CoG steps at this time
METRICS = ("rms_position_error", "max_position_error", "rms_position_error_tail",
           "final_position_error")


def _vehicles():
    """19 flights (not a whole number of 16-flight blocks), CoG steps up to 9.5 cm: some
    recover, some do not."""
    rng = np.random.default_rng(3)
    r = rng.uniform(-0.067, 0.067, (19, 2))
    return [quadcog.HUMMINGBIRD.with_cog((x, y, 0.0)) for x, y in r]


@pytest.mark.parametrize("controller", [quadcog.AdaptiveFeedbackLinearization(),
                                        quadcog.FeedbackLinearization()],
                         ids=["adaptive", "fl"])
def test_batch_metrics_equal_the_single_flight_path(controller):
    vehicles = _vehicles()
    b = quadcog.simulate_batch(controller, vehicles, duration=2.5,
                               cog_shape=lambda t: float(t >= SHAPE), threads=2)
    for i in (0, 5, 17, 18):
        v = vehicles[i]
        m = quadcog.simulate(controller, duration=2.5, vehicle=v.with_cog(np.zeros(3)),
                             cog=quadcog.CogProfile.step(SHAPE, v.r_G)).metrics
        assert b.diverged[i] == m.diverged
        for name in METRICS:
            # libmvec's sin/cos/tan/atan2 are within 4 ulp of glibc's; over 2500 steps of a
            # stable loop that stays far below 1e-9
            assert getattr(b, name)[i] == pytest.approx(getattr(m, name), rel=1e-9, abs=1e-12)


def test_bits_do_not_depend_on_threads_or_on_the_other_flights():
    ctl = quadcog.AdaptiveFeedbackLinearization()
    vehicles = _vehicles()
    shape = lambda t: float(t >= SHAPE)
    all1 = quadcog.simulate_batch(ctl, vehicles, duration=1.0, cog_shape=shape, threads=1)
    all3 = quadcog.simulate_batch(ctl, vehicles, duration=1.0, cog_shape=shape, threads=3)
    alone = quadcog.simulate_batch(ctl, vehicles[17:18], duration=1.0, cog_shape=shape)
    assert all1.final_state.tobytes() == all3.final_state.tobytes()
    assert all1.final_state[17].tobytes() == alone.final_state[0].tobytes()


def test_threads_means_that_many_threads():
    ctl = quadcog.FeedbackLinearization()
    actuation, limits = Actuation.of(ctl.vehicle), Limits()
    kernel = batch_kernel(ctl, actuation, limits)
    if kernel is None:
        pytest.skip("no vector kernel here")
    seen, fn = set(), kernel._fn

    def record(*args):
        seen.add(threading.current_thread().name)      # unique per thread started
        return fn(*args)
    kernel._fn = record
    try:
        quadcog.simulate_batch(ctl, [quadcog.HUMMINGBIRD] * 100, duration=0.05, threads=3)
    finally:
        kernel._fn = fn
    assert len(seen) == 3


def test_casadi_fallback_agrees(monkeypatch):
    """1.55 s: the CasADi map runs whole chunks of 1000 steps, so the second one is padded;
    padding steps must change nothing and count for nothing."""
    ctl = quadcog.FeedbackLinearization()
    vehicles = _vehicles()[:5]
    shape = lambda t: float(t >= SHAPE)
    k = quadcog.simulate_batch(ctl, vehicles, duration=1.55, cog_shape=shape, threads=2)
    monkeypatch.setattr(batch_module, "kernel_for", lambda *a, **kw: None)
    c = quadcog.simulate_batch(ctl, vehicles, duration=1.55, cog_shape=shape, threads=2)
    assert np.array_equal(k.diverged, c.diverged)
    for name in METRICS:
        assert np.allclose(getattr(k, name), getattr(c, name), rtol=1e-9, atol=1e-12)


@pytest.mark.skipif(platform.machine() != "x86_64" or shutil.which("cc") is None,
                    reason="checks gcc's x86-64 vectorizer")
def test_gcc_vectorizes_the_step_with_libmvec(tmp_path):
    ctl = quadcog.FeedbackLinearization()           # sin, cos, tan, atan2 like the others
    actuation = Actuation.of(ctl.vehicle)
    src = tmp_path / "k.c"
    src.write_text(emit_c(packed(monitored_step(ctl, actuation, Limits()))))
    flags = [f for f in vector_flags() if f not in ("-shared", "-fPIC")]
    r = subprocess.run(["cc", *flags, "-fopt-info-vec-optimized", "-c", str(src), "-o",
                        str(tmp_path / "k.o")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    assert "loop vectorized" in r.stderr, r.stderr[-2000:]
    nm = subprocess.run(["nm", str(tmp_path / "k.o")], capture_output=True, text=True).stdout
    assert "_ZGV" in nm and "sin" in nm, nm          # libmvec's vector sin, not a scalar loop


@pytest.mark.parametrize("name", sorted(quadcog.controllers.BY_NAME))
def test_every_controller_has_a_vector_form(name):
    """emit_c refuses operations it cannot vectorize (the batch would fall back to CasADi's
    map): every shipped controller's step must translate."""
    ctl = quadcog.make_controller(name)
    assert "#pragma omp simd" in emit_c(packed(monitored_step(ctl, Actuation.of(ctl.vehicle), Limits())))


@pytest.mark.parametrize("kernel", ["vector", "casadi"])
def test_sweep_engine_equals_single_flights(kernel):
    """The sweep engine (per-flight CoG steps, quadcog.sim.vector_batch) on both of its paths, at
    1.55 s (the CasADi map pads its second chunk), against single flights."""
    from quadcog.sim.vector_batch import fly_batch
    ctl = quadcog.AdaptiveFeedbackLinearization()
    D = np.array([[0.03, 0.0, 0.0], [0.0, 0.04, 0.0], [0.05, 0.05, 0.0]])
    b = fly_batch(ctl, [quadcog.HUMMINGBIRD] * 3, D, duration=1.55, cog_times=[(SHAPE, 0.0)],
                  kernel=kernel)
    for i in range(3):
        m = quadcog.simulate(ctl, duration=1.55, cog=quadcog.CogProfile.step(SHAPE, D[i])).metrics
        assert b.diverged[i] == m.diverged
        for name in METRICS:
            assert getattr(b, name)[i] == pytest.approx(getattr(m, name), rel=1e-9, abs=1e-12)

"""The vector batch kernel: metrics equal to the single-flight path, bits independent of threads
and of the other flights in the batch, the thread count asked for, and C that gcc vectorizes."""
import platform
import shutil
import subprocess
import threading

import casadi as ca
import numpy as np
import pytest

import quadcog
from quadcog.codegen import hoisting
import quadcog.codegen.vector_kernel as qk
from quadcog.codegen.vector_kernel import emit_c, vector_flags
import quadcog.sim.batch as batch_module
from quadcog.sim.batch import batch_kernel, slow_row_entries
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
@pytest.mark.parametrize("isa", ["sse2", "avx2", "avx512"])
def test_gcc_vectorizes_the_step_with_libmvec(tmp_path, isa):
    """Every loop of the kernel (once per call, on a change of the CoG, each step) is vector
    code for each x86 ISA, whatever this CPU runs (compiled only), as VectorKernel emits it:
    with libmvec's atan2 of that ISA, and on AVX2 and AVX-512 the sines and cosines inline
    (no vector call of libmvec's sin or cos: those spill every register; on SSE2 the inline
    ones would leave the loop scalar); and the step loop keeps few divisions (hoisted, or
    through reciprocals: 170 without)."""
    ctl = quadcog.FeedbackLinearization()           # sin, cos, tan, atan2 like the others
    actuation = Actuation.of(ctl.vehicle)
    inline = isa in qk.INLINE_TRIG_ISAS
    text = emit_c(packed(monitored_step(ctl, actuation, Limits())), slow=slow_row_entries(),
                  trig="inline" if inline else "libm", fma=isa in qk.FMA_ISAS)
    src = tmp_path / "k.c"
    src.write_text(text)
    flags = [f for f in vector_flags(isa) if f not in ("-shared", "-fPIC")]
    r = subprocess.run(["cc", *flags, "-fopt-info-vec-all", "-c", str(src), "-o",
                        str(tmp_path / "k.o")], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr[-2000:]
    vectorized = r.stderr.count("optimized: loop vectorized")
    assert text.count("#pragma omp simd") == 3 and vectorized >= 3, r.stderr[-2000:]
    assert "not vectorized: control flow" not in r.stderr, r.stderr[-2000:]
    nm = subprocess.run(["nm", str(tmp_path / "k.o")], capture_output=True, text=True).stdout
    abi = {"sse2": "_ZGVb", "avx2": "_ZGVd", "avx512": "_ZGVe"}[isa]
    assert any(s.startswith(abi) and s.endswith("_atan2") for s in nm.split()), nm
    libmvec_sines = any(s.startswith(abi) and s.endswith(("_sin", "_cos")) for s in nm.split())
    assert libmvec_sines != inline, nm
    assert (text.count("qc_sin(") >= 3 and text.count("qc_cos(") >= 3) == inline
    step_loop = text[text.rindex("#pragma omp simd"):]
    assert step_loop.count(" / ") <= 20


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


def test_hoisting_changes_no_bit(monkeypatch):
    """What the kernel computes once per call or on a change of the slow row entries (the CoG
    profile, the payloads) gives the bits of computing it every step (without reciprocals,
    hoisting reorders no rounding): a CoG that ramps (it changes every step for 0.1 s, then
    stays) over 400 steps, flown with and without hoisting. A hoisted value left stale after
    a change, a change not detected, or a step value hoisted would differ."""
    import functools

    import quadcog.codegen.vector_kernel as qk
    from quadcog.sim.prepare import batch_start, start_at_reference, whole_body
    from quadcog.sim.schedule import Schedule
    from quadcog.sim.timeline import PayloadProfile
    from quadcog.sim.vector_batch import cog_shapes, sweep_step
    from quadcog.trajectories.registry import as_trajectory
    monkeypatch.setattr(qk, "emit_c", functools.partial(qk.emit_c, reciprocals=False))
    ctl = quadcog.AdaptiveFeedbackLinearization()
    actuation = Actuation.of(ctl.vehicle)
    step = packed(sweep_step(ctl, actuation, Limits(), 1))
    hoisted = qk.VectorKernel(step, isa="portable", slow=slow_row_entries(1))
    plain = qk.VectorKernel(step, isa="portable")
    assert hoisted.library != plain.library
    schedule = Schedule.build(as_trajectory("circle"), 0.4, 1e-3,
                              payloads=PayloadProfile([], ()))
    shapes = cog_shapes(schedule.t, [(0.15, 0.1)])
    rng = np.random.default_rng(5)
    B = 11
    P = np.array([ctl.vehicle.airframe.parameters()] * B)
    Q = np.hstack([P, np.column_stack([rng.uniform(-0.05, 0.05, (B, 2)), np.zeros(B)])])
    Z = batch_start(ctl, actuation, whole_body(P, schedule.payload[0]),
                    start_at_reference(schedule.ref[0]))
    rows = schedule.rows(0, schedule.n_steps, shapes)
    a, b = hoisted(Z, Q, rows), plain(Z, Q, rows)
    assert np.all(np.isfinite(a)) and a.tobytes() == b.tobytes()
    assert not np.array_equal(a, plain(Z, Q, schedule.rows(0, schedule.n_steps, 0 * shapes)))


def test_fused_products_take_a_single_use_product_in_its_own_loop_only():
    """hoisting.fused_products: a product used once, in the same loop, by a sum that no math
    function takes; not one used twice, one computed in a hoisted loop, nor a sum that is a
    sine's argument."""
    Z, Q = ca.SX.sym("Z", 3), ca.SX.sym("Q", 2)
    once = Z[0] * Z[1] + Z[2]                 # fused
    twice_p = Z[0] * Z[2]
    twice = twice_p + Z[1]                    # not: its product is also an output
    hoisted = Q[0] * Q[1] + Z[0]              # not: the product runs once per call
    in_sin = ca.sin(Z[1] * Z[2] + Q[0])       # not: a math function takes the sum
    sub = Z[2] - Z[1] * Q[0]                  # fused, as the second operand
    f = ca.Function("f", [Z, Q], [ca.vertcat(once, twice, twice_p, hoisted, in_sin, sub)])
    lv = hoisting.levels(f, lambda i, nz: hoisting.CONSTANT if i == 1 else hoisting.STEP)
    fused = hoisting.fused_products(f, lv)
    kinds = {}
    for add, (mul, which) in fused.items():
        assert f.instruction_id(mul) == ca.OP_MUL and lv[mul] == lv[add] == hoisting.STEP
        kinds[f.instruction_id(add)] = which
    assert len(fused) == 2 and kinds == {ca.OP_ADD: 0, ca.OP_SUB: 1}, fused
    # and the kernel computes the fused forms to one rounding of the exact value
    if qk.detect_isa() in qk.FMA_ISAS and shutil.which("cc"):
        Zv = np.array([[0.1, 0.7, 0.3], [1e8 + 1, 1e8 - 1, -1e16]])
        got = qk.VectorKernel(ca.Function("g", [Z, Q, ca.SX.sym("r")], [ca.vertcat(once, sub, Z[2])]))(
            Zv, np.full((2, 2), 0.25), np.zeros((1, 1)))
        from fractions import Fraction as F
        for i, (x0, x1, x2) in enumerate(Zv):
            assert got[i, 0] == float(F(x0) * F(x1) + F(x2))
            assert got[i, 1] == float(F(x2) - F(x1) * F(0.25))

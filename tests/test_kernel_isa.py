"""The batch kernel at the CPU's vector width (quadcog.codegen.vector_kernel): the instruction set chosen from
the CPU's flags, the block of lanes matched to it, the portable rebuild when the compiler
refuses the flags, bits independent of threads and batch on every build, FMA only where no function takes the sum
(a sensed flight equals ``simulate``), and a float32 variant that really computes in float."""
from fractions import Fraction
import platform
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest

import quadcog
import quadcog.codegen.vector_kernel as qk
from quadcog.errors import InputError, QuadcogWarning
from quadcog.sim.closed_loop import monitored_step, packed
from quadcog.sim.divergence import Limits
from quadcog.sim.plant import Actuation
from quadcog.sim.vector_batch import fly_batch

X86 = platform.machine() == "x86_64"
needs_cc = pytest.mark.skipif(shutil.which("cc") is None or not X86,
                              reason="needs a C compiler on x86-64 (libmvec)")
METRICS = ("rms_position_error", "max_position_error", "rms_position_error_tail",
           "final_position_error")


def test_isa_follows_the_cpu_flags():
    base = {"sse", "sse2", "avx"}
    assert qk.detect_isa(base, "x86_64") == "sse2"
    assert qk.detect_isa(base | {"avx2"}, "x86_64") == "sse2"          # AVX2 without FMA
    assert qk.detect_isa(base | {"avx2", "fma"}, "x86_64") == "avx2"
    avx512 = base | {"avx2", "fma", "avx512f", "avx512dq", "avx512vl", "avx512bw"}
    assert qk.detect_isa(avx512, "x86_64") == "avx512"
    assert qk.detect_isa(avx512 - {"avx512bw"}, "x86_64") == "avx2"
    assert qk.detect_isa(avx512, "aarch64") == "portable"


def test_lanes_are_four_vectors_of_the_isa():
    # vector width in bits / element width in bits, four vectors per block
    for isa, bits in (("avx512", 512), ("avx2", 256), ("sse2", 128), ("portable", 128)):
        assert qk.lanes_for(isa) == 4 * bits // 64
        assert qk.lanes_for(isa, "float32") == 4 * bits // 32
    assert qk.LANES == qk.lanes_for("avx2")


def test_flags_name_the_isa_and_keep_contraction_off():
    assert {"-mavx2", "-mfma", "-ffp-contract=off"} <= set(qk.vector_flags("avx2"))
    assert "-mavx512f" in qk.vector_flags("avx512")
    assert not any(f.startswith("-m") for f in qk.vector_flags("portable"))
    assert "-fno-builtin-sinf" in qk.vector_flags("avx2", "float32")
    with pytest.raises(InputError, match="isa"):
        qk.vector_flags("avx1024")
    with pytest.raises(InputError, match="precision"):
        qk.vector_flags("avx2", "float16")


def test_float32_literals():
    assert qk._literal32(1e300) == "__builtin_inff()"
    assert qk._literal32(-1e39) == "(-__builtin_inff())"
    for v in (0.1, 1e-12, 43758.5453, -3.0, 2.0 ** -130):
        text = qk._literal32(v)
        assert text.endswith("f") and np.float32(text[:-1]) == np.float32(v)


def _step_fn():
    ctl = quadcog.FeedbackLinearization()
    return packed(monitored_step(ctl, Actuation.of(ctl.vehicle), Limits()))


@needs_cc
def test_the_compiler_refusing_the_flags_gives_the_portable_build(monkeypatch):
    native = qk.detect_isa()
    if native == "portable":
        pytest.skip("the portable build is the native one here")
    Z, Q, R = (ca.SX.sym(n, k) for n, k in (("Z", 2), ("Q", 1), ("r", 1)))
    step = ca.Function("f", [Z, Q, R], [ca.vertcat(ca.sin(Z[0]) * Q[0] + R[0], Z[1] * 0.5)])
    good = qk.VectorKernel(step, isa="portable")
    # a flag no gcc knows, in place of the native ISA's: the compiler refuses it
    monkeypatch.setitem(qk.ISA_FLAGS, native, ("-mquadcog-no-such-isa",))
    with pytest.warns(QuadcogWarning, match="refused"):
        k = qk.VectorKernel(step, isa=native)
    assert k.isa == "portable" and k.lanes == qk.lanes_for("portable")
    assert k.library == good.library
    Z0 = np.random.default_rng(0).normal(size=(13, 2))
    Q0 = np.full((13, 1), 0.7)
    rows = np.full((5, 1), 0.1)
    assert k(Z0, Q0, rows).tobytes() == good(Z0, Q0, rows).tobytes()


@needs_cc
@pytest.mark.parametrize("cpu, refused", [
    (("sse2", "avx", "avx2", "fma"), "avx512"),      # an AVX2 CPU (most users' machines)
    (("sse2",), "avx2"),                              # an old x86-64 CPU
])
def test_an_isa_the_cpu_lacks_is_refused(monkeypatch, cpu, refused):
    """Runs on any x86-64 machine: the CPU's flags are those of a narrower CPU, so an AVX-512
    machine checks the refusal an AVX2 machine makes (its instructions would stop the
    process with SIGILL there, not an error)."""
    monkeypatch.setattr(qk, "cpu_features", lambda: frozenset(cpu))
    assert qk.ISAS.index(qk.detect_isa()) > qk.ISAS.index(refused)
    with pytest.raises(qk.KernelError, match=f"isa='{refused}'"):
        qk.VectorKernel(_step_fn(), isa=refused)


@needs_cc
def test_the_isa_is_in_the_library_name_and_cache_key():
    step = _step_fn()
    a = qk.VectorKernel(step, isa="portable")
    b = qk.VectorKernel(step, isa=qk.detect_isa())
    assert "_portable_" in a.library.name and a.lanes == 8
    if b.isa != "portable":
        assert f"_{b.isa}_" in b.library.name and a.library != b.library


@pytest.mark.slow
@needs_cc
def test_avx512_build_uses_512_bit_vectors(tmp_path):
    """Compiled only (this CPU may lack AVX-512): gcc must emit zmm registers and libmvec's
    AVX-512 variants ('e' in the vector-ABI name), not 256-bit code (the sines through
    libmvec here, trig='libm', to see its variant)."""
    src = tmp_path / "k.c"
    src.write_text(qk.emit_c(_step_fn(), lanes=qk.lanes_for("avx512"), trig="libm"))
    flags = [f for f in qk.vector_flags("avx512") if f not in ("-shared", "-fPIC")]
    r = subprocess.run(["cc", *flags, "-S", str(src), "-o", str(tmp_path / "k.s")],
                       capture_output=True, text=True)
    if r.returncode:
        pytest.skip(f"this compiler refuses AVX-512: {r.stderr[-300:]}")
    asm = (tmp_path / "k.s").read_text()
    assert "%zmm" in asm and "_ZGVeN8v_sin" in asm


def _vehicles(n=19, seed=3):
    rng = np.random.default_rng(seed)
    return [quadcog.HUMMINGBIRD] * n, np.column_stack([rng.uniform(-0.06, 0.06, (n, 2)),
                                                       np.zeros(n)])


@needs_cc
@pytest.mark.parametrize("build", ["portable", "float32"])
def test_bits_independent_of_threads_and_batch_on_every_build(build, monkeypatch):
    if build == "portable":
        monkeypatch.setenv(qk.ISA_ENV, "portable")
    precision = "float32" if build == "float32" else "float64"
    ctl = quadcog.AdaptiveFeedbackLinearization()
    vehicles, D = _vehicles()
    kw = dict(duration=0.5, cog_times=[(0.2, 0.0)], precision=precision)
    a = fly_batch(ctl, vehicles, D, threads=1, **kw)
    b = fly_batch(ctl, vehicles, D, threads=3, **kw)
    alone = fly_batch(ctl, vehicles[17:18], D[17:18], threads=1, **kw)
    assert a.final_state.tobytes() == b.final_state.tobytes()
    assert a.final_state[17].tobytes() == alone.final_state[0].tobytes()


@needs_cc
def test_fma_only_where_no_math_function_takes_the_sum():
    """a*t + b as a math function's argument (the sensing hash's sin(a t + b); sqrt here, which
    IEEE rounds exactly) is two roundings, as numpy's, on every ISA; as a plain output it is
    one fused rounding on an ISA with FMA units (FMA_ISAS) and two on the others. t runs where
    the two differ (a = 12989.8 + ..., t up to 20 s)."""
    Z, Q, R = ca.SX.sym("Z", 2), ca.SX.sym("Q", 1), ca.SX.sym("r", 1)
    a, b = 13068.651, 4.8
    k = qk.VectorKernel(ca.Function("axb", [Z, Q, R], [ca.vertcat(ca.sqrt(a * Z[0] + b),
                                                                  a * Z[1] + b)]))
    t = np.linspace(0.0, 20.0, 4001)
    got = k(np.column_stack([t, t]), np.zeros((t.size, 1)), np.zeros((1, 1)))
    assert got[:, 0].tobytes() == np.sqrt(a * t + b).tobytes()
    exact = np.array([float(Fraction(a) * Fraction(x) + Fraction(b)) for x in t])
    assert np.any(exact != a * t + b)            # the oracles differ: the test can fail
    want = exact if k.isa in qk.FMA_ISAS else a * t + b
    assert got[:, 1].tobytes() == want.tobytes()


@needs_cc
def test_a_sensed_flight_from_the_kernel_equals_simulate():
    """With sensing noise (a sine hash that amplifies the last bit 1e5-fold) the kernel must
    round like the compiled single flight: FMA contraction made these differ by 1e-7."""
    dt = 1e-3
    ctl = quadcog.Sensed(quadcog.AdaptiveFeedbackLinearization(), quadcog.Sensing(), dt)
    r = np.array([[0.05, 0.04, 0.0]])
    b = fly_batch(ctl, [quadcog.HUMMINGBIRD], r, duration=1.5, cog_times=[(0.3, 0.0)])
    m = quadcog.simulate(ctl, duration=1.5, cog=quadcog.CogProfile.step(0.3, r[0])).metrics
    for name in METRICS:
        assert getattr(b, name)[0] == pytest.approx(getattr(m, name), rel=1e-12, abs=0)


@needs_cc
def test_float32_computes_in_float():
    """1 + 1e-8 is 1 in float32 (its ulp at 1 is 1.2e-7) and not in float64."""
    Z, Q, R = ca.SX.sym("Z", 1), ca.SX.sym("Q", 1), ca.SX.sym("r", 1)
    f = ca.Function("acc", [Z, Q, R], [Z[0] + R[0]])
    Z0, Q0, rows = np.ones((40, 1)), np.zeros((40, 1)), np.full((3, 1), 1e-8)
    k32 = qk.VectorKernel(f, precision="float32")
    assert k32.lanes == 2 * qk.VectorKernel(f).lanes
    assert np.all(k32(Z0, Q0, rows) == 1.0)
    assert np.all(qk.VectorKernel(f)(Z0, Q0, rows) == 1.0 + 1e-8 + 1e-8 + 1e-8)


def test_float32_refuses_the_casadi_path():
    """Refused before any work (the controller is not even looked at)."""
    with pytest.raises(InputError, match="float32"):
        fly_batch(None, [quadcog.HUMMINGBIRD], np.zeros((1, 0)), duration=0.01,
                  kernel="casadi", precision="float32")


@needs_cc
def test_batch_agrees_with_the_single_flight_path_to_1e12():
    """The native build against ``simulate`` (glibc's scalar sin/cos; libmvec's are within
    4 ulp): the whole-flight metrics to 1e-12 relative; the final error, a single sample of a
    few micrometres, to 1e-12 relative or 1e-16 m."""
    ctl = quadcog.AdaptiveFeedbackLinearization()
    rng = np.random.default_rng(1)
    vehicles = [quadcog.HUMMINGBIRD.with_cog((*rng.uniform(-0.06, 0.06, 2), 0.0))
                for _ in range(3)]
    b = quadcog.simulate_batch(ctl, vehicles, duration=5.0, cog_shape=lambda t: float(t >= 1.0))
    for i, v in enumerate(vehicles):
        m = quadcog.simulate(ctl, duration=5.0, vehicle=v.with_cog(np.zeros(3)),
                             cog=quadcog.CogProfile.step(1.0, v.r_G)).metrics
        for name in METRICS[:3]:
            assert getattr(b, name)[i] == pytest.approx(getattr(m, name), rel=1e-12, abs=0)
        assert b.final_position_error[i] == pytest.approx(m.final_position_error, rel=1e-12,
                                                          abs=1e-16)


@needs_cc
def test_the_isa_can_be_pinned_by_the_environment(monkeypatch):
    ctl = quadcog.FeedbackLinearization()
    monkeypatch.setenv(qk.ISA_ENV, "portable")
    assert qk.kernel_isa() == "portable"
    k = qk.kernel_for(("pinned", ctl.cache_key()), _step_fn)
    assert k.isa == "portable" and k.lanes == qk.lanes_for("portable")
    monkeypatch.setenv(qk.ISA_ENV, "avx9000")
    with pytest.raises(InputError, match="QUADCOG_KERNEL_ISA.*avx9000"):
        qk.kernel_isa()

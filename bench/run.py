"""`make bench`: timings in one run, medians of repeats, ratios beside absolute times.

Prints a Markdown table and writes it to out/bench/results-ISA.md (``--out``), ISA the
batch kernel's build (the CPU's widest, or what $QUADCOG_KERNEL_ISA pins: an AVX2 build on
an AVX-512 CPU is labelled as such); the tracked bench/results-ISA.md and the tables of
docs/performance.md change only through ``python bench/publish.py bench``.
No assertion: these machines are noisy, so what counts is the ratios measured side by side in
the same run.
"""
import argparse
import os
from pathlib import Path
import platform
import statistics
import subprocess
import sys
import time
import timeit

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
# crazyflow refuses to import once scipy is loaded without this (it asks scipy for the array
# API); set before quadcog imports scipy, it changes nothing for numpy arrays
os.environ.setdefault("SCIPY_ARRAY_API", "1")

from bench.machine import CHAINS, fma_roofline, loadavg, machine
import quadcog  # noqa: E402
from quadcog import AdaptiveFeedbackLinearization, CogProfile, simulate, simulate_batch
from quadcog.codegen.compiled import compile_function
from quadcog.sim.closed_loop import closed_loop_step, flight_kernel
from quadcog.sim.plant import Actuation, TruthOptions

rows = []


def record(item, value, unit, ratio="", goal="", note=""):
    rows.append((item, value, unit, ratio, goal, note))
    print(f"  {item}: {value} {unit} {ratio} {note}", flush=True)


def per_call(fn, number, repeat=7):
    """Median seconds per call over ``repeat`` runs of ``number`` calls."""
    return statistics.median(timeit.repeat(fn, number=number, repeat=repeat)) / number


def bench_single_call():
    print("one dynamics call")
    import sympy as sp

    from derive import symbols as sym
    from derive.model import derive_model
    d = derive_model()
    xdot = d.substituted(d.xdot)
    lam = sp.lambdify([list(sym.state), list(sym.U), list(sym.params)], xdot, "numpy", cse=True)
    model = quadcog.load()
    p = quadcog.default_parameters(x_G=0.02, y_G=-0.01)
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(-1, 1, 3), rng.uniform(-0.3, 0.3, 3), rng.uniform(-1, 1, 6)])
    U = np.array([7.0, 0.01, -0.02, 0.001])
    t_lam = per_call(lambda: lam(x, U, p), 2000)
    vm = model.casadi_function("dynamics")
    t_vm = per_call(lambda: vm(x, U, p), 2000)
    ext = model._library.functions()["dynamics"]
    t_ext = per_call(lambda: ext(x, U, p), 2000)
    fast = model.fast("dynamics")
    fast.inputs[0][:], fast.inputs[1][:], fast.inputs[2][:] = x, U, p
    t_fast = per_call(fast.eval, 200000)
    t_checked = per_call(lambda: model.dynamics(x, U, p), 20000)
    assert np.allclose(np.array(lam(x, U, p), float).ravel(), fast.outputs[0], rtol=1e-12)
    record("dynamics: sympy.lambdify (cse=True)", f"{t_lam * 1e6:.2f}", "us", "1x")
    record("dynamics: CasADi VM called with numpy", f"{t_vm * 1e6:.2f}", "us",
           f"{t_lam / t_vm:.1f}x")
    record("dynamics: compiled C called with numpy", f"{t_ext * 1e6:.2f}", "us",
           f"{t_lam / t_ext:.1f}x")
    record("dynamics: quadcog checked method", f"{t_checked * 1e6:.2f}", "us",
           f"{t_lam / t_checked:.1f}x")
    record("dynamics: quadcog fast path (FastCall.eval)", f"{t_fast * 1e6:.3f}", "us",
           f"{t_lam / t_fast:.0f}x", "<= 0.3 us, >= 50x lambdify")


def bench_controllers():
    print("controller laws: compiled single call (FastCall.eval)")
    ref = quadcog.Circle()(1.0)
    x = np.zeros(12)
    x[:3] = ref[:3] + 0.05
    for ctl in (quadcog.CascadePD(), quadcog.FeedbackLinearization(),
                AdaptiveFeedbackLinearization()):
        law = ctl.compiled()
        law.inputs[1][:], law.inputs[2][:] = x, ref
        t = per_call(law.eval, 100000)
        record(f"controller: {ctl.name}", f"{t * 1e6:.2f}", "us", "", "~1 us",
               f"{ctl.function().n_instructions()} instructions"
               + (" (law + r_hat_dot)" if ctl.n_state else ""))


def _min_median(times):
    return min(times), statistics.median(times)


def bench_flight(repeat=15):
    """The single flight, warm (its compiled code built and loaded): the whole simulate()
    call beside its steps, its parts, and the CasADi chunks it replaced in the same run.
    Min and median of ``repeat`` calls (the machine is shared: the min is the least
    disturbed)."""
    from quadcog.scenarios.scenario import load_scenario
    import quadcog.sim.flight as qf
    from quadcog.sim.prepare import prepare_flight
    print("20 s adaptive-FL flight at 1 kHz (CoG step [6, 6, 0] cm at 1 s)")
    ctl = AdaptiveFeedbackLinearization()
    cog = CogProfile.step(1.0, (0.06, 0.06, 0.0))
    kw = dict(trajectory="hover", duration=20.0, cog=cog)
    simulate(ctl, path="compiled", **kw)          # compile once (cached on disk)
    simulate(ctl, path="python", duration=0.1, trajectory="hover")
    t_py = statistics.median(simulate(ctl, path="python", **kw).info["seconds"] for _ in range(3))
    parts = {"set-up": [], "steps": [], "result": [], "reference check": []}
    totals, fresh = [], []
    for _ in range(repeat):
        t0 = time.perf_counter()
        setup = prepare_flight(ctl, "hover", 20.0, None, None, None, cog, (), None, None,
                               "compiled", None, None, True)
        t1 = time.perf_counter()
        X, U, e, code = qf._run_compiled(setup, None)
        t2 = time.perf_counter()
        r = qf._result(setup, X, U, e, code, t2 - t1)
        t3 = time.perf_counter()
        qf._check_reference(r, setup.schedule, setup.vehicle, setup.limits)
        t4 = time.perf_counter()
        for name, dt in zip(parts, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            parts[name].append(dt)
        t0 = time.perf_counter()
        simulate(ctl, path="compiled", **kw)
        totals.append(time.perf_counter() - t0)
        t0 = time.perf_counter()          # as the issue states it: a new controller object
        simulate(AdaptiveFeedbackLinearization(), path="compiled", **kw)
        fresh.append(time.perf_counter() - t0)
    # the previous path, CasADi's mapaccum chunks, side by side; their states against the
    # flight kernel's
    setup = prepare_flight(ctl, "hover", 20.0, None, None, None, cog, (), None, None,
                           "compiled", None, None, True)
    qf._run_chunks(setup, None)
    chunks = []
    for _ in range(max(3, repeat // 3)):
        t0 = time.perf_counter()
        Xc, _, _, _ = qf._run_chunks(setup, None)
        chunks.append(time.perf_counter() - t0)
    Xk, _, _, _ = qf._run_compiled(setup, None)
    diff = float(np.max(np.abs(Xk - Xc)))
    scenario = load_scenario("fig6")
    scenario.run()
    fig6 = []
    for _ in range(max(3, repeat // 3)):
        t0 = time.perf_counter()
        scenario.run()
        fig6.append(time.perf_counter() - t0)
    steps_min, steps_med = _min_median(parts["steps"])
    total_min, total_med = _min_median(totals)
    chunk_min, chunk_med = _min_median(chunks)
    record("flight: Python step loop", f"{t_py * 1e3:.0f}", "ms", "1x")
    record("flight: CasADi chunks (previous path), steps only", f"{chunk_med * 1e3:.1f}", "ms",
           f"{t_py / chunk_med:.0f}x", "", f"min {chunk_min * 1e3:.1f} ms; mapaccum of "
           f"{qf.CHUNK} steps, CasADi's C, default flags")
    kernel = flight_kernel(setup.controller, setup.actuation, setup.limits)
    record("flight: one-call compiled (steps only)", f"{steps_med * 1e3:.1f}", "ms",
           f"{t_py / steps_med:.0f}x; {chunk_med / steps_med:.2f}x the chunks", "<= 20 ms",
           f"min {steps_min * 1e3:.1f} ms; the flight kernel, "
           f"{' '.join(kernel.flags[:-2]) if kernel else 'absent'}; states vs the chunks: "
           f"max abs. diff {diff:.1e}")
    record("flight: simulate() call in total", f"{total_med * 1e3:.1f}", "ms",
           f"{total_med / steps_med:.2f}x its steps", "<= 15 ms",
           f"min {total_min * 1e3:.1f} ms; parts (median): "
           + ", ".join(f"{name} {statistics.median(v) * 1e3:.1f} ms" for name, v in parts.items()))
    fresh_min, fresh_med = _min_median(fresh)
    record("flight: simulate(AdaptiveFeedbackLinearization(), ...) in total",
           f"{fresh_med * 1e3:.1f}", "ms", f"{fresh_med / steps_med:.2f}x its steps", "<= 15 ms",
           f"min {fresh_min * 1e3:.1f} ms; a new controller object per call (its design kept)")
    fig6_min, fig6_med = _min_median(fig6)
    record("flight: scenario fig6, Scenario.run() in total", f"{fig6_med * 1e3:.1f}", "ms",
           f"{fig6_med / steps_med:.2f}x the steps above", "",
           f"min {fig6_min * 1e3:.1f} ms; vehicle, controller and model from the scenario file")
    return ctl, steps_med / 20000, total_med


def _kernel(kind, n_ops=3000, width=16, seed=0):
    """A random DAG of n_ops operations of one kind, ILP like generated code."""
    rng = np.random.default_rng(seed)
    x = ca.SX.sym("x", width)
    vals = [x[i] for i in range(width)]
    for _ in range(n_ops):
        a, b = vals[-1 - rng.integers(0, min(len(vals), 24))], vals[-1 - rng.integers(0, min(len(vals), 24))]
        if kind == "arithmetic":
            v = [a * b, a + b, a - b][rng.integers(0, 3)] * 0.5
        elif kind == "division":
            v = a / (1.5 + b * b)
        else:
            v = [ca.sin, ca.cos][rng.integers(0, 2)](a + 0.1 * b)
        vals.append(v)
    return ca.Function(f"kernel_{kind}", [x], [ca.vertcat(*vals[-width:])])


def _op_classes(f):
    names = {getattr(ca, n): n[3:] for n in dir(ca) if n.startswith("OP_")}
    arith = {"ADD", "SUB", "MUL", "NEG", "SQ", "TWICE", "FMIN", "FMAX", "LT", "LE", "EQ", "NE",
             "NOT", "AND", "OR", "IF_ELSE_ZERO", "FABS", "ASSIGN"}
    div = {"DIV", "INV"}
    trig = {"SIN", "COS", "TAN", "ATAN2", "SQRT", "EXP", "LOG", "ATAN", "ASIN", "ACOS", "POW",
            "CONSTPOW"}
    counts = {"arithmetic": 0, "division": 0, "trig": 0}
    for k in range(f.n_instructions()):
        name = names.get(f.instruction_id(k), "")
        if name in arith:
            counts["arithmetic"] += 1
        elif name in div:
            counts["division"] += 1
        elif name in trig:
            counts["trig"] += 1
    return counts


def bench_op_estimate(ctl, measured_step):
    """Rates per op class from three kernels, solving t_i = sum_c n_ic rate_c exactly (each
    kernel also holds a few ops of the other classes), then the step's estimate."""
    print("ns per step against an op-count estimate")
    classes = ("arithmetic", "division", "trig")
    counts, times = [], []
    for kind in classes:
        f = _kernel(kind)
        call = quadcog.codegen.fastcall.FastCall(compile_function(f))
        call.inputs[0][:] = np.linspace(0.1, 0.9, 16)
        times.append(per_call(call.eval, 2000))
        n = _op_classes(f)
        counts.append([n[c] for c in ("arithmetic", "division", "trig")])
    rates = dict(zip(("arithmetic", "division", "trig"), np.linalg.solve(counts, times)))
    for c in ("arithmetic", "division", "trig"):
        record(f"rate: {c}", f"{rates[c] * 1e9:.2f}", "ns/op", "", "",
               "from 3 kernels of ~3000 ops, random DAGs")
    step = closed_loop_step(ctl, Actuation.of(quadcog.HUMMINGBIRD, TruthOptions()), quadcog.Limits())
    n = _op_classes(step)
    estimate = sum(n[c] * rates[c] for c in n)
    record("step: op counts", f"{n['arithmetic']} / {n['division']} / {n['trig']}",
           "arith / div / trig")
    record("step: estimate from op counts", f"{estimate * 1e9:.0f}", "ns")
    record("step: measured (flight / 20000)", f"{measured_step * 1e9:.0f}", "ns",
           f"{measured_step / estimate:.2f}x estimate", "",
           "not a bound (the roofline rows are); the counts are the SX step's; the flight "
           "kernel runs fewer per step (what depends only on P and the CoG profile hoisted, "
           "shared divisors inverted once)")


def _batch_vehicles(n_flights, seed=1):
    rng = np.random.default_rng(seed)
    return [quadcog.HUMMINGBIRD.with_cog(rng.uniform(-0.06, 0.06, 2).tolist() + [0.0])
            for _ in range(n_flights)]


def bench_batch(n_flights):
    """The vector kernel against the CasADi map it replaces, the single-flight path, and its
    memory per flight. Returns (ns per flight-step with 1 thread, flight-steps/s, 2 threads)."""
    import tracemalloc

    import quadcog.sim.batch as qb
    print(f"{n_flights} adaptive flights of 20 s at 1 kHz (CoG step at 1 s), batch")
    ctl = AdaptiveFeedbackLinearization()
    vehicles = _batch_vehicles(n_flights)
    shape = lambda t: float(t >= 1.0)
    kw = dict(trajectory="hover", duration=20.0, cog_shape=shape)
    simulate_batch(ctl, vehicles[:2], "hover", duration=1.0, cog_shape=shape)    # compile

    def timed(threads):
        """(result, CPU seconds of this process): on a shared machine the wall time also
        counts the time other processes hold the cores."""
        c0, t0 = os.times(), time.perf_counter()
        r = simulate_batch(ctl, vehicles, threads=threads, **kw)
        wall, c1 = time.perf_counter() - t0, os.times()
        return r, (c1.user - c0.user) + (c1.system - c0.system), wall
    r2, cpu2, wall2 = timed(2)
    r1, cpu1, wall1 = timed(1)
    steps = n_flights * 20000
    same = r1.final_state.tobytes() == r2.final_state.tobytes()
    record("batch: vector kernel, 1 thread", f"{r1.seconds:.2f}", "s", "1x", "",
           f"{steps / r1.seconds / 1e6:.2f} M flight-steps/s; CPU {cpu1:.2f} s")
    record("batch: vector kernel, 2 threads", f"{r2.seconds:.2f}", "s",
           f"{r1.seconds / r2.seconds:.2f}x", "<= 4 s",
           f"{steps / r2.seconds / 1e6:.2f} M flight-steps/s; CPU {cpu2:.2f} s (two free "
           f"cores: {cpu2 / 2:.1f} s); bits equal to 1 thread: {same}; "
           f"{int(r2.diverged.sum())} diverged")
    record("batch: whole simulate_batch call, 2 threads", f"{wall2:.2f}", "s",
           f"{wall2 / r2.seconds:.2f}x its kernel", "<= 1.1x",
           f"kernel {r2.seconds:.2f} s; 1 thread: whole call {wall1:.2f} s, "
           f"{wall1 / r1.seconds:.2f}x its kernel {r1.seconds:.2f} s")
    # the previous path (CasADi map over flights), on a fifth of the flights: compare rates
    n_map = max(2, n_flights // 5)
    kernel_for = qb.kernel_for
    qb.kernel_for = lambda *a, **k: None
    try:
        simulate_batch(ctl, vehicles[:2], "hover", duration=1.0, cog_shape=shape)
        rm = simulate_batch(ctl, vehicles[:n_map], threads=2, **kw)
    finally:
        qb.kernel_for = kernel_for
    map_rate = n_map * 20000 / rm.seconds
    record(f"batch: CasADi map (previous path), 2 threads, {n_map} flights",
           f"{rm.seconds:.2f}", "s", f"{steps / r2.seconds / map_rate:.1f}x slower", "",
           f"{map_rate / 1e6:.3f} M flight-steps/s")
    # metrics against the single-flight path (simulate), 6 flights
    worst = 0.0
    for i in range(0, n_flights, max(1, n_flights // 6)):
        v = vehicles[i]
        m = simulate(ctl, "hover", duration=20.0, vehicle=v.with_cog(np.zeros(3)),
                     cog=CogProfile.step(1.0, v.r_G)).metrics
        for name in ("rms_position_error", "max_position_error", "rms_position_error_tail",
                     "final_position_error"):
            a, b = getattr(r2, name)[i], getattr(m, name)
            worst = max(worst, abs(a - b) / max(abs(b), 1e-12))
    record("batch: metrics vs single-flight path", f"{worst:.1e}", "max rel. diff", "",
           "<= 1e-9", "4 metrics x 6 flights")
    # memory: tracemalloc peak (numpy buffers) of 2 s batches of n and n/10 flights
    peaks = []
    for n in (n_flights // 10, n_flights):
        tracemalloc.start()
        simulate_batch(ctl, vehicles[:n], "hover", duration=2.0, cog_shape=shape, threads=2)
        peaks.append(tracemalloc.get_traced_memory()[1])
        tracemalloc.stop()
    per_flight = (peaks[1] - peaks[0]) / (n_flights - n_flights // 10)
    record("batch: memory per flight", f"{per_flight / 1024:.2f}", "KB", "", "<= 20 KB",
           "slope of the peak between 100 and 1000 flights (state, parameters, metrics)")
    return cpu1 / steps * 1e9, steps / r2.seconds


def bench_vector_limits(ns_per_flight_step, seconds=1.0):
    """The kernel against the arithmetic bound of its vector unit: a measured loop of
    independent FMAs at the kernel's flags (bench/machine.py), one thread. Every SX operation
    of the step is counted as one floating-point operation (a sin is some 20), so the
    kernel's fraction of the bound is a lower bound of the fraction it reaches."""
    from quadcog.sim.closed_loop import monitored_step, packed
    from quadcog.sim.divergence import Limits
    from quadcog.sim.plant import Actuation
    print("vector kernel against a measured FMA roofline")
    roof = fma_roofline(seconds=seconds)
    record(f"roofline: {roof['kind']} loop, {roof['isa']}, 1 thread",
           f"{roof['flops'] / 1e9:.1f}", "Gflop/s", "", "",
           f"{CHAINS} independent vector chains, the kernel's flags; an FMA counts 2")
    ctl = AdaptiveFeedbackLinearization()
    step = packed(monitored_step(ctl, Actuation.of(ctl.vehicle), Limits()))
    c = _op_classes(step)
    n_ops = sum(c.values())
    if ns_per_flight_step is None:
        return roof
    rate = n_ops / (ns_per_flight_step * 1e-9)
    record("vector step: SX operations", f"{n_ops}", "per flight-step", "", "",
           f"arith / div / trig+sqrt: {c['arithmetic']} / {c['division']} / {c['trig']}")
    record("vector step: operation rate (1 thread, CPU time)", f"{rate / 1e9:.1f}",
           "Gop/s", f"{rate / roof['flops']:.2f}x roofline", "",
           f"{ns_per_flight_step:.0f} ns per flight-step; each operation counted as 1 flop")
    nbytes = (2 * step.nnz_in(0) * 2 + step.nnz_in(1)) * 8
    record("vector step: memory traffic", f"{nbytes}", "bytes per flight-step", "", "",
           f"{nbytes / ns_per_flight_step:.1f} GB/s per thread, from L1")
    bench_object_code(roof["isa"])
    return roof


def bench_object_code(isa):
    """The step loop's vector divisions and libmvec calls in the object code of this build,
    against the previous kernel's (libmvec's sines, no FMA, CasADi's statement order;
    bench/objcode.py)."""
    from bench.objcode import step_loop_counts
    try:
        new, old = step_loop_counts(isa), step_loop_counts(isa, "previous")
    except (OSError, subprocess.CalledProcessError) as e:        # no objdump
        record("object code: step loop", "absent", "", "", "", f"objdump failed: {e}")
        return
    calls = lambda c: ", ".join(f"{n} {name}" for name, n in c["calls"].items())
    record(f"object code: step loop ({isa}), divisions", f"{new['divisions']}",
           f"per pass of {new['lanes']} flights", f"{old['divisions']} previous kernel", "",
           f"{new['instructions']} instructions per pass ({old['instructions']} previous "
           f"kernel); calls: {calls(new) or 'none'} (previous kernel: {calls(old)})")


ISA_REPEATS = 5     # calls per build in bench_isa


def bench_isa(n_flights, duration=20.0):
    """The same batch (1 thread) from every build this CPU runs (its native ISA, AVX2 where
    that is narrower, the portable build): CPU time per flight-step (the least of
    ``ISA_REPEATS`` calls, the builds in turn), and how many final
    states differ from the build of this run. A narrower build on a wider CPU runs on that
    CPU's units and clock: an AVX2 build on an AVX-512 CPU is not an AVX2 CPU."""
    import quadcog.codegen.vector_kernel as qk
    native, built = qk.detect_isa(), qk.kernel_isa()
    ctl = AdaptiveFeedbackLinearization()
    vehicles = _batch_vehicles(n_flights)
    kw = dict(trajectory="hover", duration=duration, cog_shape=lambda t: float(t >= 1.0),
              threads=1)
    isas = [i for i in qk.ISAS[qk.ISAS.index(native):] if i in (native, "avx2", "portable")]
    print(f"{n_flights} flights of {duration:g} s: builds {', '.join(isas)}")
    def pinned_to(isa, call):
        pinned = qk.kernel_isa
        qk.kernel_isa = lambda: isa
        try:
            return call()
        finally:
            qk.kernel_isa = pinned

    for isa in isas:            # compile each build first
        pinned_to(isa, lambda: simulate_batch(ctl, vehicles[:2], **dict(kw, duration=0.01)))
    # the least CPU time of ISA_REPEATS calls per build, the builds taken in turn: this
    # machine's speed drifts within minutes, and a call that another job slowed is not the
    # kernel's cost; every call's time goes into the note
    times, results = {isa: [] for isa in isas}, {}
    for _ in range(ISA_REPEATS):
        for isa in isas:
            c0 = os.times()
            results[isa] = pinned_to(isa, lambda: simulate_batch(ctl, vehicles, **kw))
            c1 = os.times()
            times[isa].append((c1.user - c0.user) + (c1.system - c0.system))
    out = {isa: (results[isa], min(times[isa])) for isa in isas}
    steps = n_flights * int(round(duration / 1e-3))
    rb, cb = out[built]
    for isa in isas:
        r, c = out[isa]
        differ = int(np.sum(np.any(r.final_state != rb.final_state, axis=1)))
        worst = float(np.max(np.abs(r.final_state - rb.final_state)
                             / np.maximum(np.abs(rb.final_state), 1e-300)))
        where = ("the CPU's native build" if isa == native else
                 f"on this {native} CPU, not on an {isa} CPU" if isa != "portable" else
                 f"the compiler's default target, on this {native} CPU")
        spread = ", ".join(f"{t / steps * 1e9:.0f}" for t in times[isa])
        record(f"batch: {isa} build ({qk.lanes_for(isa)} lanes), 1 thread",
               f"{c / steps * 1e9:.0f}", "ns per flight-step (CPU)",
               f"{c / max(cb, 1e-9):.2f}x {built}", "<= 150 ns" if isa == "avx2" else "",
               f"{where}; the least of {ISA_REPEATS} calls, the builds in turn (all: {spread} "
               f"ns); final states differ from the {built} build's in {differ} of "
               f"{n_flights} flights, at most {worst:.1e} relative")


def bench_float32(n_flights, duration=20.0):
    """The float32 kernel (measured, not offered: docs/performance.md) against float64 on the
    same batch of the sweep engine, 1 thread: CPU time per flight-step and the largest
    relative difference of the metrics of the flights that stay bounded."""
    from quadcog.sim.vector_batch import fly_batch
    ctl = AdaptiveFeedbackLinearization()
    rng = np.random.default_rng(2)
    D = np.column_stack([rng.uniform(-0.06, 0.06, (n_flights, 2)), np.zeros(n_flights)])
    vehicles = [quadcog.HUMMINGBIRD] * n_flights
    kw = dict(duration=duration, cog_times=[(1.0, 0.0)], threads=1)
    print(f"{n_flights} flights of {duration:g} s: float32 against float64 kernel")
    out = {}
    for precision in ("float64", "float32"):
        fly_batch(ctl, vehicles[:2], D[:2], **dict(kw, duration=0.01), precision=precision)
        c0 = os.times()
        r = fly_batch(ctl, vehicles, D, **kw, precision=precision)
        c1 = os.times()
        out[precision] = (r, (c1.user - c0.user) + (c1.system - c0.system))
    steps = n_flights * int(round(duration / 1e-3))
    (r64, c64), (r32, c32) = out["float64"], out["float32"]
    ok = ~(r64.diverged | r32.diverged)
    def worst_rel(m):
        a, b = getattr(r32, m)[ok], getattr(r64, m)[ok]
        d = np.where(a == b, 0.0, np.abs(a - b) / np.maximum(np.abs(b), 1e-300))
        return float(d.max()) if d.size else float("nan")
    worst = {m: worst_rel(m) for m in ("rms_position_error", "rms_position_error_tail")}
    record("batch: float32 kernel (measured, not offered), 1 thread",
           f"{c32 / steps * 1e9:.0f}", "ns per flight-step (CPU)",
           f"{c64 / max(c32, 1e-9):.2f}x faster than float64", "",
           f"float64 {c64 / steps * 1e9:.0f} ns; max rel. diff rms "
           f"{worst['rms_position_error']:.1e}, tail rms {worst['rms_position_error_tail']:.1e}; "
           f"verdicts differ: {int(np.sum(r64.diverged != r32.diverged))}")


def bench_scale(sizes=(10, 100, 1000, 10000), duration=2.0, threads=2):
    """Cost per flight-step of the kernel and of the whole simulate_batch call at each batch
    size, and the memory per flight (tracemalloc peak of a separate short run / flights)."""
    import tracemalloc
    print(f"scale: adaptive flights of {duration:g} s at 1 kHz, {threads} threads")
    ctl = AdaptiveFeedbackLinearization()
    shape = lambda t: float(t >= 0.5 * duration)
    simulate_batch(ctl, _batch_vehicles(2), "hover", duration=0.01, cog_shape=shape)
    out = []
    for n in sizes:
        vehicles = _batch_vehicles(n)
        c0, t0 = os.times(), time.perf_counter()
        r = simulate_batch(ctl, vehicles, "hover", duration=duration, cog_shape=shape,
                           threads=threads)
        wall, c1 = time.perf_counter() - t0, os.times()
        cpu = (c1.user - c0.user) + (c1.system - c0.system)
        steps = n * int(round(duration / 1e-3))
        tracemalloc.start()
        simulate_batch(ctl, vehicles, "hover", duration=0.05, cog_shape=shape, threads=threads)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        record(f"scale: {n} flights x {duration:g} s", f"{r.seconds / steps * 1e9:.1f}",
               "ns per flight-step (kernel)",
               f"whole call {wall / steps * 1e9:.1f} ns ({wall / r.seconds:.2f}x)",
               "<= 1.1x" if n >= 10000 else "",
               f"kernel {r.seconds:.3f} s, whole call {wall:.3f} s, CPU {cpu:.2f} s; "
               f"memory {peak / n / 1024:.2f} KB per flight (peak {peak / 2**20:.1f} MB)")
        out.append((n, r.seconds / steps, wall / steps, peak / n))
    return out


def bench_numba(n_flights, quadcog_rate, threads=2):
    """The afternoon baseline (bench/numba_peer.py): a hand-written numba RK4 of the plain
    rigid body with a cascade PD law, same flight count, horizon and threads as the batch;
    timed on its second full call (numba compiles once per argument types, on the first)."""
    from bench import numba_peer
    if not numba_peer.available():
        record("peer: numba RK4, plain body + PD", "absent", "", "", "",
               "not installed: pip install -e '.[bench]'")
        return None
    import numba
    n_steps = 20000
    print(f"numba baseline: {n_flights} flights x {n_steps} steps at 1 kHz, {threads} threads")
    t0 = time.perf_counter()
    numba_peer.fly(4, 10, threads, quadcog.HUMMINGBIRD)
    compile_s = time.perf_counter() - t0
    calls = []
    for _ in range(2):
        t0 = time.perf_counter()
        X = numba_peer.fly(n_flights, n_steps, threads, quadcog.HUMMINGBIRD)
        calls.append(time.perf_counter() - t0)
    t = calls[-1]
    rate = n_flights * n_steps / t
    settled = bool(np.all(np.isfinite(X)) and np.max(np.abs(X[:, :3])) < 1e-3)
    record(f"peer: numba {numba.__version__} RK4, plain body + PD, {n_flights} flights x "
           f"{n_steps} steps", f"{t:.2f}", "s", "", "",
           f"{rate:.0f} flight-steps/s, {threads} threads, float64; the 2nd full call (the "
           f"1st {calls[0]:.2f} s); compile {compile_s:.1f} s; every flight within 1 mm of "
           f"hover at the end: {settled}")
    record("peer: quadcog vector kernel / numba RK4", f"{quadcog_rate / rate:.2f}",
           "x (flight-steps/s)", "", "", "same flight count, horizon and threads, wall time, "
           "one run; numba's step has no CoG offset and no adaptation (several times less "
           "arithmetic): a floor, not a like-for-like peer")
    return rate


def bench_crazyflow(n_flights, n_steps, quadcog_rate):
    """crazyflow (JAX, CPU, float64): first-principles dynamics, its state controller, RK4 at
    1 kHz; the steps timed after a run of the same length that compiles them."""
    try:
        import jax
        jax.config.update("jax_enable_x64", True)
        from crazyflow.control import Control
        from crazyflow.dynamics import Dynamics
        from crazyflow.sim import Sim
        from crazyflow.sim.integration import Integrator
    except ImportError as e:
        record("peer: crazyflow (JAX)", "absent", "", "", "", f"not installed ({e.name}): "
               "pip install -e '.[bench]'")
        return None
    except RuntimeError as e:           # installed, but refuses to import here
        record("peer: crazyflow (JAX)", "absent", "", "", "",
               f"installed but not importable: {str(e).splitlines()[0][:120]}")
        return None
    from importlib.metadata import version
    print(f"crazyflow: {n_flights} worlds x {n_steps} steps at 1 kHz")

    def timed_calls(steps):
        """Four calls of sim.step(steps) on a fresh Sim, in seconds: the first sim.step(n)
        traces and compiles, the second traces and compiles again (it sees other array
        types), the last two are warm."""
        sim = Sim(n_worlds=n_flights, n_drones=1, dynamics=Dynamics.first_principles,
                  control=Control.state, integrator=Integrator.rk4, freq=1000,
                  state_freq=1000, attitude_freq=1000, device="cpu")
        cmd = np.zeros((n_flights, 1, 16))
        cmd[..., 2], cmd[..., 12] = 1.0, 1.0           # hover at 1 m, identity quaternion
        sim.state_control(cmd)
        calls = []
        for _ in range(4):
            t0 = time.perf_counter()
            sim.step(steps)
            jax.block_until_ready(sim.data.states.pos)
            calls.append(time.perf_counter() - t0)
        return calls

    # the compile time at a short horizon, where a warm call is short beside it: at
    # quadcog's horizon the warm calls vary by more than the compile takes
    short = max(1, min(200, n_steps))
    first = timed_calls(short)
    compile_s, spread = first[0] + first[1] - first[2] - first[3], abs(first[2] - first[3])
    calls = timed_calls(n_steps)       # the exact call timed, the fourth, warm
    t = calls[-1]
    rate = n_flights * n_steps / t
    record(f"peer: crazyflow {version('crazyflow')}, {n_flights} flights x {n_steps} steps",
           f"{t:.2f}", "s", "", "", f"{rate:.0f} flight-steps/s, JAX {jax.__version__} CPU, "
           f"float64, first-principles + state control, RK4; the 4th call of sim.step("
           f"{n_steps}) (the 3rd took {calls[2]:.2f} s; all: "
           + ", ".join(f"{c:.2f}" for c in calls) + " s)")
    record(f"peer: crazyflow compile (first two calls less two warm ones, at {short} steps)",
           f"{compile_s:.1f}", "s", "", "",
           f"a fresh Sim's calls of sim.step({short}): " + ", ".join(f"{c:.2f}" for c in first)
           + f" s (the warm two {spread:.2f} s apart); JAX traces and compiles on the first "
           f"two; measured at {short} steps because at {n_steps} the warm calls vary by "
           f"seconds")
    record("peer: quadcog vector kernel / crazyflow", f"{quadcog_rate / rate:.1f}",
           "x (flight-steps/s)", "", "", "same flight count and horizon, 1 kHz, both warm, "
           "wall time on the same cores, one run")
    return rate


def bench_rotorpy_batched(n_flights, seconds, quadcog_rate):
    """RotorPy's batched simulator (PyTorch on the CPU, float64, the Hummingbird, SE(3)
    control, RK4 at 1 ms), as many steps as fit; extrapolated to 20 s."""
    try:
        from rotorpy.controllers.quadrotor_control import BatchedSE3Control
        from rotorpy.sensors.imu import BatchedImu
        from rotorpy.simulate import simulate_batch as rotorpy_batch
        from rotorpy.trajectories.batched_traj import BatchedTrajectory
        from rotorpy.trajectories.hover_traj import HoverTraj
        from rotorpy.vehicles.hummingbird_params import quad_params
        from rotorpy.vehicles.multirotor import BatchedMultirotor, BatchedMultirotorParams
        from rotorpy.wind.default_winds import BatchedNoWind
        from rotorpy.world import World
        import torch
    except ImportError as e:
        record("peer: rotorpy batched", "absent", "", "", "", f"not installed ({e.name}): "
               "pip install torch==2.13.0 (a CPU build), then pip install -e '.[bench]'")
        return
    print(f"rotorpy simulate_batch: {n_flights} flights, {seconds} s at 1 ms")
    B, dev = n_flights, torch.device("cpu")
    params = BatchedMultirotorParams([quad_params] * B, B, dev)
    hover = np.sqrt(quad_params["mass"] * 9.81 / (4 * quad_params["k_eta"]))
    zeros = lambda: torch.zeros(B, 3, dtype=torch.double)
    init = {"x": zeros(), "v": zeros(), "w": zeros(), "wind": zeros(),
            "q": torch.tensor([[0, 0, 0, 1.0]] * B, dtype=torch.double),
            "rotor_speeds": torch.full((B, 4), hover, dtype=torch.double)}
    vehicle = BatchedMultirotor(params, B, init, dev, control_abstraction="cmd_motor_speeds",
                                integrator="rk4")
    def run():
        t0 = time.perf_counter()
        rotorpy_batch(World.empty([-10, 10, -10, 10, -10, 10]), init, vehicle,
                      BatchedSE3Control(params, B, dev),
                      BatchedTrajectory([HoverTraj() for _ in range(B)], dev), BatchedNoWind(B),
                      BatchedImu(B, device=dev), np.full(B, seconds), 0.001, 0.25,
                      terminate=False, check_collisions=False)
        return time.perf_counter() - t0
    first = run()                 # the same call once before (torch has no compile step)
    t = run()
    steps = int(round(seconds / 0.001))
    rate = B * steps / t
    record(f"peer: rotorpy simulate_batch, {B} flights x {steps} steps", f"{t:.1f}", "s", "", "",
           f"{rate:.0f} flight-steps/s, torch {torch.__version__}, {torch.get_num_threads()} "
           f"threads; the 2nd of two equal calls (the 1st {first:.1f} s); not quadcog's "
           f"horizon: its arrays grow with every step, so 20 s would take at least "
           f"{t * 20 / seconds:.0f} s (extrapolated)")
    record("peer: quadcog vector kernel / rotorpy batched", f"{quadcog_rate / rate:.0f}",
           "x (flight-steps/s)", "", "", "same flight count and step, one run; RotorPy at "
           f"{steps} steps, quadcog at 20,000")


def bench_rotorpy(quadcog_seconds):
    """RotorPy's single flight (Environment.run, the Crazyflie, SE(3) control, 20 s at 1 ms)
    against quadcog's whole simulate() call of the same length measured in this run."""
    try:
        import rotorpy  # noqa: F401
    except ImportError:
        record("peer: rotorpy Environment.run, 20 s at 1 ms", "absent", "", "", "",
               "rotorpy not installed (pip install -e '.[bench]')")
        return
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.environments import Environment
    from rotorpy.trajectories.hover_traj import HoverTraj
    from rotorpy.vehicles.crazyflie_params import quad_params
    from rotorpy.vehicles.multirotor import Multirotor
    env = Environment(vehicle=Multirotor(quad_params), controller=SE3Control(quad_params),
                      trajectory=HoverTraj(), sim_rate=1000)
    kw = dict(use_mocap=False, terminate=False, plot=False, animate_bool=False, verbose=False)
    env.run(t_final=0.1, **kw)                 # the same call once, short, before the timed one
    env = Environment(vehicle=Multirotor(quad_params), controller=SE3Control(quad_params),
                      trajectory=HoverTraj(), sim_rate=1000)
    t0 = time.perf_counter()
    env.run(t_final=20, **kw)
    t = time.perf_counter() - t0
    record("peer: rotorpy Environment.run, 20 s at 1 ms", f"{t:.1f}", "s",
           f"{t / quadcog_seconds:.0f}x quadcog's simulate()", "",
           f"Crazyflie, SE3 control, hover; quadcog's whole call {quadcog_seconds * 1e3:.1f} ms "
           "(the adaptive flight above)")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--flights", type=int, default=1000, help="batch size (default 1000)")
    ap.add_argument("--out", type=Path, default=None,
                    help="where to write the table (default: out/bench/results-ISA.md, ISA "
                         "the batch kernel's build: $QUADCOG_KERNEL_ISA pins it)")
    ap.add_argument("--peer-seconds", type=float, default=0.05,
                    help="simulated seconds of RotorPy's batched run (default 0.05: its "
                         "trajectory arrays grow with every step)")
    ap.add_argument("--peer-steps", type=int, default=20000,
                    help="steps of crazyflow's timed run (default 20000: quadcog's 20 s)")
    ap.add_argument("--scale", type=int, nargs="*", default=[10, 100, 1000, 10000],
                    help="batch sizes of the scale table (default 10 100 1000 10000)")
    args = ap.parse_args()
    m = machine()
    load_before = loadavg()
    print(f"quadcog bench on {m['cpu']} ({m['machine']}), {m['cores']} cores, CasADi "
          f"{ca.__version__}, Python {platform.python_version()}; load {load_before}")
    record("machine: CPU", m["cpu"], "", "", "",
           f"{m['machine']}, {m['cores']} cores; {m['identity']}")
    record("machine: vector features", m["features"], "", "", "", "/proc/cpuinfo flags")
    record("machine: compiler", m["compiler"], "", "", "", "")
    record("machine: batch kernel build", m["isa"], "", "", "",
           f"{m['lanes']} flights per block; flags {m['flags']}; "
           + ("the CPU's widest" if m["isa"] == m["native"] else
              f"pinned by ${m['isa_env']}, narrower than the CPU's {m['native']}: the figures "
              f"are of a {m['isa']} build on this CPU, not of a {m['isa']} CPU"))
    record("machine: load before", load_before, "1/5/15 min", "", "", "/proc/loadavg")
    bench_single_call()
    bench_controllers()
    ctl, step, flight_total = bench_flight()
    bench_op_estimate(ctl, step)
    ns_step, rate = bench_batch(args.flights)
    bench_vector_limits(ns_step)
    bench_isa(args.flights)
    bench_float32(args.flights)
    if args.scale:
        bench_scale(tuple(args.scale))
    bench_rotorpy_batched(args.flights, args.peer_seconds, rate)
    bench_crazyflow(args.flights, args.peer_steps, rate)
    bench_numba(args.flights, rate)
    bench_rotorpy(flight_total)
    record("machine: load after", loadavg(), "1/5/15 min", "", "", "/proc/loadavg")
    lines = ["| measurement | value | unit | ratio | goal | note |", "|---|---|---|---|---|---|"]
    lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    table = "\n".join(lines)
    print("\n" + table)
    out = args.out or ROOT / "out" / "bench" / f"results-{m['isa']}.md"
    out.parent.mkdir(parents=True, exist_ok=True)
    build = (f"kernels built for {m['isa']}, the CPU's widest" if m["isa"] == m["native"] else
             f"kernels built for {m['isa']} on a CPU that runs {m['native']}: not a CPU "
             f"whose widest is {m['isa']}")
    out.write_text("# `make bench` results\n\nMedian of repeats, measured in one run on "
                   f"{m['cpu']} ({m['cores']} cores, {m['machine']}, {build}), "
                   f"{time.strftime('%Y-%m-%d')}.\n\n" + table + "\n")
    print(f"\nwritten to {out}; `python bench/publish.py bench` copies each "
          "out/bench/results-ISA.md into docs/performance.md and bench/")


if __name__ == "__main__":
    main()

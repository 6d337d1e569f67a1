"""`make bench`: timings in one run, medians of repeats, ratios beside absolute times.

Prints a Markdown table and writes it to out/bench/results.md (``--out``); the tracked
bench/results.md and the README's table change only through ``python bench/publish.py bench``.
No assertion: these machines are noisy, so what counts is the ratios measured side by side in
the same run.
"""
import argparse
import os
from pathlib import Path
import platform
import statistics
import sys
import time
import timeit

import casadi as ca
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import quadcog  # noqa: E402
from quadcog import (AdaptiveFeedbackLinearization, CogProfile, simulate,  # noqa: E402
                     simulate_batch)
from quadcog.closed_loop import closed_loop_step  # noqa: E402
from quadcog.compiled import compile_function  # noqa: E402
from quadcog.plant import Actuation, TruthOptions  # noqa: E402

rows = []


def record(item, value, unit, ratio="", goal="", note=""):
    rows.append((item, value, unit, ratio, goal, note))
    print(f"  {item}: {value} {unit} {ratio} {note}", flush=True)


def per_call(fn, number, repeat=7):
    """Median seconds per call over ``repeat`` runs of ``number`` calls."""
    return statistics.median(timeit.repeat(fn, number=number, repeat=repeat)) / number


def bench_single_call():
    print("one dynamics call")
    from derive.model import derive_model
    import sympy as sp
    from derive import symbols as sym
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
    ext = model._compiled["dynamics"]
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


def bench_flight():
    print("20 s adaptive-FL flight at 1 kHz (CoG step [6, 6, 0] cm at 1 s)")
    ctl = AdaptiveFeedbackLinearization()
    cog = CogProfile.step(1.0, (0.06, 0.06, 0.0))
    kw = dict(trajectory="hover", duration=20.0, cog=cog)
    simulate(ctl, path="compiled", **kw)          # compile once (cached on disk)
    simulate(ctl, path="python", duration=0.1, trajectory="hover")
    t_py = statistics.median(simulate(ctl, path="python", **kw).info["seconds"] for _ in range(3))
    runs = [simulate(ctl, path="compiled", **kw) for _ in range(7)]
    t_c = statistics.median(r.info["seconds"] for r in runs)
    t_total = per_call(lambda: simulate(ctl, path="compiled", **kw), 1, repeat=5)
    record("flight: Python step loop", f"{t_py * 1e3:.0f}", "ms", "1x")
    record("flight: one-call compiled (steps only)", f"{t_c * 1e3:.1f}", "ms",
           f"{t_py / t_c:.0f}x", "<= 20 ms")
    record("flight: simulate() call in total", f"{t_total * 1e3:.1f}", "ms",
           f"{t_py / t_total:.0f}x", "", "with set-up, checks, metrics")
    return ctl, t_c / 20000


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
        call = quadcog.fastcall.FastCall(compile_function(f))
        call.inputs[0][:] = np.linspace(0.1, 0.9, 16)
        times.append(per_call(call.eval, 2000))
        n = _op_classes(f)
        counts.append([n[c] for c in ("arithmetic", "division", "trig")])
    rates = dict(zip(("arithmetic", "division", "trig"), np.linalg.solve(counts, times)))
    for c in ("arithmetic", "division", "trig"):
        record(f"rate: {c}", f"{rates[c] * 1e9:.2f}", "ns/op", "", "",
               "from 3 kernels of ~3000 ops, random DAGs")
    step = closed_loop_step(ctl, Actuation.of(quadcog.HUMMINGBIRD, TruthOptions()))
    n = _op_classes(step)
    estimate = sum(n[c] * rates[c] for c in n)
    record("step: op counts", f"{n['arithmetic']} / {n['division']} / {n['trig']}",
           "arith / div / trig")
    record("step: estimate from op counts", f"{estimate * 1e9:.0f}", "ns")
    record("step: measured (flight / 20000)", f"{measured_step * 1e9:.0f}", "ns",
           f"{measured_step / estimate:.2f}x estimate", "<= 1.5x")


def bench_batch(n_flights):
    print(f"{n_flights} adaptive flights of 20 s, batch")
    ctl = AdaptiveFeedbackLinearization()
    rng = np.random.default_rng(1)
    params = [quadcog.HUMMINGBIRD.with_cog(rng.uniform(-0.06, 0.06, 2).tolist() + [0.0])
              for _ in range(n_flights)]
    shape = lambda t: float(t >= 1.0)
    simulate_batch(ctl, params[:2], "hover", duration=1.0, cog_shape=shape)    # compile
    r1 = simulate_batch(ctl, params, "hover", duration=20.0, cog_shape=shape, threads=1)
    r2 = simulate_batch(ctl, params, "hover", duration=20.0, cog_shape=shape, threads=2)
    same = np.allclose(r1.rms_position_error, r2.rms_position_error, rtol=1e-12)
    record("batch: 1 thread", f"{r1.seconds:.1f}", "s", "1x")
    record("batch: 2 threads", f"{r2.seconds:.1f}", "s", f"{r1.seconds / r2.seconds:.2f}x",
           "<= 10 s", f"same metrics: {same}; {int(r2.diverged.sum())} diverged")


def bench_rotorpy():
    try:
        import rotorpy  # noqa: F401
    except ImportError:
        record("peer: rotorpy Environment.run, 20 s at 1 ms", "n/a", "", "", "",
               "rotorpy not installed (pip install '.[peer]')")
        return
    from rotorpy.controllers.quadrotor_control import SE3Control
    from rotorpy.environments import Environment
    from rotorpy.trajectories.hover_traj import HoverTraj
    from rotorpy.vehicles.crazyflie_params import quad_params
    from rotorpy.vehicles.multirotor import Multirotor
    env = Environment(vehicle=Multirotor(quad_params), controller=SE3Control(quad_params),
                      trajectory=HoverTraj(), sim_rate=1000)
    t0 = time.perf_counter()
    env.run(t_final=20, use_mocap=False, terminate=False, plot=False, animate_bool=False,
            verbose=False)
    t = time.perf_counter() - t0
    record("peer: rotorpy Environment.run, 20 s at 1 ms", f"{t:.1f}", "s", "", "",
           "Crazyflie, SE3 control, hover")


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--flights", type=int, default=1000, help="batch size (default 1000)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench" / "results.md",
                    help="where to write the table (default: out/bench/results.md)")
    args = ap.parse_args()
    print(f"quadcog bench on {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, CasADi {ca.__version__}, Python {platform.python_version()}")
    bench_single_call()
    bench_controllers()
    ctl, step = bench_flight()
    bench_op_estimate(ctl, step)
    bench_batch(args.flights)
    bench_rotorpy()
    lines = ["| measurement | value | unit | ratio | goal | note |", "|---|---|---|---|---|---|"]
    lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    table = "\n".join(lines)
    print("\n" + table)
    out = args.out
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text("# `make bench` results\n\nMedian of repeats, measured in one run on "
                   f"{os.cpu_count()} cores ({platform.machine()}), "
                   f"{time.strftime('%Y-%m-%d')}.\n\n" + table + "\n")
    print(f"\nwritten to {out}; `python bench/publish.py bench` copies it into README.md and "
          "bench/results.md")


if __name__ == "__main__":
    main()

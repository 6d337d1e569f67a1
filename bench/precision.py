"""How far the batch kernel's results move with its precision and its instruction set.

    python bench/precision.py [--flights N] [--out out/bench/precision.md]

Tables (Markdown, printed and written to ``--out``, and each to its own file beside it,
``precision-float32.md``, ``precision-isa.md`` and ``precision-fma.md``, which
``python bench/publish.py precision-float32`` etc. copy into docs/performance.md):

1. float32 against float64 (both the vector kernel): every shipped scenario flown as a batch
   of one, and a Monte-Carlo sweep (fig6, the adaptive controller, the CoG step drawn uniformly
   in a disc of 9 cm): the largest relative difference of each metric, and the flights whose
   divergence verdict differs.
2. The portable build (SSE2 on x86-64) against the native one (``quadcog.codegen.vector_kernel.detect_isa``),
   float64, the same sweep: which metrics change and by how much, how many flights' final
   states differ in any bit.
3. FMA contraction: the sensed scenario fig6-real from the kernel as built (``-ffp-contract=off``
   with quadcog's own fused products, none in a math function's argument:
   ``quadcog.codegen.hoisting.fused_products``) and with gcc's ``-ffp-contract=fast`` (every
   contraction gcc finds, the sensing hash's argument included), against ``simulate``.

Numbers for docs/performance.md come from this script's output.
"""
import argparse
import dataclasses
from pathlib import Path
import sys

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import quadcog.codegen.vector_kernel as qk
from quadcog.files import run_stamp
from quadcog.scenarios.lookup import scenario_names
from quadcog.scenarios.scenario import load_scenario
from quadcog.sim.timeline import CogProfile
from quadcog.sweeps.flights import CONTROLLERS_BY_GROUP, METRICS, fly_group

CONTINUOUS = METRICS[:4]          # the four position-error metrics (m)


def rel(a, b):
    """Largest |a - b| / |b| over flights (0 where both are equal, inf/NaN where equal)."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    d = np.where(same, 0.0, np.abs(a - b) / np.maximum(np.abs(b), 1e-300))
    return float(np.max(d)) if d.size else 0.0


def absdiff(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    same = (a == b) | (np.isnan(a) & np.isnan(b))
    return float(np.max(np.where(same, 0.0, np.abs(a - b))))


def fly(scenarios, precision="float64"):
    CONTROLLERS_BY_GROUP.clear()
    return fly_group("precision-bench", scenarios, threads=2, precision=precision)


def monte_carlo(n, seed=0):
    base = load_scenario("fig6")
    rng = np.random.default_rng(seed)
    radius = 0.09 * np.sqrt(rng.uniform(0, 1, n))
    angle = rng.uniform(0, 2 * np.pi, n)
    return [dataclasses.replace(base, controller="adaptive",
                                cog=CogProfile.step(1.0, (r * np.cos(a), r * np.sin(a), 0.0)))
            for r, a in zip(radius, angle)]


def table(header, rows):
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    return "\n".join(lines)


def float32_table(n):
    rows = []
    cases = [(name, [load_scenario(name)]) for name in scenario_names()]
    cases.append((f"Monte-Carlo: fig6 adaptive, {n} CoG steps in a 9 cm disc", monte_carlo(n)))
    for name, scenarios in cases:
        r64, r32 = fly(scenarios, "float64"), fly(scenarios, "float32")
        flips = int(np.sum(r64["diverged"] != r32["diverged"]))
        ok = ~(r64["diverged"] | r32["diverged"])
        cells = []
        for m in CONTINUOUS:
            a, b = r32[m][ok], r64[m][ok]
            cells.append(f"{rel(a, b):.1e} ({absdiff(a, b):.1e} m)" if ok.any() else "-")
        rows.append([name, len(scenarios), int(r64["diverged"].sum()), flips] + cells)
        print(rows[-1], flush=True)
    return table(["flights", "n", "diverged (float64)", "verdicts that differ",
                  *(f"{m}: rel. (abs.)" for m in CONTINUOUS)], rows)


def isa_table(n):
    native = qk.detect_isa()
    scenarios = monte_carlo(n)
    r_native = fly(scenarios)
    pinned = qk.kernel_isa
    qk.kernel_isa = lambda: "portable"
    try:
        r_port = fly(scenarios)
    finally:
        qk.kernel_isa = pinned
    ok = ~(r_port["diverged"] | r_native["diverged"])
    rows = [[m, f"{rel(r_port[m][ok], r_native[m][ok]):.1e}",
             int(np.sum(r_port[m][ok] != r_native[m][ok])),
             f"{rel(r_port[m][~ok], r_native[m][~ok]):.1e}"] for m in CONTINUOUS]
    rows.append(["diverged", "-", int(np.sum(r_port["diverged"] != r_native["diverged"])),
                 "-"])
    print(rows, flush=True)
    return native, table([f"metric ({int(ok.sum())} flights that did not diverge)",
                          f"max rel. diff portable vs {native}", "flights whose value differs",
                          f"max rel. diff, the {int((~ok).sum())} that diverged"], rows)


def contraction_table():
    from quadcog.sweeps.flights import METRICS as names
    s = load_scenario("fig6-real")
    single = s.run().metrics
    out = {}
    flags = qk.vector_flags
    for mode in ("off", "fast"):
        qk.vector_flags = (lambda *a, _m=mode, **k: tuple(
            f"-ffp-contract={_m}" if f.startswith("-ffp-contract") else f
            for f in flags(*a, **k)))
        qk._kernels.clear()
        try:
            out[mode] = fly([s])
        finally:
            qk.vector_flags = flags
            qk._kernels.clear()
    label = {"off": "as built (-ffp-contract=off, quadcog's fused products)",
             "fast": "-ffp-contract=fast (every contraction gcc finds)"}
    rows = [[label[mode]] + [f"{rel(out[mode][m], [getattr(single, m)]):.1e}"
                             for m in names[:4]] for mode in out]
    print(rows, flush=True)
    return table(["fig6-real (sensed) kernel build", *(f"{m} vs simulate" for m in names[:4])],
                 rows)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--flights", type=int, default=256, help="Monte-Carlo flights (256)")
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench" / "precision.md")
    args = ap.parse_args()
    t32 = float32_table(args.flights)
    native, tisa = isa_table(args.flights)
    tfma = contraction_table()
    text = (f"# Precision and instruction set of the batch kernel\n\n"
            f"CPU features: native ISA {native}; `python bench/precision.py --flights "
            f"{args.flights}`.\n\n## float32 against float64\n\n{t32}\n\n"
            f"## portable against native\n\n{tisa}\n\n## FMA contraction\n\n{tfma}\n")
    print("\n" + text)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(f"written to {args.out}")
    stamp = (f"Measured by `python bench/precision.py --flights {args.flights}` {run_stamp()}, "
             f"native build {native}.")
    for name, title, tab in (("float32", "float32 against float64", t32),
                             ("isa", "portable against native", tisa),
                             ("fma", "FMA contraction", tfma)):
        part = args.out.parent / f"precision-{name}.md"
        part.write_text(f"# {title}\n\n{stamp}\n\n{tab}\n")
        print(f"written to {part}")


if __name__ == "__main__":
    main()

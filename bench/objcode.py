"""What the batch kernel's object code does per step, counted: its vector divisions and the
libmvec calls of its step loop, for an instruction set, with and without the hoisting of
``quadcog.codegen.vector_kernel.emit_c`` (what depends only on the parameters and the CoG
profile computed less often, divisions through reciprocals).

The kernel's C is compiled with its own flags (``vector_flags``) to an object file, which
objdump disassembles; the step loop is the code between two markers put around it. Run
alone: ``python bench/objcode.py [ISA ...]``.
"""
import collections
from pathlib import Path
import re
import subprocess
import sys
import tempfile

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import quadcog  # noqa: E402
from quadcog.codegen import vector_kernel as qk  # noqa: E402
from quadcog.sim.batch import slow_row_entries  # noqa: E402
from quadcog.sim.closed_loop import monitored_step, packed  # noqa: E402
from quadcog.sim.divergence import Limits  # noqa: E402
from quadcog.sim.plant import Actuation  # noqa: E402

__all__ = ["MCA_MODELS", "VARIANTS", "mca_cycles", "step_loop_counts"]

# llvm-mca's CPU model for each ISA's estimate: AMD family 25 (Zen 3), the AVX2 EPYC of the
# issue's 420 ns; and an AVX-512 core (llvm-mca 14 has no Zen 4 or 5 model)
MCA_MODELS = {"avx2": "znver3", "avx512": "skylake-avx512"}

_DIVISION = re.compile(r"^v?div[ps]d$")


VARIANTS = {"unhoisted": "not hoisted, libmvec's sin, cos, tan, no FMA",
            "previous": "hoisted, reciprocals; libmvec's sin, cos, tan, no FMA (the previous "
                        "kernel)",
            "built": "as built (hoisted, reciprocals, inline sin, cos, tan, FMA, statements "
                     "ordered)"}


def _flags(isa, variant):
    return [f for f in qk.vector_flags(isa) if f not in ("-shared", "-fPIC")]


def _emit_options(isa, variant):
    """emit_c's options of a variant: the previous kernels called libmvec for the sines,
    fused nothing and kept CasADi's order of the statements."""
    if variant == "built":
        return dict(slow=slow_row_entries(), fma=isa in qk.FMA_ISAS)
    old = dict(trig="libm", order=False)
    return dict(old, slow=slow_row_entries()) if variant == "previous" else dict(
        old, reciprocals=False)


def _marked(isa, variant, controller, begin, end):
    """The kernel's C with ``begin`` and ``end`` (asm text) around its step loop."""
    ctl = controller or quadcog.AdaptiveFeedbackLinearization()
    step = packed(monitored_step(ctl, Actuation.of(ctl.vehicle), Limits()))
    src = qk.emit_c(step, lanes=qk.lanes_for(isa), **_emit_options(isa, variant))
    i = src.rindex("#pragma omp simd")          # the step loop is the last simd loop
    src = src[:i] + f'__asm__ volatile("{begin}");\n      ' + src[i:]
    # after the step loop: before the rerun of a step with large angles, if any
    j = src.find("      {\n        int any = 0;")
    j = j if j >= 0 else src.index("      for (long i = 0; i < NZ * LANES; ++i) z[i] = zn[i];")
    return src[:j] + f'      __asm__ volatile("{end}");\n' + src[j:]


def mca_cycles(isa, variant="built", controller=None, iterations=10):
    """llvm-mca's estimate of the step loop's cycles per flight-step on ``MCA_MODELS[isa]``:
    the loop's code alone (a libmvec call counts as one instruction; their insides are not
    modelled), load-independent.

    Parameters
    ----------
    isa : str
        "avx2" or "avx512".
    variant : str
        One of ``VARIANTS``, as for ``step_loop_counts``.
    controller : Controller, optional
        Default: the adaptive feedback linearization.
    iterations : int
        llvm-mca's iterations of the loop's code.

    Returns
    -------
    dict or None
        cycles (per flight-step), throughput (llvm-mca's block reciprocal throughput per
        flight-step: the bound of the busiest resource), resource (that resource), model;
        None without llvm-mca.
    """
    import shutil
    exe = shutil.which("llvm-mca") or shutil.which("llvm-mca-14")
    if exe is None:
        return None
    src = _marked(isa, variant, controller, "# LLVM-MCA-BEGIN step", "# LLVM-MCA-END step")
    flags = _flags(isa, variant)
    with tempfile.TemporaryDirectory() as tmp:
        c, asm = Path(tmp) / "k.c", Path(tmp) / "k.s"
        c.write_text(src)
        subprocess.run(["cc", *flags, "-S", str(c), "-o", str(asm)], check=True)
        out = subprocess.run([exe, f"-mcpu={MCA_MODELS[isa]}", f"-iterations={iterations}",
                              str(asm)], capture_output=True, text=True, check=True).stdout
    lanes = qk.VECTOR_BITS[isa] // 64
    total = int(re.search(r"Total Cycles:\s+(\d+)", out).group(1))
    rthroughput = float(re.search(r"Block RThroughput:\s+([\d.]+)", out).group(1))
    return {"cycles": total / iterations / lanes, "throughput": rthroughput / lanes,
            "model": MCA_MODELS[isa]}


def step_loop_counts(isa, variant="built", controller=None):
    """Instructions of the batch kernel's step loop, from its object code.

    Parameters
    ----------
    isa : str
        One of ``quadcog.codegen.vector_kernel.ISAS`` (compiled only: this CPU need not run it).
    variant : str
        One of ``VARIANTS``: the kernel as built, the previous kernel (libmvec's sines, no
        FMA, CasADi's statement order), or that without hoisting and reciprocals.
    controller : Controller, optional
        Default: the adaptive feedback linearization.

    Returns
    -------
    dict
        instructions (of the loop's code), divisions (vector and scalar div), calls ({name:
        count}, e.g. {"_ZGVdN4v_sin": 13}), lanes (flights per pass of the code: one vector).
    """
    src = _marked(isa, variant, controller, "qc_step_begin:", "qc_step_end:")
    flags = _flags(isa, variant)
    with tempfile.TemporaryDirectory() as tmp:
        c, o = Path(tmp) / "k.c", Path(tmp) / "k.o"
        c.write_text(src)
        subprocess.run(["cc", *flags, "-c", str(c), "-o", str(o)], check=True)
        dump = subprocess.run(["objdump", "-dr", "--no-show-raw-insn", str(o)],
                              capture_output=True, text=True, check=True).stdout
    inside, ops, calls = False, collections.Counter(), collections.Counter()
    for line in dump.splitlines():
        if line.endswith("<qc_step_begin>:"):
            inside = True
        elif line.endswith("<qc_step_end>:"):
            inside = False
        elif inside and "R_X86_64_PLT32" in line:
            calls[line.split()[-1].split("-")[0]] += 1
        elif inside and "\t" in line.strip():
            ops[line.split("\t")[-1].split()[0]] += 1
    return {"instructions": sum(ops.values()),
            "divisions": sum(n for op, n in ops.items() if _DIVISION.match(op)),
            "calls": dict(sorted(calls.items())), "lanes": qk.VECTOR_BITS[isa] // 64}


def main():
    import argparse
    import os
    import platform
    import time
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("isas", nargs="*", default=["avx2", "avx512"])
    ap.add_argument("--out", type=Path, default=ROOT / "out" / "bench" / "objcode.md")
    args = ap.parse_args()
    lines = ["| build | step loop | instructions per flight-step | divisions per flight-step "
             "| libmvec calls per pass | llvm-mca cycles per flight-step (model) |",
             "|---|---|---|---|---|---|"]
    for isa in args.isas:
        for variant, label in VARIANTS.items():
            c = step_loop_counts(isa, variant)
            m = mca_cycles(isa, variant)
            calls = ", ".join(f"{n} {name}" for name, n in c["calls"].items())
            mca = (f"{m['cycles']:.0f} (throughput bound {m['throughput']:.0f}; {m['model']})"
                   if m else "no llvm-mca")
            lines.append(f"| {isa} | {label} "
                         f"| {c['instructions'] / c['lanes']:.0f} "
                         f"| {c['divisions'] / c['lanes']:.1f} | {calls} | {mca} |")
    table = "\n".join(lines)
    print(table)
    from quadcog.codegen.compiler import _compiler_identity, find_compiler
    compiler = _compiler_identity(find_compiler())
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text("# Object code of the batch kernel's step loop\n\nMeasured by "
                        f"`python bench/objcode.py` on {platform.machine()}, "
                        f"{os.cpu_count()} cores ({compiler}, "
                        f"{time.strftime('%Y-%m-%d')}; compiled, not run: any x86-64 machine "
                        "gives the same table with the same compiler).\n\n" + table + "\n")


if __name__ == "__main__":
    main()

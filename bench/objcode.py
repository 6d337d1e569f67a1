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

__all__ = ["step_loop_counts"]

_DIVISION = re.compile(r"^v?div[ps]d$")


def step_loop_counts(isa, hoisted=True, controller=None):
    """Instructions of the batch kernel's step loop, from its object code.

    Parameters
    ----------
    isa : str
        One of ``quadcog.codegen.vector_kernel.ISAS`` (compiled only: this CPU need not run it).
    hoisted : bool
        The kernel as built (True) or the same step without hoisting and reciprocals.
    controller : Controller, optional
        Default: the adaptive feedback linearization.

    Returns
    -------
    dict
        instructions (of the loop's code), divisions (vector and scalar div), calls ({name:
        count}, e.g. {"_ZGVdN4v_sin": 13}), lanes (flights per pass of the code: one vector).
    """
    ctl = controller or quadcog.AdaptiveFeedbackLinearization()
    step = packed(monitored_step(ctl, Actuation.of(ctl.vehicle), Limits()))
    kw = dict(slow=slow_row_entries()) if hoisted else dict(reciprocals=False)
    src = qk.emit_c(step, lanes=qk.lanes_for(isa), **kw)
    i = src.rindex("#pragma omp simd")          # the step loop is the last simd loop
    src = src[:i] + '__asm__ volatile("qc_step_begin:");\n      ' + src[i:]
    j = src.index("      for (long i = 0; i < NZ * LANES; ++i) z[i] = zn[i];")
    src = src[:j] + '      __asm__ volatile("qc_step_end:");\n' + src[j:]
    flags = [f for f in qk.vector_flags(isa) if f not in ("-shared", "-fPIC")]
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


if __name__ == "__main__":
    for isa in sys.argv[1:] or ["avx2", "avx512"]:
        for hoisted in (False, True):
            print(isa, "hoisted" if hoisted else "not hoisted", step_loop_counts(isa, hoisted))

"""Export the derived objects as CasADi functions (.casadi) and one self-contained C file."""
from pathlib import Path
import tempfile

import casadi as ca

from derive.contract import FUNCTIONS, VECTORS
from derive.headers import c_header
from derive.to_casadi import Translator

C_BASENAME = "quadcog_gen"


def build_function(spec, model):
    """One CasADi Function from its spec; I_G^{-1} placeholders become SX of p (or pi)."""
    args = {name: ca.SX.sym(name, len(VECTORS[name][1])) for name in spec.inputs}
    tr = Translator({})
    for name in spec.inputs:
        for k, s in enumerate(VECTORS[name][1]):
            tr.bind(s, args[name][k])
    for placeholder, definition in spec.placeholders(model).items():
        tr.bind(placeholder, tr.expr(definition, f"{spec.name} (I_G^-1)"))
    outs = [ca.densify(tr.matrix(getter(model), spec.name)) for _, getter in spec.outputs]
    outs = ca.cse(outs)   # CasADi's CSE finds what the SymPy memo misses (10-20 % fewer ops)
    return ca.Function(spec.name, [args[n] for n in spec.inputs], outs,
                       list(spec.inputs), [n for n, _ in spec.outputs])


def build_functions(model):
    return {spec.name: build_function(spec, model) for spec in FUNCTIONS}


def write_casadi(functions, out_dir):
    folder = Path(out_dir) / "casadi"
    folder.mkdir(parents=True, exist_ok=True)
    for name, fn in functions.items():
        fn.save(str(folder / f"{name}.casadi"))


def write_c(functions, out_dir):
    """All functions in one C file and its header, with no dependency on CasADi."""
    folder = Path(out_dir) / "c"
    folder.mkdir(parents=True, exist_ok=True)
    gen = ca.CodeGenerator(f"{C_BASENAME}.c", {"with_header": True})
    for fn in functions.values():
        gen.add(fn)
    with tempfile.TemporaryDirectory() as tmp:
        gen.generate(tmp + "/")
        for suffix in (".c", ".h"):
            text = (Path(tmp) / f"{C_BASENAME}{suffix}").read_text()
            (folder / f"{C_BASENAME}{suffix}").write_text(c_header() + text)

"""The LaTeX report of what was derived, filled into derive/templates/report.tex."""
from pathlib import Path
import string

import casadi
import sympy as sp

from . import symbols as sym
from .headers import tex_header

TEMPLATE = Path(__file__).parent / "templates" / "report.tex"


class _TexTemplate(string.Template):
    delimiter = "@@"      # '$' is LaTeX's math shift


def _tex(e):
    return sp.latex(e, mat_str="bmatrix", mat_delim="")


def _vec(symbols):
    return ", ".join(_tex(s) for s in symbols)


def _rows(lhs_names, exprs):
    return ",\\\\\n".join(f"{a} &= {_tex(e)}" for a, e in zip(lhs_names, exprs))


def _named_subexpressions(named):
    """CSE over several named expressions: kappa_k definitions, then the entries."""
    names = [n for n, _ in named]
    kappas = sp.numbered_symbols(r"\kappa_", start=1)
    replacements, reduced = sp.cse([e for _, e in named], symbols=kappas, order="canonical")
    lines = [f"{_tex(s)} &= {_tex(e)}" for s, e in replacements]
    lines += [f"{n} &= {_tex(e)}" for n, e in zip(names, reduced)]
    return ",\\\\\n".join(lines)


def _hover_linearization(model):
    point = {s: 0 for s in sym.state}
    point.update({sym.U[0]: sym.m * sym.g, sym.U[1]: 0, sym.U[2]: 0, sym.U[3]: 0,
                  sym.x_G: 0, sym.y_G: 0, sym.z_G: 0})
    point.update({s: model.I_G_inv[s].subs(point) for s in sym.I_G_INV_SYMBOLS})
    lines = []
    for mat, label in ((model.A, "A"), (model.B, "B")):
        at = mat.xreplace(point).applyfunc(sp.simplify)
        for i in range(at.rows):
            for j in range(at.cols):
                if at[i, j] != 0:
                    lines.append(f"{label}_{{{i + 1},{j + 1}}} &= {_tex(at[i, j])}")
    return ",\\\\\n".join(lines)


def render(model):
    """The report text (header included)."""
    body, out = model.body, model.outputs
    ne_names = ["F_x", "F_y", "F_z", "T_\\phi", "T_\\theta", "T_\\psi"]
    alpha_b = [(f"\\alpha_{{{i + 1}{j + 1}}}", out.alpha[i, j])
               for i in range(4) for j in range(4)]
    alpha_b += [(f"b_{{{i + 1}}}", out.b[i]) for i in range(4)]
    fields = dict(
        sympy_version=sp.__version__, casadi_version=casadi.__version__,
        state=_vec(sym.state), inputs=_vec(sym.U), params=_vec(sym.params),
        R=_tex(model.R), Q=_tex(model.Q),
        newton_euler=_rows(ne_names, body.newton_euler),
        M=_tex(body.M), D=_tex(body.D), B_u=_tex(body.B_u), g_G=_tex(body.g_G),
        C12=_tex(body.C[:3, 3:]), C22=_tex(body.C[3:, 3:]), I_G=_tex(body.I_G),
        Phi=_rows([f"\\Phi_{{{i + 1},:}}" for i in range(6)],
                  [model.Phi[i, :] for i in range(6)]),
        relative_degree=", ".join(map(str, out.relative_degree)),
        relative_degree_total=str(sum(out.relative_degree)),
        zero_dynamics_dim=str(len(sym.state) - sum(out.relative_degree)),
        alpha_b=_named_subexpressions(alpha_b),
        linearization=_hover_linearization(model),
    )
    return tex_header() + _TexTemplate(TEMPLATE.read_text()).substitute(fields)

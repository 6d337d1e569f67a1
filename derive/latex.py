"""The LaTeX report of what was derived, filled into derive/templates/report.tex.

Everything printed here is computed from the derived model. The only expressions typed in
are the paper's printed equations (``_paper_*``), kept solely to compute, for the comparison
table, how the derived equations differ from them. The text is deterministic (no numbers from
a run): the verification table and the paper's results are \\input by the template from files
that ``make report`` writes next to it (report/verify.py, report/pdf.py).
"""
import functools
from pathlib import Path
import re
import string

import casadi
import sympy as sp
from sympy.printing.latex import LatexPrinter

from derive import symbols as sym
from derive.contract import FUNCTIONS, VECTORS
from derive.headers import tex_header
from derive.newton_euler import NU_DOT, solve_accelerations

TEMPLATE = Path(__file__).parent / "templates" / "report.tex"

# Widths in pt of 10 pt type: the text block is 17 cm (484 pt) wide. _width estimates the
# printed width of a formula; report/pdf.py fails on any real overflow over 10 pt.
TEXT_WIDTH = 470           # what a display line may use, with a little slack
CONTINUATION = 20          # \qquad at the start of a continuation line
PAIR_GAP = 30              # between the two entries of a line that holds two


class _TexTemplate(string.Template):
    delimiter = "@@"      # '$' is LaTeX's math shift


class _Printer(LatexPrinter):
    """SymPy's LaTeX with compact trigonometry: cos(phi)**2 -> \\cos^{2}{\\phi}."""

    def __init__(self):
        super().__init__({"mat_str": "bmatrix", "mat_delim": ""})

    def _print_Function(self, expr, exp=None):
        if expr.func in (sp.sin, sp.cos, sp.tan) and expr.args[0].is_Symbol:
            power = "" if exp is None else f"^{{{exp}}}"
            return rf"\{expr.func.__name__}{power}{{{self._print(expr.args[0])}}}"
        return super()._print_Function(expr, exp)


_PRINTER = _Printer()


def _tex(e):
    return _PRINTER.doprint(e)


def _vec(symbols):
    return ", ".join(_tex(s) for s in symbols)


_GLYPH = {"m": 8.8, "w": 7.2, "M": 9.7, "W": 10.3, "i": 3.5, "j": 4.1, "l": 3.0}
_COMMAND = {"sin": 15.0, "cos": 15.0, "tan": 15.0, "qquad": 20.0, "quad": 10.0, ",": 1.7,
            ";": 2.8, "!": -1.7, " ": 3.3, "left": 0.0, "right": 0.0, "lVert": 5.0,
            "rVert": 5.0, "cdot": 7.8, "times": 12.2, "dot": 0.0}


def _group(tex, k):
    """The brace group starting at tex[k] ('{'), and the index after it."""
    depth = 0
    for i in range(k, len(tex)):
        depth += {"{": 1, "}": -1}.get(tex[i], 0)
        if depth == 0:
            return tex[k + 1:i], i + 1
    return tex[k + 1:], len(tex)


def _width(tex, scale=1.0):
    """Estimated printed width (pt) of math LaTeX as SymPy writes it, in a display."""
    width, k, prev = 0.0, 0, ""
    while k < len(tex):
        c = tex[k]
        if c == "\\":
            mo = re.match(r"\\([A-Za-z]+|.)", tex[k:])
            name = mo.group(1)
            k += len(mo.group(0))
            if name == "frac":
                num, k = _group(tex, k)
                den, k = _group(tex, k)
                width += max(_width(num, scale), _width(den, scale)) + 2 * scale
            elif name in ("operatorname", "mathrm", "text"):
                arg, k = _group(tex, k)
                width += 5.0 * len(arg) * scale
            else:
                width += _COMMAND.get(name, 6.5) * scale
            prev = "x"
        elif c in "^_":
            k += 1
            if k < len(tex) and tex[k] == "{":
                arg, k = _group(tex, k)
            else:
                arg, k = tex[k:k + 1], k + 1
            width += _width(arg, scale * 0.7)
        elif c == "{":
            arg, k = _group(tex, k)
            width += _width(arg, scale)
            prev = "x"
        else:
            if c in "+-":
                binary = prev not in ("", "(", "[", "{", "=", ",", "+", "-", "&")
                width += (12.2 if binary else 7.8) * scale
            elif c == "=":
                width += 13.4 * scale
            elif c == ",":
                width += 2.8 * scale
            elif c in "()[]":
                width += 3.9 * scale
            elif c.isalpha():
                width += _GLYPH.get(c, 7.5 if c.isupper() else 5.3) * scale
            elif c.isdigit():
                width += 5.0 * scale
            elif c not in " &}":
                width += 5.0 * scale
            if not c.isspace():
                prev = c
            k += 1
    return width


# --- sums, broken lines and displays ----------------------------------------------------------

def _signed(term):
    """(sign, LaTeX) of one term of a sum."""
    sign = "+"
    if term.could_extract_minus_sign():
        sign, term = "-", -term
    tex = _tex(term)
    if _PRINTER._needs_add_brackets(term):
        tex = rf"\left({tex}\right)"
    return sign, tex


def _signed_terms(expr):
    """(sign, LaTeX) for the terms of a sum, in SymPy's order."""
    terms = _PRINTER._as_ordered_terms(expr) if expr.is_Add else [expr]
    return [_signed(t) for t in terms]


def _join(parts):
    """LaTeX of a sum from its (sign, LaTeX) terms."""
    text = ""
    for sign, tex in parts:
        text += (f" {sign} " if text else ("-" if sign == "-" else "")) + tex
    return text


def _sum(expr):
    """A sum with its positive terms first, accelerations first among them (I_zz - I_yy
    rather than -I_yy + I_zz, w_dot + p v - q u)."""
    terms = _PRINTER._as_ordered_terms(expr) if expr.is_Add else [expr]
    accelerations = set(NU_DOT)
    terms = sorted(terms, key=lambda t: (t.could_extract_minus_sign(),
                                         not (t.free_symbols & accelerations)))  # stable
    return _join([_signed(t) for t in terms])


def _broken(expr, room):
    """``expr`` as LaTeX lines that fit in ``room`` pt (continuation lines, which start
    with a \\qquad and their sign, in CONTINUATION pt less): a long sum is split between
    its terms."""
    tex = _tex(expr)
    if _width(tex) <= room or not expr.is_Add:
        return [tex]
    lines, current = [], ""
    for sign, term in _signed_terms(expr):
        piece = f"{sign} {term}" if (current or lines or sign == "-") else term
        limit = room - (CONTINUATION if lines else 0)
        if current and _width(current + " " + piece) > limit:
            lines.append(current)
            current, piece = "", f"{sign} {term}"
        current = f"{current} {piece}".strip()
    lines.append(current)
    return lines


def _display(pairs, end="."):
    """``name = value`` lines in one align*. Two short entries share a line (the first is
    set in a box of half the width, so that the second ones line up); long values are
    broken over continuation lines."""
    names = max(_width(name) for name, _ in pairs) + 14          # name and ' = '
    half = (TEXT_WIDTH - PAIR_GAP) / 2
    items = [(name, _broken(expr, TEXT_WIDTH - names)) for name, expr in pairs]

    def short(item):
        return len(item[1]) == 1 and names + _width(item[1][0]) + 3 <= half

    rows, k = [], 0
    while k < len(items):
        name, lines = items[k]
        if short(items[k]) and k + 1 < len(items) and short(items[k + 1]):
            other, (value,) = items[k + 1]
            box = f"{half - names:.0f}pt"
            rows.append(f"{name} &= \\makebox[{box}][l]{{$\\displaystyle {lines[0]},$}}"
                        f"\\quad {other} = {value}")
            k += 2
        else:
            rows.append(f"{name} &= {lines[0]}"
                        + "".join(f"\\\\\n  &\\qquad {line}" for line in lines[1:]))
            k += 1
    return "\\begin{align*}\n" + ",\\\\\n".join(rows) + f"{end}\n\\end{{align*}}"


def _row(vector):
    """A column vector inline, as c [a, b]^T with the common factor c of its entries."""
    entries = list(vector)
    nonzero = [e for e in entries if e != 0]
    common = functools.reduce(sp.gcd, nonzero) if nonzero else sp.S.One
    inner = [sp.expand(sp.cancel(e / common)) for e in entries]
    body = r",\ ".join(_sum(e) if e.is_Add else _tex(e) for e in inner)
    return ("" if common == 1 else f"{_tex(common)} ") + rf"\left[{body}\right]^T"


def _fits(name, matrix):
    columns = [max(_width(_tex(e)) for e in matrix.col(j)) for j in range(matrix.cols)]
    return _width(name) + 25 + sum(columns) + 10 * (matrix.cols - 1) <= TEXT_WIDTH


def _entries(name, matrix, first_row=0):
    return [(f"{name}_{{{i + first_row + 1},{j + 1}}}", matrix[i, j])
            for i in range(matrix.rows) for j in range(matrix.cols) if matrix[i, j] != 0]


def _regressor(Phi):
    """Phi as its force rows (a 3x3 matrix) and moment rows; a skew-symmetric block is
    printed as S(a) with its vector a, so that it fits the page."""
    out = []
    for top, name in ((0, r"\Phi_{1:3}"), (3, r"\Phi_{4:6}")):
        block = Phi[top:top + 3, :]
        skew = (block + block.T).applyfunc(sp.expand) == sp.zeros(3, 3)
        if _fits(name, block):
            out.append(f"\\begin{{align*}}\n{name} &= {_tex(block)}.\n\\end{{align*}}")
        elif skew:
            a = [block[2, 1], block[0, 2], block[1, 0]]
            out.append(rf"and ${name} = S(a)$ (skew-symmetric, $S(a)\,b = a\times b$) with")
            out.append(_display([(f"a_{{{k + 1}}}", a[k]) for k in range(3)]))
        else:
            out.append(_display(_entries(r"\Phi", block, top)))
    return "\n".join(out)


# --- named subexpressions -------------------------------------------------------------------

def _named_subexpressions(named):
    """CSE over named expressions; returns (definitions, entries) as (LaTeX name, expr) lists.

    Only common subexpressions that are sums keep a name kappa_k: products, powers and
    functions of one symbol read better inline, so they are substituted back. The kappas are
    numbered in the order they are defined.
    """
    temporaries = sp.numbered_symbols("cse_tmp_")
    replacements, reduced = sp.cse([e for _, e in named], symbols=temporaries,
                                   order="canonical")
    inline, kept = {}, []
    for s, e in replacements:
        e = e.xreplace(inline)
        if e.is_Add and sp.count_ops(e) > 2:
            kept.append((s, e))
        else:
            inline[s] = e
    renamed = {s: sp.Symbol(f"kappa_{k + 1}") for k, (s, _) in enumerate(kept)}
    definitions = [(_tex(renamed[s]), e.xreplace(renamed)) for s, e in kept]
    entries = [(n, r.xreplace(inline).xreplace(renamed)) for (n, _), r in zip(named, reduced)]
    return definitions, entries


def _alpha_b(model):
    """alpha and b, with row 1 of alpha collected on the entries of row 3 of R."""
    out = model.outputs
    row3 = [sp.cos(sym.phi) * sp.cos(sym.theta), sp.sin(sym.phi) * sp.cos(sym.theta),
            sp.sin(sym.theta)]
    alpha = out.alpha.copy()
    for j in range(4):
        alpha[0, j] = sp.collect(sp.expand(alpha[0, j]), row3)
    named = [(f"\\alpha_{{{i + 1}{j + 1}}}", alpha[i, j]) for i in range(4) for j in range(4)]
    named += [(f"b_{{{i + 1}}}", out.b[i]) for i in range(4)]
    return _named_subexpressions(named)


# --- Newton-Euler rows in the paper's grouping ----------------------------------------------

def _grouped(symbol, coeff):
    """symbol (coeff), with the minus outside when every term of coeff is negative."""
    if all(t.could_extract_minus_sign() for t in sp.Add.make_args(coeff)):
        return "-", rf"{_tex(symbol)}\left({_sum(-coeff)}\right)"
    return "+", rf"{_tex(symbol)}\left({_sum(coeff)}\right)"


def _in_r_G(expr):
    """A polynomial affine in r_G as 'e_0 + x_G(...) + y_G(...) + z_G(...)', where e_0 lists
    its acceleration terms first."""
    expr = sp.expand(expr)
    base = expr.xreplace({s: 0 for s in sym.r_G})
    terms = _PRINTER._as_ordered_terms(base) if base.is_Add else ([base] if base != 0 else [])
    accelerations = set(NU_DOT)
    terms = sorted(terms, key=lambda t: not (t.free_symbols & accelerations))     # stable
    parts = [_signed(t) for t in terms]
    for s in sym.r_G:
        coeff = sp.expand(expr.coeff(s))
        if coeff != 0:
            parts.append(_grouped(s, coeff))
    return _join(parts)


def _newton_euler_rows(lhs):
    """The six left-hand sides as m[...] (forces) and I... + m[...] (moments), as the paper
    groups them."""
    rows = []
    for k, e in enumerate(lhs):
        e = sp.expand(e)
        if k < 3:
            rows.append(rf"m\left[{_in_r_G(e / sym.m)}\right]")
            continue
        inertia = e.xreplace({sym.m: 0})
        mass = sp.expand((e - inertia) / sym.m)
        poly = sp.Poly(inertia, *NU_DOT[3:], *sym.nu2)
        parts = []
        for monom, coeff in poly.terms():
            mono = sp.Mul(*(v ** n for v, n in zip(poly.gens, monom)))
            tex = rf"\left({_sum(coeff)}\right)" if coeff.is_Add else _tex(coeff)
            parts.append(("+", f"{tex} {_tex(mono)}"))
        rows.append(_join(parts) + rf" + m\left[{_in_r_G(mass)}\right]")
    return rows


# --- what the paper prints, for the comparison only ------------------------------------------

def _paper_newton_euler():
    """The paper's expanded Newton-Euler lines, as printed (sec. 2.2)."""
    u, v, w, p, q, r = sym.nu
    ud, vd, wd, pd, qd, rd = NU_DOT
    xG, yG, zG, m = sym.x_G, sym.y_G, sym.z_G, sym.m
    return sp.Matrix([
        m * (ud - v * r + w * q - xG * (q**2 + r**2) + yG * (p * q - rd) + zG * (p * r + qd)),
        m * (vd - w * p + u * r + xG * (q * p + rd) - yG * (p**2 + r**2) + zG * (q * r - pd)),
        m * (wd - u * q + v * p + xG * (r * p - qd) + yG * (r * q - pd) - zG * (q**2 + p**2)),
        sym.Ixx * pd + (sym.Izz - sym.Iyy) * q * r
        + m * (yG * (wd - u * q + v * p) - zG * (vd - w * p + u * r)),
        sym.Iyy * qd + (sym.Ixx - sym.Izz) * r * p
        + m * (zG * (ud - v * r + w * q) - xG * (wd - u * q + v * p)),
        sym.Izz * rd + (sym.Iyy - sym.Ixx) * p * q
        + m * (xG * (vd - w * p + u * r) - yG * (ud - v * r + w * q)),
    ])


def _paper_mass_matrix():
    m, xG, yG, zG = sym.m, sym.x_G, sym.y_G, sym.z_G
    return sp.Matrix([
        [m, 0, 0, 0, m * zG, -m * yG],
        [0, m, 0, -m * zG, 0, m * xG],
        [0, 0, m, m * yG, -m * xG, 0],
        [0, -m * zG, m * yG, sym.Ixx, 0, 0],
        [m * zG, 0, -m * xG, 0, sym.Iyy, 0],
        [-m * yG, m * xG, 0, 0, 0, sym.Izz],
    ])


def _paper_euler_rate_map():
    sf, cf, tt, ct = sp.sin(sym.phi), sp.cos(sym.phi), sp.tan(sym.theta), sp.cos(sym.theta)
    return sp.Matrix([[1, sf * tt, cf * tt], [0, cf, -sf], [0, sf / ct, cf / ct]])


def _paper_input(model):
    """tau = [f_tau; U2; U3; U4] with f_tau = R^{-1} [0, 0, U1], as printed."""
    return sp.Matrix.vstack(model.R.T * sp.Matrix([0, 0, sym.U[0]]), sym.U[1:, :])


def _comparison(model):
    body, out = model.body, model.outputs
    ne_diff = (body.newton_euler - _paper_newton_euler()).applyfunc(sp.expand)
    rows = [k for k in range(6) if ne_diff[k] != 0]
    ne = "; ".join(rf"row {k + 1}, derived $-$ printed $= {_tex(ne_diff[k])}$" for k in rows)
    m_same = (body.M - _paper_mass_matrix()).applyfunc(sp.expand) == sp.zeros(6, 6)
    q_same = (model.Q - _paper_euler_rate_map()).applyfunc(sp.simplify) == sp.zeros(3, 3)
    force = sp.trigsimp((body.B_u * sym.U - _paper_input(model))[:3, :])
    level = {sym.phi: 0, sym.theta: 0}
    # F selects the w, p, q, r rows of nu_dot = M^{-1}(B_u U - C nu - D nu - g_G).
    a_same = (out.alpha - model.G[8:, :]).xreplace(level).applyfunc(sp.expand) == sp.zeros(4, 4)
    b_diff = (out.b - model.f[8:, :]).xreplace(level).applyfunc(sp.expand)
    return dict(
        ne_diff=ne or "no row differs",
        ne_rows_equal=str(6 - len(rows)),
        mass_matrix_check=("identical to the derived $M$" if m_same
                           else r"\textbf{different} from the derived $M$"),
        euler_rate_map_check="identical to" if q_same else r"\textbf{different} from",
        thrust_diff=_row(force),
        alpha_level_check="equals" if a_same else r"\textbf{differs} from",
        b_level_diff=_row(b_diff),
    )


# --- the function list, zero dynamics, hover -------------------------------------------------

_FUNCTION_TEXT = {
    "dynamics": r"$\dot x = f(x) + G(x)U$",
    "mass_matrix": r"$M$ (about $O$)",
    "inverse_mass_matrix": r"$M^{-1}$",
    "coriolis": r"$C(\nu)$, skew-symmetric",
    "damping": r"$D = \operatorname{diag}(c)$",
    "gravity": r"$g_G(\eta)$",
    "regressor": r"$\Phi = \partial_{r_G}[M\vartheta + C\nu + g_G]$",
    "decoupling": r"$\alpha = L_G L_f h$",
    "drift": r"$b = L_f^2 h$",
    "linearization": r"$\partial\dot x/\partial x$, $\partial\dot x/\partial U$",
    "truth_dynamics": r"$\dot x$ of the truth model",
    "inertial_regressor": r"$Y$: $Y\pi = M\dot\nu + C\nu + g_G$",
    "inertial_mass_matrix": r"$M$ of the body $\pi$",
    "inertial_dynamics": r"$\dot x$ of the body $\pi$",
    "se3_dynamics": r"$\dot x_q$ on SE(3), quaternion",
    "se3_regressor": r"$Y$ with the attitude as $R$",
    "quaternion_rotation": r"$R(q)$",
}


def _escape(text):
    return re.sub(r"([_%&#$])", r"\\\1", text)


def _shape(matrix):
    rows, cols = matrix.shape
    return f"{rows}" if cols == 1 else rf"{rows}$\times${cols}"


def _function_table(model):
    lines = []
    for spec in FUNCTIONS:
        inputs = ", ".join(rf"\code{{{_escape(n)}}}\,({len(VECTORS[n][1])})" for n in spec.inputs)
        outputs = ", ".join(rf"\code{{{_escape(n)}}}\,({_shape(get(model))})"
                            for n, get in spec.outputs)
        text = _FUNCTION_TEXT.get(spec.name, _escape(spec.doc))
        lines.append(rf"\code{{{_escape(spec.name)}}} & {inputs} & {outputs} & {text} \\")
    return "\n".join(lines)


def _zero_dynamics(model):
    """On y = 0: z = phi = theta = psi = 0 for all t, hence w = p = q = r = 0 and their
    derivatives vanish; the equations of motion then give u_dot, v_dot and the input U*."""
    body = model.body
    ud, vd = NU_DOT[0], NU_DOT[1]
    manifold = {s: 0 for s in (sym.z, sym.phi, sym.theta, sym.psi, sym.w, sym.p, sym.q, sym.r)}
    nu_dot = sp.Matrix([ud, vd, 0, 0, 0, 0])
    eqs = (body.M * nu_dot + body.C * sym.nu + body.D * sym.nu + body.g_G
           - body.B_u * sym.U).xreplace(manifold)
    (sol,) = sp.solve(list(eqs), [ud, vd, *sym.U], dict=True)
    eta1_dot = (model.R * sym.nu1).xreplace(manifold)
    U_star = sp.Matrix([sol[s] for s in sym.U])
    return dict(
        zd_x=_tex(eta1_dot[0]), zd_y=_tex(eta1_dot[1]),
        zd_u=_tex(sol[ud]), zd_v=_tex(sol[vd]),
        zd_U=_tex(U_star),
        trim_U=_row(U_star.xreplace({sym.u: 0, sym.v: 0})),
    )


def _hover(model):
    """Blocks of A and B at x = 0, U = [m g, 0, 0, 0], r_G = 0, and the structure at the
    trim for any r_G (checked here symbolically)."""
    point = {s: 0 for s in sym.state}
    point.update({sym.U[0]: sym.m * sym.g, sym.U[1]: 0, sym.U[2]: 0, sym.U[3]: 0,
                  sym.x_G: 0, sym.y_G: 0, sym.z_G: 0})
    point.update({s: model.I_G_inv[s].xreplace(point) for s in sym.I_G_INV_SYMBOLS})
    A = model.A.xreplace(point).applyfunc(sp.simplify)
    B = model.B.xreplace(point).applyfunc(sp.simplify)
    if A[:6, :6] != sp.zeros(6, 6) or A[:6, 6:] != sp.eye(6) or B[:6, :] != sp.zeros(6, 4):
        raise AssertionError("hover linearization: the kinematic rows are not [0, I]")

    # Any r_G, at x = 0 and the trim U* = [m g, m g y_G, -m g x_G, 0]: the rows of nu are
    # A = -M^{-1}[dg_G/deta, D] and B = M^{-1} B_u (I_G^{-1} placeholders on both sides).
    body = model.body
    trim = {s: 0 for s in sym.state}
    trim.update(zip(sym.U, [sym.m * sym.g, sym.m * sym.g * sym.y_G, -sym.m * sym.g * sym.x_G, 0]))
    if model.xdot.xreplace(trim).applyfunc(sp.expand) != sp.zeros(12, 1):
        raise AssertionError("U* is not a trim")
    dg = body.g_G.jacobian(sym.eta).xreplace(trim)
    expected = solve_accelerations(body, -sp.Matrix.hstack(dg, body.D))
    if (model.A[6:, :].xreplace(trim) - expected).applyfunc(sp.expand) != sp.zeros(6, 12):
        raise AssertionError("linearization at the trim is not -M^{-1}[dg_G/deta, D]")
    if (model.B[6:, :] - solve_accelerations(body, body.B_u)).applyfunc(sp.expand) \
            != sp.zeros(6, 4):
        raise AssertionError("B is not M^{-1} B_u")
    if dg[:, :3] != sp.zeros(6, 3) or dg[:, 5] != sp.zeros(6, 1):
        raise AssertionError("dg_G/deta at level attitude has more than the roll, pitch columns")
    return dict(A_nu_eta=_tex(A[6:, :6]), A_nu_nu=_tex(A[6:, 6:]), B_nu=_tex(B[6:, :]),
                dg_deta=_tex(dg[:, 3:5].T))


def _inertial(model):
    """Y in its blocks [[a_O, Y_h, 0], [0, -S(a_O), Y_I]] (each block checked here), and the
    inertia about the CoG in pi."""
    Y = model.inertial.Y
    a_O = Y[:3, 0]
    if Y[3:, 0] != sp.zeros(3, 1) or Y[:3, 4:] != sp.zeros(3, 6):
        raise AssertionError("Y is not block triangular: m in the moments or I_O in the forces")
    if (Y[3:, 1:4] + sym.skew(a_O)).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("the h columns of the moment rows of Y are not -S(a_O)")
    return dict(
        pi=_vec(sym.inertial), h=_vec(sym.h), paper_pi=_vec(model.inertial.paper_pi),
        Y_a=_tex(a_O), Y_hf=_tex(Y[:3, 1:4]), Y_I=_tex(Y[3:, 4:]),
        I_G_pi=_inertia_about_cog_in_pi(model.inertial.body),
    )


def _se3(model):
    """R(q), q_dot and the gravity column of Y on SE(3); the blocks of Y are those of the
    Euler model with R for R(eta) (checked here)."""
    se3 = model.se3
    n = (sym.quaternion.T * sym.quaternion)[0]
    J = (se3.R_q * n).applyfunc(sp.expand)
    a_O = se3.Y[:3, 0]
    if (se3.Y[3:, 1:4] + sym.skew(a_O)).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("the h columns of the moment rows of Y on SE(3) are not -S(a_O)")
    return dict(se3_state=_vec(sym.state_se3), se3_J=_tex(J), se3_qdot=_tex(se3.q_dot),
                se3_a=_tex(a_O))


def _inertia_about_cog_in_pi(body):
    """I_G = I_O - (|h|^2 I - h h^T) / m, checked against the body's, printed as m I_G."""
    h = sym.h
    expected = sym.I_O_full - ((h.T * h)[0] * sp.eye(3) - h * h.T) / sym.m
    if (body.I_G - expected).applyfunc(sp.expand) != sp.zeros(3, 3):
        raise AssertionError("I_G in pi is not I_O - (|h|^2 I - h h^T) / m")
    mI_G = (sym.m * body.I_G).applyfunc(sp.expand)
    formula = r"I_G = I_O - \frac{1}{m}\left(\lVert h\rVert^2 I - h h^T\right)"
    if _fits(formula + " = \\frac{1}{m}", mI_G):
        return f"\\begin{{align*}}\n{formula} = \\frac{{1}}{{m}}{_tex(mI_G)}.\n\\end{{align*}}"
    return f"\\begin{{align*}}\n{formula}.\n\\end{{align*}}"


def render(model):
    """The report text (header included)."""
    body, out = model.body, model.outputs
    ne_names = ["F_x", "F_y", "F_z", r"T_\phi", r"T_\theta", r"T_\psi"]
    definitions, entries = _alpha_b(model)
    fields = dict(
        sympy_version=sp.__version__, casadi_version=casadi.__version__,
        state=_vec(sym.state), inputs=_vec(sym.U), params=_vec(sym.params),
        functions=_function_table(model),
        R=_tex(model.R), Q=_tex(model.Q),
        newton_euler=",\\\\\n".join(f"{n} &= {row}" for n, row in
                                    zip(ne_names, _newton_euler_rows(body.newton_euler))),
        M=_tex(body.M), D=_tex(body.D), B_u=_tex(body.B_u), g_G=_tex(body.g_G),
        C12=_tex(body.C[:3, 3:]), C22=_tex(body.C[3:, 3:]), I_G=_tex(body.I_G),
        Phi=_regressor(model.Phi),
        relative_degree=", ".join(map(str, out.relative_degree)),
        relative_degree_total=str(sum(out.relative_degree)),
        zero_dynamics_dim=str(len(sym.state) - sum(out.relative_degree)),
        kappas=_display(definitions),
        alpha=_display(entries[:16]),
        b=_display(entries[16:]),
        n_kappa=str(len(definitions)),
        **_zero_dynamics(model), **_hover(model), **_comparison(model), **_inertial(model),
        **_se3(model),
    )
    return tex_header() + _TexTemplate(TEMPLATE.read_text()).substitute(fields)

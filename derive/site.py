"""The derived equations for the documentation site, printed by the report's printer.

The docs hook (``docs/gen_reference.py``) puts ``EQUATIONS[name]`` where a page holds
``<!-- equation name -->``, as display mathematics that MathJax renders. Every expression is
printed by the functions that fill the LaTeX report (``derive.latex``: its printer ``_tex``, the
Newton-Euler rows, the regressor's blocks, the zero dynamics and the hover linearization), from
the model that ``derive.model.derive_model`` builds: one source, so a change in ``derive/``
changes the site and the PDF together. Only the names on the left are typed here.

This module is not imported by ``derive.pipeline``, so editing it never makes generated/ stale.
"""
import sympy as sp

from derive import latex
from derive import symbols as sym

__all__ = ["NAMES", "equations"]

# name: what the page says the display shows (used by tests/test_docsite.py to name a gap)
NAMES = {
    "vectors": "the state, input and parameter vectors",
    "R": "the rotation from body to ground axes",
    "Q": "the map from body rates to Euler-angle rates",
    "newton_euler": "the six Newton-Euler rows, as the paper groups them",
    "M": "the mass matrix about O",
    "D_B": "the damping and input matrices",
    "g_G": "the weight's generalized force",
    "C": "the Coriolis-centripetal blocks (Fossen's construction)",
    "I_G": "the inertia about the CoG",
    "Phi": "the regressor's force and moment rows",
    "zero_dynamics": "the zero dynamics on y = 0 and the input that holds it",
    "hover": "the linearization at hover",
}


def _aligned(rows):
    return "\\begin{aligned}\n" + ",\\\\\n".join(rows) + ".\n\\end{aligned}"


def equations(model):
    """Every display of ``NAMES`` as LaTeX (math mode, without delimiters).

    Parameters
    ----------
    model : derive.model.DerivedModel
        The derivation (``derive.model.derive_model()``).

    Returns
    -------
    dict of str to str
        {name: LaTeX}, in the order of ``NAMES``.
    """
    tex = latex._tex
    body = model.body
    ne_names = ["F_x", "F_y", "F_z", r"T_\phi", r"T_\theta", r"T_\psi"]
    Phi = model.Phi
    zd, hover = latex._zero_dynamics(model), latex._hover(model)
    out = {
        "vectors": _aligned([rf"x &= [{latex._vec(sym.state)}]^T",
                             rf"U &= [{latex._vec(sym.U)}]^T",
                             rf"p &= [{latex._vec(sym.params)}]^T"]),
        "R": rf"R = {tex(model.R)}",
        "Q": rf"Q(\eta_2) = {tex(model.Q)}",
        "newton_euler": _aligned([f"{n} &= {row}" for n, row in
                                  zip(ne_names, latex._newton_euler_rows(body.newton_euler))]),
        "M": rf"M = {tex(body.M)}",
        "D_B": rf"D = {tex(body.D)}, \qquad B_u = {tex(body.B_u)}",
        "g_G": rf"g_G(\eta) = -\begin{{bmatrix}} f_G \\ r_G\times f_G \end{{bmatrix}} "
               rf"= {tex(body.g_G)}",
        "C": _aligned([rf"C &= \begin{{bmatrix}} 0 & C_{{12}} \\ -C_{{12}}^T & C_{{22}} "
                       rf"\end{{bmatrix}}, \qquad C_{{12}} = {tex(body.C[:3, 3:])}",
                       rf"C_{{22}} &= {tex(body.C[3:, 3:])}"]),
        "I_G": rf"I_G = I_O - m\,(\lVert r_G\rVert^2 I - r_G r_G^T) = {tex(body.I_G)}",
        "Phi": _aligned([rf"\Phi_{{1:3}} &= {tex(Phi[:3, :])}",
                         rf"\Phi_{{4:6}} &= {tex(sp.Matrix(Phi[3:, :]))}"]),
        "zero_dynamics": _aligned([
            rf"\dot x &= {zd['zd_x']}, \quad \dot y = {zd['zd_y']}, \quad "
            rf"\dot u = {zd['zd_u']}, \quad \dot v = {zd['zd_v']}",
            rf"U^* &= {zd['zd_U']}, \quad \text{{at rest }} U^* = {zd['trim_U']}"]),
        "hover": _aligned([rf"A_{{\nu\eta}} &= {hover['A_nu_eta']}",
                           rf"A_{{\nu\nu}} &= {hover['A_nu_nu']}, \qquad "
                           rf"B_\nu = {hover['B_nu']}"]),
    }
    return {name: out[name] for name in NAMES}

"""The CasADi functions (virtual machine), the compiled C and SymPy lambdify agree."""
from conftest import assert_close
import numpy as np
import pytest
import sympy as sp

from derive import symbols as sym
from derive.contract import FUNCTIONS as SPECS
from derive.contract import VECTORS
from quadcog.model.attitude import quaternion_of_euler
from quadcog.model.conventions import FUNCTIONS, rotation_matrix
from quadcog.model.inertial_parameters import box

RTOL = 1e-12


@pytest.fixture(scope="module")
def lambdified(derived):
    """name -> callable(args by input name) -> list of outputs, from the SymPy objects.

    The I_G^{-1} placeholders are evaluated from their own lambdified definition, so the
    whole chain is SymPy's."""
    gammas = list(sym.I_G_INV_SYMBOLS)
    out = {}
    for spec in SPECS:
        inputs = [list(VECTORS[name][1]) for name in spec.inputs]
        definitions = spec.placeholders(derived)     # {} for a function without I_G^{-1}
        gamma_fn = sp.lambdify(inputs, [definitions.get(s, 0) for s in gammas], "numpy")
        fns = [sp.lambdify(inputs + [gammas], getter(derived), "numpy", cse=True)
               for _, getter in spec.outputs]
        names = list(spec.inputs)
        out[spec.name] = (names, fns, gamma_fn)
    return out


def _args(names, x, U, p, v):
    products = 0.1 * p[2:5] * np.sin(x[:3])      # small products of inertia, I_G stays > 0
    wrench = np.concatenate([v[:3], 0.1 * v[3:]])
    pi = box(p[0], 10 * p[2:5], p[11:14])          # a box of positive volume: consistent
    q = quaternion_of_euler(*x[3:6])               # the model on SE(3): the same attitude
    return [{"x": x, "U": U, "p": p, "vartheta": v, "I_products": products,
             "wrench": wrench, "nu_dot": v, "pi": pi, "g": p[1:2], "c": p[5:11],
             "xq": np.concatenate([x[:3], q, x[6:]]), "R": rotation_matrix(*x[3:6]).ravel(),
             "nu": x[6:], "quaternion": q}[n]
            for n in names]


@pytest.mark.slow
def test_every_function_exported(lambdified):
    assert set(lambdified) == set(FUNCTIONS)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(FUNCTIONS))
def test_c_casadi_sympy_agree(name, model, lambdified, points):
    names, fns, gamma_fn = lambdified[name]
    vm = model.casadi_function(name)
    compiled = getattr(model, name)
    for k, (x, U, p, v) in enumerate(points):
        args = _args(names, x, U, p, v)
        c_out = compiled(*args)
        c_out = list(c_out) if isinstance(c_out, tuple) else [c_out]
        vm_out = vm(*args)
        vm_out = [np.array(o) for o in (vm_out if isinstance(vm_out, tuple) else [vm_out])]
        sp_out = [np.array(f(*args, gamma_fn(*args)), dtype=float) for f in fns]
        for c, m, s in zip(c_out, vm_out, sp_out):
            assert_close(c, m.reshape(c.shape), RTOL, f"{name}: C vs CasADi", k)
            assert_close(c, s.reshape(c.shape), RTOL, f"{name}: C vs SymPy", k)

"""The relative degree and the decoupling matrix at hover. alpha and b against CasADi's
automatic differentiation of the exported dynamics, and alpha = H M^{-1} B_u
(docs/model.md sec. 2.4), are identities in report/identities.py (tests/test_identities.py)."""
import numpy as np

import quadcog


def test_relative_degree_computed(derived):
    assert derived.outputs.relative_degree == (2, 2, 2, 2)
    assert all(e == 0 for e in derived.outputs.L_g_h)


def test_alpha_nonsingular_and_thrust_in_attitude_rows(model):
    x = np.zeros(12)
    balanced = quadcog.default_parameters()
    a0 = model.decoupling(x, balanced)
    assert abs(np.linalg.det(a0)) > 1e-6
    assert np.all(a0[1:, 0] == 0), "balanced: thrust must not enter attitude rows at hover"
    shifted = quadcog.default_parameters(x_G=0.03, y_G=0.02)
    a1 = model.decoupling(x, shifted)
    assert abs(np.linalg.det(a1)) > 1e-6
    assert np.all(np.abs(a1[1:3, 0]) > 1e-3), "shifted CoG: thrust must enter phi, theta rows"

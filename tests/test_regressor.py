"""docs/model.md sec. 3.1: M(r) v + C(nu, r) nu + g(eta, r) - (same at r = 0) = Phi(nu, eta, v) r."""
from conftest import assert_close
import numpy as np

import quadcog


def _lhs(model, x, v, p):
    return model.mass_matrix(p) @ v + model.coriolis(x, p) @ x[6:] + model.gravity(x, p)


def test_linear_in_r_G(model, points):
    """Superposition: Phi r1 + Phi r2 = Phi (r1 + r2)."""
    rng = np.random.default_rng(6)
    for k, (x, U, p, v) in enumerate(points):
        r1, r2 = rng.uniform(-0.02, 0.02, (2, 3))
        base = _lhs(model, x, v, quadcog.with_cog(p, [0, 0, 0]))
        d1 = _lhs(model, x, v, quadcog.with_cog(p, r1)) - base
        d2 = _lhs(model, x, v, quadcog.with_cog(p, r2)) - base
        d12 = _lhs(model, x, v, quadcog.with_cog(p, r1 + r2)) - base
        assert_close(d1 + d2, d12, 1e-12, "linearity in r_G", k)

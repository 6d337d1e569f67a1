"""docs/model.md sec. 3.3: U = [m g, m g y_G, -m g x_G, 0] holds a level hover with an offset
CoG (an identity in report/identities.py); without its moments the vehicle tips."""
import numpy as np

from quadcog.model.conventions import hover_trim


def test_hover_without_moment_accelerates(model, points):
    """The moment is needed: thrust alone tips an unbalanced vehicle (why PD and FL fail)."""
    for k, (_, _, p, _) in enumerate(points[:50]):
        U = hover_trim(p)
        U[1:3] = 0
        ang = model.dynamics(np.zeros(12), U, p)[9:11]
        assert np.linalg.norm(ang) > 1e-3, f"no angular acceleration at point {k}"

"""docs/model.md sec. 3.3: U = [m g, m g y_G, -m g x_G, 0] holds a level hover with an offset CoG."""
import numpy as np

from conftest import assert_close
from quadcog.conventions import hover_trim


def test_hover_trim_zero_acceleration(model, points):
    for k, (x, _, p, _) in enumerate(points):
        x0 = np.zeros(12)
        x0[:3], x0[5] = x[:3], x[5]          # any position and heading, level, at rest
        assert_close(model.dynamics(x0, hover_trim(p), p), np.zeros(12), 1e-12, "x_dot", k)


def test_hover_without_moment_accelerates(model, points):
    """The moment is needed: thrust alone tips an unbalanced vehicle (why PD and FL fail)."""
    for k, (_, _, p, _) in enumerate(points[:50]):
        U = hover_trim(p)
        U[1:3] = 0
        ang = model.dynamics(np.zeros(12), U, p)[9:11]
        assert np.linalg.norm(ang) > 1e-3, f"no angular acceleration at point {k}"

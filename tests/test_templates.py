"""The interfaces of quadcog.controllers.template and quadcog.trajectories.template: the
examples fly, every built-in controller and trajectory satisfies its protocol, and the
modules' own examples (doctests) run.

Wrong implementations this catches: an example that no longer flies (a sign or a unit wrong in
HoverPD, a derivative of VerticalSine that does not match its position), a built-in that lost
an attribute the protocol states (``project_numpy``, ``initial_state``, ``estimates_cog``), and
a protocol that accepts what quadcog cannot call.
"""
import doctest

import numpy as np
import pytest

import quadcog
from quadcog.controllers import template as controller_template
from quadcog.controllers.registry import CONTROLLERS
from quadcog.controllers.template import ControllerProtocol, FullControllerProtocol, HoverPD
from quadcog.trajectories import template as trajectory_template
from quadcog.trajectories.analytic import REF_SIZE, FromCallable
from quadcog.trajectories.registry import TRAJECTORIES, default_kinds, make_trajectory
from quadcog.trajectories.template import TrajectoryProtocol, VerticalSine


@pytest.mark.parametrize("module", [controller_template, trajectory_template],
                         ids=lambda m: m.__name__)
def test_module_examples_run(module):
    failed, attempted = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert attempted > 0 and failed == 0


def test_example_controller_flies_at_hover():
    """From 30 cm, 20 cm and 20 cm off the hover point, HoverPD returns to it."""
    ctrl = HoverPD()
    x0 = np.r_[0.3, -0.2, 0.8, np.zeros(9)]
    result = quadcog.simulate(ctrl, "hover", duration=6.0, path="python", x0=x0)
    assert not result.metrics.diverged
    assert result.controller == "hover_pd"
    assert result.metrics.final_position_error < 2e-3          # m
    assert np.abs(result.x[-1, 3:6]).max() < 1e-3              # rad: level, heading held
    assert np.abs(result.U[-1] - [ctrl.m * ctrl.g, 0, 0, 0]).max() < 1e-2   # N, N m


def test_example_controller_output_shapes_and_units():
    ctrl = HoverPD()
    x = np.r_[0.0, 0.0, 1.0, np.zeros(9)]
    ref = np.r_[0.0, 0.0, 1.0, np.zeros(11)]
    U, c_dot = ctrl(0.0, x, ref, ctrl.initial_state())
    assert U.shape == (4,) and c_dot.shape == (ctrl.n_state,)
    assert U == pytest.approx([0.68 * 9.81, 0.0, 0.0, 0.0])      # m g (N) at hover
    below = ctrl(0.0, x - np.r_[0, 0, 0.1, np.zeros(9)], ref, ctrl.initial_state())
    assert below[0][0] > U[0] and below[1][0] == pytest.approx(0.1)   # climbs; 0.1 m error
    c = np.array([5.0])
    assert ctrl.project_numpy(c) is c and c[0] == ctrl.integral_limit


@pytest.mark.parametrize("name", list(CONTROLLERS))
def test_every_builtin_controller_satisfies_the_protocol(name):
    ctrl = CONTROLLERS[name]()
    assert isinstance(ctrl, ControllerProtocol)
    assert isinstance(ctrl, FullControllerProtocol)
    assert np.asarray(ctrl.initial_state()).shape == (ctrl.n_state,)


def test_what_the_controller_protocol_accepts():
    assert isinstance(HoverPD(), FullControllerProtocol)
    assert isinstance(lambda t, x, ref, c: np.zeros(4), ControllerProtocol)
    assert not isinstance(lambda t, x, ref, c: np.zeros(4), FullControllerProtocol)
    assert not isinstance(object(), ControllerProtocol)
    with pytest.raises(TypeError, match="Protocols cannot be instantiated"):
        ControllerProtocol()
    with pytest.raises(TypeError, match="Protocols cannot be instantiated"):
        FullControllerProtocol()


def _builtin_trajectories():
    out = {kind: make_trajectory(kind) for kind in default_kinds()}
    out["waypoints"] = TRAJECTORIES["waypoints"]([[0, 0, 1], [1, 0, 1], [1, 1, 1.5]])
    out["callable"] = FromCallable(lambda t: [np.cos(t), np.sin(t), 1.0])
    return out


@pytest.mark.parametrize("name", ["hover", "circle", "figure8", "helix", "waypoints",
                                  "callable"])
def test_every_builtin_trajectory_satisfies_the_protocol(name):
    traj = _builtin_trajectories()[name]
    assert isinstance(traj, TrajectoryProtocol)
    t = np.linspace(0.0, 3.0, 7)
    rows = traj.sample(t)
    assert rows.shape == (7, REF_SIZE) and traj(1.5).shape == (REF_SIZE,)
    assert traj(t[2]) == pytest.approx(rows[2])


def test_example_trajectory_rows_and_derivatives():
    bob = VerticalSine(position=(0.5, -0.5, 2.0), amplitude=0.3, period=3.0, yaw=0.2)
    assert isinstance(bob, TrajectoryProtocol)
    assert not isinstance(object(), TrajectoryProtocol)
    t = np.linspace(0.0, 6.0, 61)
    rows = bob.sample(t)
    assert rows.shape == (61, REF_SIZE)
    assert bob(t[7]) == pytest.approx(rows[7])
    assert rows[:, 0:2] == pytest.approx(np.tile([0.5, -0.5], (61, 1)))
    assert rows[:, 12] == pytest.approx(0.2) and rows[:, 13] == pytest.approx(0.0)
    h = 1e-4                                    # each derivative against a central difference
    for rate, of in ((5, 2), (8, 5), (11, 8)):
        fd = (bob.sample(t + h)[:, of] - bob.sample(t - h)[:, of]) / (2 * h)
        assert rows[:, rate] == pytest.approx(fd, rel=1e-6, abs=1e-6)
    with pytest.raises(TypeError, match="Protocols cannot be instantiated"):
        TrajectoryProtocol()


def test_example_trajectory_flies_with_the_example_controller():
    bob = VerticalSine(amplitude=0.2, period=4.0)
    result = quadcog.simulate(HoverPD(), bob, duration=4.0, path="python")
    assert not result.metrics.diverged
    assert result.ref[:, 2] == pytest.approx(bob.sample(result.t)[:, 2])
    assert result.metrics.max_position_error < 0.03           # m, on a 0.2 m bob

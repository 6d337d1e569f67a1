"""The interface a reference trajectory implements, and a complete example.

A trajectory maps time t (s) to the reference row of 14 entries (``quadcog.trajectories
.analytic``, whose slices ``POS``, ``VEL``, ``ACC``, ``JERK``, ``YAW``, ``YAW_RATE`` index it):

====  ==========  ==========  =====================================================
row   name        unit        what
====  ==========  ==========  =====================================================
0-2   x, y, z     m           position, ground axes (z up)
3-5   vx, vy, vz  m/s         velocity, ground axes
6-8   ax, ay, az  m/s^2       acceleration, ground axes
9-11  jx, jy, jz  m/s^3       jerk, ground axes (the controllers feed forward the
                              rate of the attitude they command from it)
12    yaw         rad         heading psi
13    yaw_rate    rad/s       its rate
====  ==========  ==========  =====================================================

``TrajectoryProtocol`` states the two methods every ``quadcog.Trajectory`` has: ``traj(t)``,
one row (14,), and ``traj.sample(t)``, rows (N, 14) for N times. ``quadcog.simulate`` (and
``simulate_batch``) also take any function of time alone: it is wrapped in
``quadcog.trajectories.analytic.FromCallable``, which calls it once per time step and accepts a
position (3,), a tuple (p, v, a[, j]) or the full row (14,); derivatives it does not return
are taken by central differences. Rows must be finite and within +-``REFERENCE_LIMIT`` (SI
units), else the run stops with an ``InputError``.

``VerticalSine`` below is a complete example with exact derivatives:

>>> import numpy as np, quadcog
>>> from quadcog.trajectories.template import VerticalSine
>>> bob = VerticalSine(amplitude=0.2, period=4.0)
>>> bob(1.0)[:3].tolist()                      # m: a quarter period, at the top
[0.0, 0.0, 1.2]
>>> bob.sample(np.linspace(0.0, 4.0, 5)).shape
(5, 14)
>>> from quadcog.controllers.template import HoverPD
>>> result = quadcog.simulate(HoverPD(), bob, duration=2.0, path="python")
"""
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.model.parameters import LARGEST
from quadcog.trajectories.analytic import REF_SIZE, Trajectory, sample_times

__all__ = ["TrajectoryProtocol", "VerticalSine"]

Array = npt.NDArray[np.float64]


@runtime_checkable
class TrajectoryProtocol(Protocol):
    """A reference trajectory: the 14-entry row at a time, and rows at many times.

    See Also
    --------
    quadcog.trajectories.analytic.Trajectory : the base class of quadcog's own trajectories.
    VerticalSine : a complete example.
    """

    # Stated so that the protocol's own signature is empty (typing would give it a
    # placeholder (*args, **kwargs)); a class that implements it needs no such constructor.
    def __init__(self) -> None:
        """Refuse to instantiate the protocol itself (as typing does)."""
        if getattr(type(self), "_is_protocol", False):
            raise TypeError("Protocols cannot be instantiated")

    def __call__(self, t: float) -> Array:
        """The reference row at one time.

        Parameters
        ----------
        t : float
            Time (s).

        Returns
        -------
        (14,) numpy.ndarray
            [p (3, m), v (3, m/s), a (3, m/s^2), j (3, m/s^3), yaw (rad), yaw_rate (rad/s)].
        """
        ...

    def sample(self, t: npt.ArrayLike) -> Array:
        """The reference rows at many times.

        Parameters
        ----------
        t : float or (N,) array_like
            Times (s).

        Returns
        -------
        (N, 14) numpy.ndarray
            One row per time, as ``__call__``.
        """
        ...


class VerticalSine:
    """An example trajectory: hold x, y and bob up and down, z = z0 + A sin(w t), w = 2 pi / T.

    Parameters
    ----------
    position : (3,) array_like
        The centre [x, y, z0] (m), ground axes; default [0, 0, 1].
    amplitude : float
        A (m), default 0.1.
    period : float
        T (s), > 0; default 5.
    yaw : float
        Heading held (rad), default 0.

    Raises
    ------
    InputError
        When a setting is not finite, the amplitude beyond +-LARGEST m or the period below
        2 pi / LARGEST s (``quadcog.model.parameters``: the rows then stay finite).
    """

    def __init__(self, position: npt.ArrayLike = (0.0, 0.0, 1.0), amplitude: float = 0.1,
                 period: float = 5.0, yaw: float = 0.0) -> None:
        self.position = validate.array(position, "position", (3,))          # (3,) m
        self.amplitude = validate.real(amplitude, "amplitude", lo=-LARGEST, hi=LARGEST,
                                       unit="m")                            # m
        # at least 2 pi / LARGEST s: w^3 A stays finite (a period of 1e-320 s gave NaN rows)
        self.period = validate.real(period, "period", lo=2 * np.pi / LARGEST, unit="s")
        self.yaw = validate.real(yaw, "yaw", unit="rad")                    # rad

    def sample(self, t: npt.ArrayLike) -> Array:
        """The reference rows at many times, with exact derivatives.

        Parameters
        ----------
        t : float or (N,) array_like
            Times (s).

        Returns
        -------
        (N, 14) numpy.ndarray
            [p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)] per time.

        Raises
        ------
        InputError
            When ``t`` is not finite times (``quadcog.trajectories.analytic.sample_times``).
        """
        t = sample_times(t)                                          # (N,) s, finite
        w = 2.0 * np.pi / self.period                                # rad/s
        A = self.amplitude                                           # m
        ref = np.zeros((t.size, REF_SIZE))                           # (N, 14)
        ref[:, 0:3] = self.position                                  # m
        ref[:, 2] += A * np.sin(w * t)                               # z (m)
        ref[:, 5] = A * w * np.cos(w * t)                            # vz (m/s)
        ref[:, 8] = -A * w ** 2 * np.sin(w * t)                      # az (m/s^2)
        ref[:, 11] = -A * w ** 3 * np.cos(w * t)                     # jz (m/s^3)
        ref[:, 12] = self.yaw                                        # yaw (rad); rate 0
        return ref

    def __call__(self, t: float) -> Array:
        """The reference row at one time.

        Parameters
        ----------
        t : float
            Time (s).

        Returns
        -------
        (14,) numpy.ndarray
            [p (m), v (m/s), a (m/s^2), j (m/s^3), yaw (rad), yaw_rate (rad/s)].
        """
        return self.sample([t])[0]

    def __repr__(self) -> str:
        return (f"VerticalSine(position={self.position.tolist()}, amplitude={self.amplitude:g}, "
                f"period={self.period:g}, yaw={self.yaw:g})")


if TYPE_CHECKING:       # mypy checks that the example and the built-ins satisfy the protocol
    _example: TrajectoryProtocol = VerticalSine()
    _builtin: TrajectoryProtocol = Trajectory()

"""A payload: a rigid body fastened to the vehicle (a parcel, a battery, a weight taped on).

A payload is a solid homogeneous box with its edges along the body axes, or a point mass (a box
of size zero). It is known by its ten inertial parameters about O (``inertial_parameters``, the
order of ``quadcog.model.inertial_parameters.PI_NAMES``); because mass, first moment and inertia
are integrals over the body, a vehicle carrying payloads has the sum of their pi and its own
(``Vehicle.with_payload``), and the truth model flies that sum.
"""
from dataclasses import dataclass
from functools import cached_property
from typing import Any, cast

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import InputError, ParameterError
from quadcog.model.inertial_parameters import placed
from quadcog.model.parameters import LARGEST
from quadcog.vehicles.description import PAYLOAD_REACH, THRUST_TO_WEIGHT

__all__ = ["Payload", "as_payload", "PAYLOAD_REACH", "check_reach", "check_lift"]
# PAYLOAD_REACH (10 arm lengths) is defined with the vehicle files' bounds, which hold a
# file's own links to it too (quadcog.vehicles.description)



def check_reach(position: npt.ArrayLike, size: npt.ArrayLike | None, arm: float,
                where: str) -> None:
    """Refuse a payload not carried on the vehicle: its centre, or its box's far corner,
    farther from O than ``PAYLOAD_REACH`` arm lengths.

    Parameters
    ----------
    position : (3,) array_like
        The payload's centre (m, body frame).
    size : (3,) array_like or None
        The box's sides (m); None: a point mass.
    arm : float
        The vehicle's arm length (m).
    where : str
        The start of the message (the payload or the event).

    Raises
    ------
    InputError
        Naming the position (and size), the distance and the reach.
    """
    # checked here too: a public function, and a NaN arm or centre read as "beyond reach"
    arm = validate.real(arm, f"{where}: arm length", lo=0.0, lo_open=True, unit="m")
    position = validate.array(position, f"{where}: position", (3,),
                              what="3 finite numbers (m, body axes)")
    if size is not None:
        size = validate.array(size, f"{where}: size", (3,), what="3 edge lengths >= 0 (m)")
    reach = PAYLOAD_REACH * arm
    centre = float(np.linalg.norm(position))
    corner = centre + (0.0 if size is None else 0.5 * float(np.linalg.norm(size)))
    if not centre <= reach:
        raise InputError(f"{where}: its centre {np.asarray(position).tolist()} m is {centre:.3g} m from O, "
                         f"beyond {PAYLOAD_REACH:g} arm lengths ({reach:.3g} m); a payload is "
                         "carried on the vehicle")
    if not corner <= reach:
        raise InputError(f"{where}: its box of size {np.asarray(size).tolist()} m at {np.asarray(position).tolist()} m "
                         f"reaches {corner:.3g} m from O, beyond {PAYLOAD_REACH:g} arm lengths "
                         f"({reach:.3g} m); a payload is carried on the vehicle")


def check_lift(mass: float, on_board: float, g: float, max_thrust: float, where: str) -> None:
    """Refuse a payload that the vehicle cannot carry: with it on board, the rotors' largest
    total thrust must exceed the weight (a thrust-to-weight ratio above
    ``quadcog.vehicles.description.THRUST_TO_WEIGHT[0]``, 1: else the vehicle cannot even
    hover with it).

    Parameters
    ----------
    mass : float
        The payload's mass (kg), checked (> 0).
    on_board : float
        The mass already carried without it: the airframe's and the other payloads' (kg).
    g : float
        Gravitational acceleration (m/s^2), > 0.
    max_thrust : float
        The rotors' largest total thrust (N): ``N_ROTORS * max_rotor_thrust``.
    where : str
        The start of the message (the vehicle and the payload, or the event).

    Raises
    ------
    quadcog.ParameterError
        Naming the payload's mass, the most the rotors lift beyond what is on board, and
        what that was computed from.
    """
    lo = THRUST_TO_WEIGHT[0]
    if (on_board + mass) * g * lo < max_thrust:     # NaN and inf fail (none reach here)
        return
    capacity = max_thrust / (lo * g) - on_board
    lift = (f"the rotors' largest total thrust {max_thrust:.4g} N at g = {g:g} m/s^2 "
            f"(a thrust-to-weight ratio above {lo:g})")
    what = (f"a mass below {capacity:.4g} kg, what {lift} lifts beyond the {on_board:.4g} kg "
            "already on board (the airframe and the other payloads)" if capacity > 0 else
            f"no payload: {lift} does not lift even the {on_board:.4g} kg already on board "
            "(the airframe and the other payloads)")
    validate.fail(f"{where}: mass", what, mass, ParameterError)


@dataclass(frozen=True)
class Payload:
    """A rigid body carried by the vehicle. Units SI.

    Parameters
    ----------
    mass : float
        Its mass (kg), > 0.
    position : (3,) tuple of float
        Its centre (its CoG) from O in body axes (m).
    size : (3,) tuple of float, default (0, 0, 0)
        Edge lengths along body x, y, z (m), >= 0: a solid homogeneous box; all zero: a
        point mass.
    name : str, default "payload"
        A label; scenarios attach, move and drop payloads by it.

    Raises
    ------
    quadcog.InputError
        A field of the wrong type or shape, naming it.
    quadcog.ParameterError
        A mass that is not > 0, an edge below 0 or a number beyond the model's scale.
    """
    mass: float
    position: tuple[float, float, float]
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    name: str = "payload"

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            validate.fail("payload name", "a non-empty string", self.name)
        # a str subclass (numpy.str_) is kept as the plain str that JSON and TOML write
        object.__setattr__(self, "name", str(self.name))
        where = f"payload {self.name!r}"
        m = validate.real(self.mass, f"{where}: mass", lo=0.0, lo_open=True, hi=LARGEST,
                         unit="kg", error=ParameterError)
        r = validate.array(self.position, f"{where}: position", (3,),
                           what="3 finite numbers (m, body axes)")
        s = validate.array(self.size, f"{where}: size", (3,),
                           what="3 edge lengths >= 0 (m)")
        if not np.abs(r).max() <= LARGEST:
            validate.fail(f"{where}: position", f"entries within +-{LARGEST:g} m", r.tolist(),
                          ParameterError)
        if not (s.min() >= 0 and s.max() <= LARGEST):
            validate.fail(f"{where}: size", f"3 edge lengths in [0, {LARGEST:g}] m", s.tolist(),
                          ParameterError)
        object.__setattr__(self, "mass", m)
        object.__setattr__(self, "position", tuple(float(v) for v in r))
        object.__setattr__(self, "size", tuple(float(v) for v in s))

    def inertia_about_centre(self) -> npt.NDArray[np.float64]:
        """Its inertia about its own CoG, a solid homogeneous box's.

        Returns
        -------
        (3, 3) numpy.ndarray
            ``m / 12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)`` (kg m^2) for edges a, b, c; zero for
            a point mass.
        """
        a, b, c = self.size
        return self.mass / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])

    def inertial_parameters(self, positions: npt.ArrayLike | None = None) -> npt.NDArray[np.float64]:
        """Its ten inertial parameters about O.

        Parameters
        ----------
        positions : (N, 3) array_like, optional
            Positions of its centre (m, body axes) to evaluate at instead of ``position``.

        Returns
        -------
        (10,) or (N, 10) numpy.ndarray
            ``[m, m x, m y, m z, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (kg, kg m, kg m^2): the
            inertia about its centre moved to O by the parallel-axis theorem
            (``quadcog.model.inertial_parameters.placed``); one row per position when
            ``positions`` is given.

        Raises
        ------
        quadcog.InputError
            ``positions`` not an (N, 3) array of finite real numbers.
        quadcog.ParameterError
            A position beyond the model's scale (``LARGEST`` m), where pi would overflow.
        """
        if positions is None:
            return self._pi.copy()
        where = f"payload {self.name!r}: positions"
        r = validate.array(positions, where, (None, 3),
                           what="an (N, 3) array of finite positions (m, body axes)")
        # as a payload's own position: past LARGEST m the parallel-axis terms m r^2 overflow
        # to inf and their differences to NaN (a move to 1e300 m gave pi of NaN, silently)
        if r.size and not np.abs(r).max() <= LARGEST:
            validate.fail(where, f"entries within +-{LARGEST:g} m", float(np.abs(r).max()),
                          ParameterError)
        return placed(self.mass, self.inertia_about_centre(), r)

    @cached_property
    def _pi(self) -> npt.NDArray[np.float64]:
        """Its pi at its own position, computed once: a vehicle carrying thousands of
        payloads sums them without placing each again (``Vehicle.with_payload``)."""
        return placed(self.mass, self.inertia_about_centre(), [self.position])[0]

    def moved(self, position: npt.ArrayLike) -> "Payload":
        """The same payload at another position.

        Parameters
        ----------
        position : (3,) array_like
            Its new centre from O in body axes (m).

        Returns
        -------
        Payload
            The moved payload (validated).

        Raises
        ------
        quadcog.InputError
            A position that is not 3 real numbers (bools and complex numbers are not cast).
        """
        # checked and made a tuple of floats by __post_init__, as for a new payload
        return Payload(self.mass, cast(tuple[float, float, float], position), self.size,
                       self.name)

    def as_dict(self) -> dict[str, Any]:
        """Its fields as plain Python values (for JSON and scenario files).

        Returns
        -------
        dict of str to Any
            ``{"name", "mass", "position", "size"}``, the vectors as lists.
        """
        return {"name": self.name, "mass": self.mass, "position": list(self.position),
                "size": list(self.size)}


def as_payload(value: Any, where: str = "payload") -> Payload:
    """A Payload from a Payload or a table of its fields.

    Parameters
    ----------
    value : Payload or dict
        A Payload, or a dict with keys ``mass``, ``position`` and optionally ``size``, ``name``.
    where : str, optional
        Where the value came from (an argument or a scenario key), for the message.

    Returns
    -------
    Payload
        The checked payload.

    Raises
    ------
    quadcog.InputError
        A value that is neither, or a table with unknown or missing keys.
    """
    if isinstance(value, Payload):
        return value
    if not isinstance(value, dict):
        validate.fail(where, "a quadcog Payload or a table with keys mass, position[, size, name]",
                      value)
    unknown = sorted(set(value) - {"mass", "position", "size", "name"})
    missing = sorted({"mass", "position"} - set(value))
    if unknown or missing:
        raise InputError(f"{where}: " + "; ".join(
            ([f"unknown key(s) {', '.join(map(repr, unknown))}"] if unknown else [])
            + ([f"missing key(s) {', '.join(map(repr, missing))}"] if missing else []))
            + "; expected keys mass (kg), position (m) and optionally size (m), name")
    return Payload(**value)

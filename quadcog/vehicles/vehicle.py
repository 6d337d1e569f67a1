"""The vehicle: everything physical about a quadrotor in one typed, documented, frozen object.

A ``Vehicle`` holds the rigid body (mass, inertia about O, linear drag, gravity, the CoG offset
``r_G``) and the rotors (positions in the rotor plane, spin directions, thrust and moment
constants, thrust limits, motor time constant). It gives the 14-entry parameter vector of the
generated functions (``parameters()``) and the mixer ``U = mixer() @ f`` from rotor thrusts
``f`` (N) to ``U = [U1 (N), U2, U3, U4 (N m, about O)]`` and back (``rotor_thrusts(U)``).

Four vehicles ship, nearly two orders of magnitude apart in mass: ``HUMMINGBIRD`` (AscTec
Hummingbird, 0.68 kg, "+" layout, the default), ``CRAZYFLIE`` (Bitcraze Crazyflie 2.0, 27 g,
"X" layout), ``CRAZYFLIE_21`` (Crazyflie 2.1 from its firmware's constants, 29 g) and
``X500`` (Holybro X500 as in PX4's Gazebo model, 2 kg, "X" layout). Any planar layout of four rotors is data:
``Vehicle(..., rotor_positions=x_layout(0.225), rotor_directions=(1, -1, 1, -1), ...)``.

Frames: body x forward, z up (thrust along +z at O), so a rotor at (x_i, y_i) with thrust f_i
adds ``y_i f_i`` to the roll moment U2 and ``-x_i f_i`` to the pitch moment U3. A rotor's drag
(reaction) moment on the body is ``d_i k f_i`` about body z, with ``d_i = rotor_directions[i]``:
+1 for a rotor turning clockwise seen from above (its reaction turns the body
counter-clockwise), -1 for counter-clockwise.
"""
import copy
from dataclasses import asdict, dataclass, fields, replace
from functools import cached_property
import os
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError, ParameterError, VehicleFileError
from quadcog.model.conventions import IDX, PARAM_NAMES, R_G, hover_trim
from quadcog.model.inertial_parameters import (
    check_physically_consistent,
    from_inertial_parameters,
    inertial_parameters,
    is_physically_consistent,
)
from quadcog.model.parameters import LARGEST, SMALLEST, check_parameters
from quadcog.numerics import exact_inverse
from quadcog.validate import array, fail, plain, real, vector
from quadcog.vehicles.description import (
    MAX_MOMENT_CONSTANT,
    MAX_MOTOR_TIME_CONSTANT,
    check_options,
    file_fields,
    sdf_fields,
    urdf_fields,
)
from quadcog.vehicles.payload import Payload, as_payload, check_lift, check_reach
from quadcog.vehicles.rotor_model import CRAZYFLIE_21_PLUS_CUBIC, CRAZYFLIE_BITCRAZE_VOLTAGE, ROTOR_MODELS, RotorModel

__all__ = ["Vehicle", "HUMMINGBIRD", "CRAZYFLIE", "CRAZYFLIE_21", "X500", "PRESETS", "FIELD_NAMES", "N_ROTORS",
           "plus_layout", "x_layout", "default_parameters", "preset_drag", "DENSEST",
           "least_inertia_trace"]

N_ROTORS = 4
# kg/m^3, osmium's, the densest element: no airframe is denser, which bounds its inertia
DENSEST = 22_590.0


def least_inertia_trace(m: float) -> float:
    """The least Ixx + Iyy + Izz a body of mass ``m`` can have, no part denser than DENSEST.

    Among bodies of a given mass and largest density, a ball of that density has the least
    trace about its centre: 6/5 m R^2, R = (3 m / (4 pi DENSEST))^(1/3); about any other
    point the trace is larger still.

    Parameters
    ----------
    m : float
        The mass (kg), >= 0.

    Returns
    -------
    float
        The least trace (kg m^2).
    """
    radius = (3.0 * m / (4.0 * np.pi * DENSEST)) ** (1.0 / 3.0)
    return 1.2 * m * radius ** 2

Layout = tuple[tuple[float, float], ...]


def plus_layout(arm: float) -> Layout:
    """Rotor positions of a "+" frame: rotor 1 on +x (front), 2 on +y (left), 3 on -x, 4 on -y.

    Parameters
    ----------
    arm : float
        Arm length, centre to rotor (m), in (0, LARGEST] (``quadcog.model.parameters``).

    Returns
    -------
    tuple of 4 (x, y) pairs of float
        Rotor positions (m) in the body frame, for ``Vehicle.rotor_positions``.
    """
    a = real(arm, "arm", lo=0, lo_open=True, hi=LARGEST, unit="m")
    return ((a, 0.0), (0.0, a), (-a, 0.0), (0.0, -a))


def x_layout(arm: float) -> Layout:
    """Rotor positions of an "X" frame: rotor 1 front-right (+x, -y), 2 back-right,
    3 back-left, 4 front-left (the Crazyflie firmware's M1..M4).

    Parameters
    ----------
    arm : float
        Arm length, centre to rotor (m), in (0, LARGEST] (``quadcog.model.parameters``).

    Returns
    -------
    tuple of 4 (x, y) pairs of float
        Rotor positions (m) in the body frame, for ``Vehicle.rotor_positions``.
    """
    h = real(arm, "arm", lo=0, lo_open=True, hi=LARGEST, unit="m") / np.sqrt(2.0)
    return ((h, -h), (-h, -h), (-h, h), (h, h))     # the Crazyflie firmware's M1..M4


@dataclass(frozen=True)
class Vehicle:
    """A quadrotor: rigid body and rotors. Units SI; all numbers are plain floats.

    Parameters
    ----------
    m : float
        Mass (kg), > 0.
    g : float
        Gravitational acceleration (m/s^2), > 0.
    Ixx : float
        Roll inertia about O at the stated CoG (kg m^2), > 0; with ``r_G = 0`` the inertia
        about the CoG. The model holds ``Ixx``, ``Iyy``, ``Izz`` constant as the CoG moves (the
        truth model's ``parallel_axis`` option adds the change).
    Iyy : float
        Pitch inertia about O at the stated CoG (kg m^2), > 0.
    Izz : float
        Yaw inertia about O at the stated CoG (kg m^2), > 0.
    c_x : float
        Linear drag of the forward body velocity u (N s/m), >= 0.
    c_y : float
        Linear drag of the sideways body velocity v (N s/m), >= 0.
    c_z : float
        Linear drag of the vertical body velocity w (N s/m), >= 0.
    c_phi : float
        Linear drag of the roll rate p (N m s/rad), >= 0.
    c_theta : float
        Linear drag of the pitch rate q (N m s/rad), >= 0.
    c_psi : float
        Linear drag of the yaw rate r (N m s/rad), >= 0.
    rotor_positions : (4, 2) array_like
        Four (x, y) pairs (m) in the body frame, in the rotor plane through O
        (``plus_layout(arm)``, ``x_layout(arm)`` or any); stored as a tuple of tuples.
    rotor_directions : (4,) sequence of int
        Four signs d_i (+1 or -1): rotor i's drag moment on the body is
        ``d_i * moment_constant * f_i`` about body z (+1: the rotor turns clockwise seen from
        above).
    thrust_constant : float
        Rotor thrust per squared rotor speed (N / (rad/s)^2), > 0; converts thrust limits to
        and from rotor speeds.
    moment_constant : float
        Rotor drag moment per unit thrust (m), > 0.
    max_rotor_thrust : float
        Largest thrust of one rotor (N), > min_rotor_thrust.
    min_rotor_thrust : float, default 0
        Smallest thrust of one rotor (N), >= 0 (rotors only push).
    motor_time_constant : float, default 0
        First-order time constant from commanded to actual rotor thrust (s), >= 0; 0 means
        instant. Used by the truth model's ``motor_lag`` option.
    x_G : float, default 0
        CoG offset from O along body x (m, forward). The inertia about the CoG,
        ``I_O - m (|r_G|^2 I - r_G r_G^T)`` with ``r_G = [x_G, y_G, z_G]``, must stay
        positive definite.
    y_G : float, default 0
        CoG offset from O along body y (m, left).
    z_G : float, default 0
        CoG offset from O along body z (m, up).
    name : str, default "vehicle"
        A label.
    rotor_model : RotorModel or str or None, default None
        A ``quadcog.vehicles.rotor_model.RotorModel`` or the name of one in its
        ``ROTOR_MODELS`` (optional): what turns this vehicle's logged motor outputs into rotor
        thrust (``quadcog identify`` reads it); ``as_dict`` writes its name.
    payloads : tuple of Payload, default ()
        Rigid bodies it carries (``with_payload``; dicts of their fields are accepted). The
        fields above are the airframe's; ``inertial_parameters`` and ``parameters`` are those
        of the whole body, airframe and payloads, which must be physically consistent.

    Raises
    ------
    ParameterError
        Naming the field and the value, for a value out of range (or a singular mixer, or an
        inertia about the CoG that is not positive definite).
    InputError
        Naming the field and the value, for a value of the wrong type or shape.
    """
    m: float
    g: float
    Ixx: float
    Iyy: float
    Izz: float
    c_x: float
    c_y: float
    c_z: float
    c_phi: float
    c_theta: float
    c_psi: float
    rotor_positions: tuple[tuple[float, float], ...]
    rotor_directions: tuple[int, ...]
    thrust_constant: float
    moment_constant: float
    max_rotor_thrust: float
    min_rotor_thrust: float = 0.0
    motor_time_constant: float = 0.0
    x_G: float = 0.0
    y_G: float = 0.0
    z_G: float = 0.0
    name: str = "vehicle"
    rotor_model: RotorModel | None = None
    payloads: tuple[Payload, ...] = ()

    def __post_init__(self) -> None:
        # a name that is not a string (refused below) is written plainly, never as a numpy repr
        shown = repr(self.name) if isinstance(self.name, str) else plain(self.name)
        where = lambda f: f"vehicle {shown}: {f}"
        for f in fields(self):
            if f.name in ("rotor_positions", "rotor_directions", "name", "rotor_model", "payloads"):
                continue
            v = getattr(self, f.name)
            if isinstance(v, bool) or not isinstance(v, (int, float, np.integer, np.floating)):
                raise InputError(where(f"{f.name} must be a number, got {plain(v)}"))
            try:
                x = float(v)
            except OverflowError:       # an int beyond the float range
                raise ParameterError(where(f"{f.name} = {plain(v)} is beyond the range of "
                                           f"a float")) from None
            if not np.isfinite(x):
                raise ParameterError(where(f"{f.name} = {plain(v)} is not finite"))
            object.__setattr__(self, f.name, x)
        if not isinstance(self.name, str):
            raise InputError(where(f"name must be a string, got {plain(self.name)}"))
        # real numbers only (validate.array): numpy's float() cast took '0.1' and True as
        # numbers and dropped the imaginary part of complex ones
        pos = array(self.rotor_positions, where("rotor_positions"), (N_ROTORS, 2),
                    what=f"{N_ROTORS} pairs (x, y) of finite numbers (m)")
        if not np.abs(pos).max() <= LARGEST:
            fail(where("rotor_positions"), f"{N_ROTORS} pairs (x, y) within +-{LARGEST:g} m "
                 "(the model's scale)", pos.tolist(), ParameterError)
        object.__setattr__(self, "rotor_positions", tuple(tuple(map(float, r)) for r in pos))
        try:         # np.ndim of a ragged list raises ValueError
            flat = not isinstance(self.rotor_directions, (str, bytes)) and \
                np.ndim(self.rotor_directions) == 1
        except ValueError:
            flat = False
        dirs = tuple(self.rotor_directions) if flat else None
        if dirs is None or len(dirs) != N_ROTORS or any(
                isinstance(d, (bool, np.bool_)) or d not in (1, -1) for d in dirs):
            raise InputError(where(f"rotor_directions must be {N_ROTORS} numbers, each +1 or -1, "
                                   f"got {plain(self.rotor_directions)}"))
        object.__setattr__(self, "rotor_directions", tuple(int(d) for d in dirs))
        if isinstance(self.rotor_model, str) and self.rotor_model in ROTOR_MODELS:
            object.__setattr__(self, "rotor_model", ROTOR_MODELS[self.rotor_model])
        if self.rotor_model is not None and not isinstance(self.rotor_model, RotorModel):
            raise InputError(where(f"rotor_model must be a quadcog RotorModel, a name of "
                                   f"{tuple(ROTOR_MODELS)} or None, got "
                                   f"{plain(self.rotor_model)}"))
        for name in ("thrust_constant", "moment_constant", "max_rotor_thrust"):
            if getattr(self, name) <= 0:
                raise ParameterError(where(f"{name} = {getattr(self, name)} must be > 0"))
        # the scale of each rotor constant: the model's (LARGEST), and what a propeller and a
        # motor can be (the readers of vehicle files hold files to the same bounds)
        for name, hi, unit, why in (
                ("thrust_constant", LARGEST, "N/(rad/s)^2", "the model's scale"),
                ("max_rotor_thrust", LARGEST, "N", "the model's scale"),
                ("moment_constant", MAX_MOMENT_CONSTANT, "m", "a propeller's drag moment per "
                 "thrust"),
                ("motor_time_constant", MAX_MOTOR_TIME_CONSTANT, "s", "a motor that can hold "
                 "a quadrotor's attitude")):
            if not getattr(self, name) <= hi:
                fail(where(name), f"a number <= {hi:g} ({unit}, {why})", getattr(self, name),
                     ParameterError)
        if self.min_rotor_thrust < 0:
            raise ParameterError(where(f"min_rotor_thrust = {self.min_rotor_thrust} N must be "
                                       ">= 0 (a rotor only pushes)"))
        if self.min_rotor_thrust >= self.max_rotor_thrust:
            raise ParameterError(where(
                f"min_rotor_thrust = {self.min_rotor_thrust} N must be below max_rotor_thrust = "
                f"{self.max_rotor_thrust} N"))
        if self.motor_time_constant < 0:
            raise ParameterError(where(f"motor_time_constant = {self.motor_time_constant} s must "
                                       "be >= 0 (0: instant)"))
        cond = np.linalg.cond(self.mixer())
        if not cond < 1e12:
            raise ParameterError(where(
                f"the mixer of rotor_positions {self.rotor_positions} and rotor_directions "
                f"{self.rotor_directions} is singular (condition number {cond:.3g}): the rotors "
                "cannot produce every [U1, U2, U3, U4]"))
        # the airframe's own parameters as the paper's model takes them; with payloads the
        # whole body must be a rigid body's (the pseudo-inertia), which makes the admissible
        # radius of the paper's model (I_O held as the CoG moves) moot for it
        check_parameters(np.array([getattr(self, n) for n in PARAM_NAMES], dtype=float),
                         where("parameters"))
        # an airframe lighter in inertia than a ball of osmium of its mass has its mass or its
        # inertias in other units (a file's 27 g read as 27 kg); each unit alone passes the
        # checks above, since the rotors' thrust is read per mass
        trace, least = self.Ixx + self.Iyy + self.Izz, least_inertia_trace(self.m)
        if not trace >= least:
            fail(where("Ixx + Iyy + Izz"), f"at least {least:.3g} kg m^2, what a ball of "
                 f"osmium (the densest element) of m = {self.m:g} kg has: a mass in kg and "
                 "inertias in kg m^2 (a mass in grams?)", trace, ParameterError)
        _check_payloads(self, where)
        _check_rigid_body(self, where)

    @cached_property
    def _whole_pi(self) -> npt.NDArray[np.float64]:
        """pi of the whole body, computed once (``inertial_parameters`` hands out copies)."""
        pi = inertial_parameters(self.m, self.r_G, np.diag([self.Ixx, self.Iyy, self.Izz]),
                                 f"vehicle {self.name!r}")
        for payload in self.payloads:
            pi = pi + payload.inertial_parameters()
        return pi

    @cached_property
    def _payload_names(self) -> frozenset[str]:
        return frozenset(p.name for p in self.payloads)

    # -- from the files users have -------------------------------------------------------
    @classmethod
    def from_urdf(cls, path: str | os.PathLike[str], drag: dict[str, float] | None = None,
                  **options: Any) -> "Vehicle":
        """A vehicle from a URDF file (gym-pybullet-drones' ``cf2x.urdf`` and its kind).

        Parameters
        ----------
        path : str or os.PathLike
            The URDF file.
        drag : dict of str to float, optional
            The six drag coefficients by field name; default ``preset_drag`` (the file has
            none).
        **options
            ``rotor_directions``, ``g``, ``name``: see
            ``quadcog.vehicles.description.urdf_fields``, which says what is read and how the
            file's inertia about the CoG becomes this class's inertia about O.

        Returns
        -------
        Vehicle
            The vehicle.

        Raises
        ------
        VehicleFileError
            A missing file, a needed value missing, not a number or out of its range, links
            that are not one tree of uniquely named links
            (``quadcog.vehicles.description.urdf_fields``), or a CoG that leaves no level
            hover within the rotors' thrusts (named with the file).
        InputError
            An unknown option, or ``drag`` not None or a table of the six drag coefficients.
        PhysicalConsistencyError
            A link whose mass and inertia no rigid body has.
        """
        check_options(urdf_fields, options, "Vehicle.from_urdf")
        return cls._from_fields(urdf_fields(path, **options), drag, path)

    @classmethod
    def from_sdf(cls, path: str | os.PathLike[str], drag: dict[str, float] | None = None,
                 **options: Any) -> "Vehicle":
        """A vehicle from an SDF model (Gazebo; PX4's gz ``x500/model.sdf``).

        Parameters
        ----------
        path : str or os.PathLike
            The model's SDF file; ``model://`` includes are found beside its folder or in
            ``model_paths``.
        drag : dict of str to float, optional
            The six drag coefficients by field name; default ``preset_drag``.
        **options
            ``model_paths``, ``g``, ``name``, ``rotor_links``: see
            ``quadcog.vehicles.description.sdf_fields``.

        Returns
        -------
        Vehicle
            The vehicle.

        Raises
        ------
        VehicleFileError
            A missing file or included model, includes that loop or copy too much, a
            needed value missing, not a number or out of its range
            (``quadcog.vehicles.description.sdf_fields``), or a CoG that leaves no level
            hover within the rotors' thrusts.
        InputError
            An unknown option, or ``drag`` not None or a table of the six drag coefficients.
        PhysicalConsistencyError
            A link whose mass and inertia no rigid body has.
        """
        check_options(sdf_fields, options, "Vehicle.from_sdf")
        return cls._from_fields(sdf_fields(path, **options), drag, path)

    @classmethod
    def from_file(cls, path: str | os.PathLike[str], drag: dict[str, float] | None = None,
                  **options: Any) -> "Vehicle":
        """A vehicle from a ``.urdf`` or ``.sdf`` file, by its suffix.

        Parameters
        ----------
        path : str or os.PathLike
            The file.
        drag : dict of str to float, optional
            The six drag coefficients by field name; default ``preset_drag``.
        **options
            Passed on to ``from_urdf`` or ``from_sdf``.

        Returns
        -------
        Vehicle
            The vehicle.

        Raises
        ------
        VehicleFileError
            Another suffix, or what ``from_urdf`` or ``from_sdf`` raises.
        InputError
            An unknown option, or ``drag`` not None or a table of the six drag coefficients.
        """
        return cls._from_fields(file_fields(path, **options), drag, path)

    @classmethod
    def _from_fields(cls, fields_: dict[str, Any], drag: dict[str, float] | None,
                     path: str | os.PathLike[str]) -> "Vehicle":
        names = tuple(preset_drag(1.0, 1.0))            # the six drag fields, in order
        if drag is None:
            drag = preset_drag(fields_["m"], fields_["Ixx"])
        elif not isinstance(drag, dict) or set(drag) != set(names):
            # a partial or misspelt table was a raw TypeError of the constructor
            got = (f"a table with keys {sorted(map(str, drag))}" if isinstance(drag, dict)
                   else plain(drag))
            raise InputError(f"drag: expected None or a table of the six drag coefficients "
                             f"{', '.join(names)} (N s/m, N m s/rad), got {got}")
        vehicle = cls(**{**fields_, **drag})
        # a file's CoG comes with its inertia, so the model's admissible radius does not bound
        # it: a CoG outside the rotors' polygon (or too near a rotor) leaves no level hover
        # within the rotors' thrusts, and the file was flown as if it had one
        f = vehicle.rotor_thrusts(vehicle.hover_input())
        if not ((f >= vehicle.min_rotor_thrust).all() and (f <= vehicle.max_rotor_thrust).all()):
            raise VehicleFileError(
                f"{path}: the links' CoG at ({vehicle.x_G:.4g}, {vehicle.y_G:.4g}) m from the "
                f"rotors' centre needs rotor thrusts {[float(f'{x:.4g}') for x in f]} N to hover; "
                f"expected each in [{vehicle.min_rotor_thrust:g}, "
                f"{vehicle.max_rotor_thrust:.4g}] N (a CoG inside the rotors' polygon, which "
                "the rotors can hold level)")
        return vehicle

    # -- what the generated functions and the plant need --------------------------------
    def parameters(self) -> npt.NDArray[np.float64]:
        """The parameter vector p of the generated functions: the paper's model of the whole
        body.

        With payloads, m and r_G are the whole body's and Ixx, Iyy, Izz the diagonal of its
        inertia about O; the products of inertia are left out, as the paper's model has none
        (``inertial_parameters`` keeps them, and the truth model flies them).

        Returns
        -------
        (14,) numpy.ndarray
            ``[m, g, Ixx, Iyy, Izz, c_x, c_y, c_z, c_phi, c_theta, c_psi, x_G, y_G, z_G]``
            [kg, m/s^2, kg m^2 (3), N s/m (3), N m s/rad (3), m (3)], a new array.
        """
        p = np.array([getattr(self, n) for n in PARAM_NAMES], dtype=float)
        if self.payloads:
            m, r, I_O = from_inertial_parameters(self.inertial_parameters(), "vehicle")
            p[IDX["m"]] = m
            p[IDX["Ixx"]:IDX["Izz"] + 1] = np.diag(I_O)
            p[R_G] = r
        return p

    def inertial_parameters(self) -> npt.NDArray[np.float64]:
        """The ten inertial parameters about O of the whole body: the airframe (its m, r_G and
        diagonal inertia about O) plus every payload.

        Returns
        -------
        (10,) numpy.ndarray
            ``[m, m x_G, m y_G, m z_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (kg, kg m, kg m^2),
            the order of ``quadcog.model.inertial_parameters.PI_NAMES``.
        """
        return self._whole_pi.copy()

    @property
    def airframe(self) -> "Vehicle":
        """Vehicle: This vehicle without its payloads (the fields as they are)."""
        return replace(self, payloads=()) if self.payloads else self

    def with_payload(self, payload: Payload | dict[str, Any]) -> "Vehicle":
        """A copy that carries one more payload (parallel-axis theorem: the pi add up).

        Only the new payload is checked (the rest of the vehicle was when it was made), and
        the whole body's pi is this one's plus the payload's: loading N payloads one by one
        costs time linear in N.

        Parameters
        ----------
        payload : Payload or dict
            The payload, or a dict of its fields (mass, position[, size, name]).

        Returns
        -------
        Vehicle
            The loaded vehicle (validated: the whole body must be physically consistent).

        Raises
        ------
        InputError
            When ``payload`` is not a payload, one of that name is already carried, or it
            sits farther from O than ``PAYLOAD_REACH`` arm lengths.
        ParameterError
            When the rotors cannot lift the vehicle with it (``check_lift``).
        PhysicalConsistencyError
            When the airframe with the payload is not physically consistent.
        """
        shown = f"vehicle {self.name!r}"
        load = as_payload(payload, "payload")
        _check_carried(self, load, self._payload_names, float(self._whole_pi[0]),
                       lambda f: f"{shown}: {f}")
        total = self._whole_pi + load.inertial_parameters()
        if not is_physically_consistent(total):
            names = [p.name for p in self.payloads] + [load.name]
            check_physically_consistent(total, f"{shown}: airframe with payloads {names}: pi")
        loaded = copy.copy(self)        # the fields are checked: only the payloads change
        object.__setattr__(loaded, "payloads", self.payloads + (load,))
        loaded.__dict__["_whole_pi"] = total
        loaded.__dict__["_payload_names"] = self._payload_names | {load.name}
        return loaded

    def without_payload(self, name: str) -> "Vehicle":
        """A copy without the payload of that name.

        Parameters
        ----------
        name : str
            The payload's name.

        Returns
        -------
        Vehicle
            The vehicle without it.

        Raises
        ------
        InputError
            When no payload of that name is carried.
        """
        names = [p.name for p in self.payloads]
        if not isinstance(name, str) or name not in names:
            shown = repr(name) if isinstance(name, str) else plain(name)
            raise InputError(f"vehicle {self.name!r}: no payload named {shown} to remove; it "
                             f"carries {names or 'none'}")
        return replace(self, payloads=tuple(p for p in self.payloads if p.name != name))

    @property
    def r_G(self) -> npt.NDArray[np.float64]:
        """(3,) numpy.ndarray: The CoG offset [x_G, y_G, z_G] (m), a new array."""
        return np.array([self.x_G, self.y_G, self.z_G])

    @property
    def arm_length(self) -> float:
        """float: The largest distance of a rotor from O (m)."""
        return float(np.max(np.hypot(*np.asarray(self.rotor_positions).T)))

    def mixer(self) -> npt.NDArray[np.float64]:
        """The mixer B from rotor thrusts to the input, ``U = B @ f``.

        Returns
        -------
        (4, 4) numpy.ndarray
            Rows [1 ...], [y_i ...] (m), [-x_i ...] (m), [d_i k ...] (m): thrust, roll, pitch
            and yaw about O, so that U [N, N m, N m, N m] = B @ f (N).
        """
        pos = np.asarray(self.rotor_positions, dtype=float)
        return np.vstack([np.ones(N_ROTORS), pos[:, 1], -pos[:, 0],
                          self.moment_constant * np.asarray(self.rotor_directions, float)])

    def mixer_inverse(self) -> npt.NDArray[np.float64]:
        """The inverse of the mixer, from the input to rotor thrusts, ``f = B^-1 @ U``.

        Each entry is the nearest float to the exact inverse's (``numerics.exact_inverse``),
        so generated code and compiled kernels carry the same constants on every machine.

        Returns
        -------
        (4, 4) numpy.ndarray
            Columns per input [U1 (N), U2, U3, U4 (N m)], rows per rotor thrust (N).
        """
        return exact_inverse(self.mixer(), "the mixer")

    def rotor_thrusts(self, U: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The rotor thrusts that produce ``U``: the inverse of the mixer.

        Limits are not applied (see ``min_rotor_thrust``, ``max_rotor_thrust``).

        Parameters
        ----------
        U : (4,) or (4, N) array_like
            [U1 (N), U2, U3, U4 (N m, about O)], one column per sample.

        Returns
        -------
        (4,) or (4, N) numpy.ndarray
            Rotor thrusts f (N).

        Raises
        ------
        InputError
            When ``U`` does not have 4 rows of finite numbers, or the thrusts overflow.
        """
        U = array(U, "U", what="4 rows [U1 (N), U2, U3, U4 (N m)] of finite numbers")
        if U.shape[:1] != (4,):
            raise InputError(f"U must have 4 rows [U1, U2, U3, U4], got shape {U.shape}")
        with np.errstate(over="ignore", invalid="ignore"):
            f = np.asarray(self.mixer_inverse() @ U, dtype=np.float64)
        if not np.isfinite(f).all():       # never a silent NaN: U near the float range
            raise InputError(f"U: the rotor thrusts overflow (not finite) at max |U| = "
                             f"{float(np.abs(U).max()):.3g}; expected an input a vehicle's "
                             "rotors give (thrusts and moments within the float range over "
                             "the mixer's entries)")
        return f

    def rotor_speeds(self, f: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Rotor speeds of rotor thrusts: sqrt(f / thrust_constant).

        Parameters
        ----------
        f : array_like
            Rotor thrusts (N); negative values count as 0.

        Returns
        -------
        numpy.ndarray, shape of f
            Rotor speeds (rad/s), >= 0.

        Raises
        ------
        InputError
            ``f`` is not real numbers (a string, None, complex, ragged) or not finite.
        """
        thrusts = array(f, "f", what="rotor thrusts (N): finite real numbers")
        # sqrt of each factor: f / thrust_constant overflows to inf for a finite f near the
        # float range (1e308 N over 1e-8 N s^2), its root does not
        return np.sqrt(np.maximum(thrusts, 0.0)) / np.sqrt(self.thrust_constant)

    def hover_input(self) -> npt.NDArray[np.float64]:
        """The input that holds a level hover with this vehicle's CoG
        (``quadcog.model.conventions.hover_trim``).

        Returns
        -------
        (4,) numpy.ndarray
            U = [m g, m g y_G, -m g x_G, 0] (N, N m, N m, N m).
        """
        return hover_trim(self.parameters())

    # -- variants ------------------------------------------------------------------------
    def replace(self, **changes: Any) -> "Vehicle":
        """A copy with fields replaced by name (validated).

        Parameters
        ----------
        **changes
            Field names (``FIELD_NAMES``) and their new values, in the units of the fields.

        Returns
        -------
        Vehicle
            The new vehicle.

        Raises
        ------
        InputError
            For an unknown field name, or a value of the wrong type.
        ParameterError
            For a value out of range.
        """
        unknown = set(changes) - set(FIELD_NAMES)
        if unknown:
            raise InputError(f"unknown vehicle field(s) {sorted(unknown)}; expected some of "
                             f"{FIELD_NAMES}")
        return replace(self, **changes)

    def with_cog(self, r_G: npt.ArrayLike) -> "Vehicle":
        """A copy with another CoG offset.

        Parameters
        ----------
        r_G : (3,) array_like
            The CoG offset [x_G, y_G, z_G] from O in the body frame (m).

        Returns
        -------
        Vehicle
            The new vehicle (validated).

        Raises
        ------
        InputError
            When ``r_G`` is not 3 numbers.
        """
        r = vector(r_G, "r_G", 3)
        return replace(self, x_G=float(r[0]), y_G=float(r[1]), z_G=float(r[2]))

    def with_parameters(self, p: npt.ArrayLike) -> "Vehicle":
        """A copy whose 14 parameters are ``p``; rotors unchanged.

        Parameters
        ----------
        p : (14,) array_like
            The parameter vector in ``parameters()`` order and units.

        Returns
        -------
        Vehicle
            The new vehicle (validated).

        Raises
        ------
        ParameterError
            When ``p`` is not an admissible parameter vector.
        """
        if self.payloads:
            raise InputError(f"vehicle {self.name!r} carries payloads, so its parameters are the "
                             "whole body's; use vehicle.airframe.with_parameters(p) for the "
                             "airframe's")
        q = check_parameters(p, "p")
        return self.replace(**{n: float(q[IDX[n]]) for n in PARAM_NAMES})

    def as_dict(self) -> dict[str, Any]:
        """Every field as plain Python values (for JSON and scenario files).

        Returns
        -------
        dict of str to Any
            {field: value}; ``rotor_positions`` and ``rotor_directions`` as lists,
            ``rotor_model`` as its name (or None), ``payloads`` as a list of dicts.
        """
        d = asdict(self)
        d["rotor_positions"] = [list(r) for r in self.rotor_positions]
        d["rotor_directions"] = list(self.rotor_directions)
        d["rotor_model"] = None if self.rotor_model is None else self.rotor_model.name
        d["payloads"] = [p.as_dict() for p in self.payloads]
        return d


FIELD_NAMES = tuple(f.name for f in fields(Vehicle))


def _check_payloads(vehicle, where):
    """Turn the payloads into a tuple of Payload (names unique, each carried on the vehicle
    and lifted by its rotors) and check the whole body."""
    loads = vehicle.payloads
    if isinstance(loads, (str, bytes, dict, Payload, np.ndarray)) or not hasattr(loads,
                                                                                  "__iter__"):
        raise InputError(where(f"payloads must be a sequence of Payload, got {plain(loads)}"))
    loads = tuple(as_payload(p, where(f"payloads[{k}]")) for k, p in enumerate(loads))
    object.__setattr__(vehicle, "payloads", ())     # the airframe's pi, then each payload's
    pi = vehicle._whole_pi
    names: set[str] = set()
    for p in loads:
        _check_carried(vehicle, p, names, float(pi[0]), where)
        names.add(p.name)
        pi = pi + p.inertial_parameters()
    object.__setattr__(vehicle, "payloads", loads)
    vehicle.__dict__["_whole_pi"] = pi
    vehicle.__dict__.pop("_payload_names", None)
    if loads:
        check_physically_consistent(pi, where(f"airframe with payloads "
                                              f"{[p.name for p in loads]}: pi"))


def _check_carried(vehicle, payload, names, on_board, where):
    """Refuse ``payload`` on ``vehicle`` if its name is taken (``names``), it sits beyond
    ``PAYLOAD_REACH`` arm lengths, or the rotors do not lift it with the ``on_board`` kg
    already carried (``check_lift``)."""
    if payload.name in names:
        raise InputError(where(f"payloads: two payloads are named {payload.name!r}; expected "
                               "unique names"))
    check_reach(payload.position, payload.size, vehicle.arm_length,
                where(f"payload {payload.name!r}"))
    check_lift(payload.mass, on_board, vehicle.g, N_ROTORS * vehicle.max_rotor_thrust,
               where(f"payload {payload.name!r}"))


def _check_rigid_body(vehicle, where):
    """PhysicalConsistencyError unless the inertia the vehicle states is that of some rigid
    body: its principal inertias (Ixx, Iyy, Izz) positive and each smaller than the sum of the
    other two (the triangle inequality; no mass distribution has Izz > Ixx + Iyy).

    The CoG offset is not part of this check. The paper's model holds I_O as the CoG moves, so
    an offset may leave no rigid body with that I_O and r_G (docs/model.md sec. 7.2 says how
    far: 9.39 cm along x, y and 3.83 cm along z for the Hummingbird); the paper's scenarios fly
    such offsets, and the model's own admissibility (``quadcog.model.parameters``) bounds
    them. A payload model in the ten inertial parameters checks the full pseudo-inertia
    (``quadcog.model.inertial_parameters.check_physically_consistent``)."""
    from quadcog.errors import PhysicalConsistencyError
    I = sorted((vehicle.Ixx, vehicle.Iyy, vehicle.Izz))
    if not I[2] < I[0] + I[1]:
        raise PhysicalConsistencyError(
            f"{where('inertia (Ixx, Iyy, Izz)')} = ({vehicle.Ixx:g}, {vehicle.Iyy:g}, "
            f"{vehicle.Izz:g}) kg m^2: the principal inertias break the triangle inequality, "
            f"{I[2]:g} >= {I[0]:g} + {I[1]:g} = {I[0] + I[1]:g} (no mass distribution has a "
            f"largest principal inertia as large as the sum of the other two)")

# AscTec Hummingbird as modelled in the ETH RotorS simulator (rotors_description/urdf/
# hummingbird.xacro: mass, inertia, arm, motor_constant, moment_constant, max_rot_velocity,
# time_constant_up; Furrer et al., "RotorS - A Modular Gazebo MAV Simulator Framework", 2016).
# Rotor 1 front (+x) and 3 back turn clockwise there. The drag coefficients are this
# project's own choice (neither the paper nor RotorS gives linear drag): small, so that the
# zero dynamics decay slowly (c_x / m = 0.15 1/s).
_HB_THRUST_CONSTANT = 8.54858e-6      # N / (rad/s)^2
_HB_MAX_ROTOR_SPEED = 838.0           # rad/s
HUMMINGBIRD = Vehicle(
    name="AscTec Hummingbird", m=0.68, g=9.81, Ixx=0.007, Iyy=0.007, Izz=0.012,
    c_x=0.1, c_y=0.1, c_z=0.1, c_phi=0.001, c_theta=0.001, c_psi=0.001,
    rotor_positions=plus_layout(0.17), rotor_directions=(1, -1, 1, -1),
    thrust_constant=_HB_THRUST_CONSTANT, moment_constant=0.016,
    max_rotor_thrust=_HB_THRUST_CONSTANT * _HB_MAX_ROTOR_SPEED ** 2,    # 6.00 N
    motor_time_constant=0.0125)

# Bitcraze Crazyflie 2.0, "X" layout. Mass and the diagonal of the inertia from J. Foerster,
# "System Identification of the Crazyflie 2.0 Nano Quadrocopter", BSc thesis, ETH Zurich
# IDSC, 2015 (its products of inertia, at most 1.8e-6 kg m^2, are left out: the model's I_O
# is diagonal). Arm 0.046 m, thrust constant 1.28192e-8 N/(rad/s)^2, moment constant
# 5.964552e-3 m, rotor speed at most 2618 rad/s, motor time constant 0.0125 s (spin-up) and
# the rotor directions as in the RotorS crazyflie2 model (rotors_description/urdf/
# crazyflie2.xacro; Silano et al., "CrazyS", 2018, from Foerster's identification). The drag
# coefficients are this project's choice: the Hummingbird's drag per mass and per inertia.
_CF_THRUST_CONSTANT = 1.28192e-8
_CF_MAX_ROTOR_SPEED = 2618.0
CRAZYFLIE = Vehicle(
    name="Crazyflie 2.0", m=0.027, g=9.81, Ixx=16.571710e-6, Iyy=16.655602e-6,
    Izz=29.261652e-6, c_x=0.004, c_y=0.004, c_z=0.004, c_phi=2.4e-6, c_theta=2.4e-6,
    c_psi=2.4e-6, rotor_positions=x_layout(0.046), rotor_directions=(-1, 1, -1, 1),
    thrust_constant=_CF_THRUST_CONSTANT, moment_constant=5.964552e-3,
    max_rotor_thrust=_CF_THRUST_CONSTANT * _CF_MAX_ROTOR_SPEED ** 2,    # 0.0879 N
    motor_time_constant=0.0125, rotor_model=CRAZYFLIE_BITCRAZE_VOLTAGE)

# Holybro X500 as modelled in PX4's Gazebo (gz) simulation: PX4/PX4-gazebo-models,
# models/x500_base/model.sdf (mass 2.0 kg, the diagonal inertia, rotor_0..3 at
# (+-0.174, +-0.174) m) and models/x500/model.sdf (the MulticopterMotorModel plugins:
# motorConstant 8.54858e-06 N/(rad/s)^2, momentConstant 0.016 m, maxRotVelocity 1000 rad/s,
# timeConstantUp 0.0125 s; rotors 0 (front right) and 1 (back left) turn ccw, 2 (front
# left) and 3 (back right) cw); the same files as PX4-Autopilot's
# Tools/simulation/gz/models/x500*. Its frame is ours (x forward, y left, z up), so the rotor
# order and positions are the model's; a ccw rotor (seen from above) has d_i = -1. The drag
# coefficients are this project's choice, as for the Crazyflie: the Hummingbird's drag per
# mass and per inertia.
_X500_THRUST_CONSTANT = 8.54858e-06
_X500_MAX_ROTOR_SPEED = 1000.0
_X500_MASS, _X500_IXX = 2.0, 0.02166666666666667
_DRAG_PER_MASS = HUMMINGBIRD.c_x / HUMMINGBIRD.m             # 1/s
_RATE_DRAG_PER_INERTIA = HUMMINGBIRD.c_phi / HUMMINGBIRD.Ixx  # 1/s
X500 = Vehicle(
    name="Holybro X500 (PX4 gz)", m=_X500_MASS, g=9.81, Ixx=_X500_IXX, Iyy=_X500_IXX,
    Izz=0.04000000000000001, c_x=_DRAG_PER_MASS * _X500_MASS, c_y=_DRAG_PER_MASS * _X500_MASS,
    c_z=_DRAG_PER_MASS * _X500_MASS, c_phi=_RATE_DRAG_PER_INERTIA * _X500_IXX,
    c_theta=_RATE_DRAG_PER_INERTIA * _X500_IXX, c_psi=_RATE_DRAG_PER_INERTIA * _X500_IXX,
    rotor_positions=((0.174, -0.174), (-0.174, 0.174), (0.174, 0.174), (-0.174, -0.174)),
    rotor_directions=(-1, -1, 1, 1), thrust_constant=_X500_THRUST_CONSTANT,
    moment_constant=0.016,
    max_rotor_thrust=_X500_THRUST_CONSTANT * _X500_MAX_ROTOR_SPEED ** 2,   # 8.55 N
    motor_time_constant=0.0125)


def preset_drag(m: float, Ixx: float) -> dict[str, float]:
    """The linear drag of the presets that no source gives (the X500, the Crazyflie, a vehicle
    from a file): the Hummingbird's drag per mass and per inertia.

    Parameters
    ----------
    m : float
        Mass (kg).
    Ixx : float
        Roll inertia about O (kg m^2).

    Returns
    -------
    dict of str to float
        ``c_x = c_y = c_z = (c_x / m)_Hummingbird m`` (N s/m) and ``c_phi = c_theta = c_psi =
        (c_phi / Ixx)_Hummingbird Ixx`` (N m s/rad), by field name.

    Raises
    ------
    InputError
        ``m`` or ``Ixx`` not a number in [SMALLEST, LARGEST] (``quadcog.model.parameters``).
    """
    m = real(m, "preset_drag: m", lo=SMALLEST, hi=LARGEST, unit="kg")
    Ixx = real(Ixx, "preset_drag: Ixx", lo=SMALLEST, hi=LARGEST, unit="kg m^2")
    linear, rate = _DRAG_PER_MASS * m, _RATE_DRAG_PER_INERTIA * Ixx
    return {"c_x": linear, "c_y": linear, "c_z": linear, "c_phi": rate, "c_theta": rate,
            "c_psi": rate}


# Bitcraze Crazyflie 2.1 with its default 2.1+ propellers, from the firmware's own constants
# (crazyflie-firmware 2a18fc29, src/platform/interface/platform_defaults_cf2.h with the
# Kconfig defaults ENABLE_THRUST_BAT_COMPENSATED and CRAZYFLIE_21_PLUS): CF_MASS 0.029 kg,
# ARM_LENGTH 0.046 m ("X" layout, M1 front-right .. M4 front-left), THRUST2TORQUE
# 0.0069928948992470565 m, THRUST_MAX 0.12 N per motor, the thrust map VMOTOR2THRUST0..3
# (CRAZYFLIE_21_PLUS_CUBIC). The inertia is the one the firmware's Lee controller flies with
# (controller_lee.c, .J), which is Foerster's published identification (as for the 2.0). The
# firmware has no rotor-speed constant: the thrust constant is Foerster's (it only turns
# thrust limits into rotor speeds), the motor time constant the 2.0's, the rotor directions
# those of the firmware's force-torque mixer (power_distribution_quadrotor.c: M2, M4 give
# +torqueZ, i.e. turn clockwise seen from above). Drag as for the other presets: the
# Hummingbird's per mass and per inertia. tests/test_crazyflie_preset.py checks the firmware
# numbers against the header of a firmware tree. (The CrazyPAD drones weigh 34-38 g by
# quadcog's identification: `vehicle.replace(m=...)`.)
_CF21_MASS, _CF21_IXX = 0.029, 16.571710e-6
CRAZYFLIE_21 = Vehicle(
    name="Crazyflie 2.1 (2.1+ propellers)", m=_CF21_MASS, g=9.81, Ixx=_CF21_IXX,
    Iyy=16.655602e-6, Izz=29.261652e-6, c_x=_DRAG_PER_MASS * _CF21_MASS,
    c_y=_DRAG_PER_MASS * _CF21_MASS, c_z=_DRAG_PER_MASS * _CF21_MASS,
    c_phi=_RATE_DRAG_PER_INERTIA * _CF21_IXX, c_theta=_RATE_DRAG_PER_INERTIA * _CF21_IXX,
    c_psi=_RATE_DRAG_PER_INERTIA * _CF21_IXX, rotor_positions=x_layout(0.046),
    rotor_directions=(-1, 1, -1, 1), thrust_constant=_CF_THRUST_CONSTANT,
    moment_constant=0.0069928948992470565, max_rotor_thrust=0.12,
    motor_time_constant=0.0125, rotor_model=CRAZYFLIE_21_PLUS_CUBIC)

PRESETS = {"hummingbird": HUMMINGBIRD, "crazyflie": CRAZYFLIE, "x500": X500,
           "crazyflie21": CRAZYFLIE_21}


def default_parameters(**overrides: float) -> npt.NDArray[np.float64]:
    """The default vehicle's (``HUMMINGBIRD``) parameter vector, entries replaced by name.

    Parameters
    ----------
    **overrides
        Parameter names (``quadcog.model.conventions.PARAM_NAMES``) and values in SI units,
        e.g. ``default_parameters(x_G=0.03, m=0.8)``.

    Returns
    -------
    (14,) numpy.ndarray
        The parameter vector p, ordered as ``Vehicle.parameters()``.

    Raises
    ------
    InputError
        For an unknown name.
    ParameterError
        For a value that is not a real number or out of range.
    """
    unknown = set(overrides) - set(PARAM_NAMES)
    if unknown:
        raise InputError(f"unknown parameter {sorted(unknown)[0]!r}; expected one of "
                         f"{PARAM_NAMES}")
    return HUMMINGBIRD.replace(**{k: real(v, k, error=ParameterError)
                                  for k, v in overrides.items()}).parameters()

"""Vehicles from the description files users have: URDF (gym-pybullet-drones) and SDF (Gazebo,
PX4's gz models).

The files are read with the standard library's ``xml.etree.ElementTree``: both formats are
plain XML whose few elements this module needs (links' ``<inertial>``, joints, a plugin's or a
``<properties>`` tag's numbers), and no URDF/SDF library on PyPI is kept for both without a
simulator attached (``urdfpy`` has not been released since 2020 and pins an old networkx;
``sdformat`` is Gazebo's C++ library with bindings only from Gazebo's own packages).

What is read
------------
- The rigid body: every link's ``<inertial>`` (mass, CoG pose, inertia about the CoG in the
  inertial frame's axes), turned to body axes and summed about the common CoG
  (parallel-axis theorem): the mass, the CoG and the inertia about the CoG of the whole
  model. Each link and the whole must be physically consistent: a link whose numbers no
  rigid body has gets ``PhysicalConsistencyError`` (``quadcog.model.inertial_parameters``).
- The origin O: on the rotors' axis (their centroid in x, y), at the height of the CoG. The
  moments of thrusts along body z do not depend on the height of the plane they act in, so O
  may sit at any height on that axis; at the CoG's, ``z_G = 0`` and a vehicle whose CoG lies on
  the rotors' axis gets the file's inertia about the CoG as its ``Ixx, Iyy, Izz``.
- The inertia in quadcog's convention (``Vehicle``, docs/model.md sec. 1.2): the diagonal of
  the inertia about O at the stated CoG, ``I_O = I_G + m (|r_G|^2 I - r_G r_G^T)`` with the
  file's whole-body ``I_G``; the products of inertia are left out, as the model has none.
- The rotors, in the file's order: positions (x, y) from O, spin directions, thrust and
  moment constants, the largest thrust and the motor time constant, from the SDF's
  ``MulticopterMotorModel`` plugins or the URDF's ``<properties>`` tag.
- Linear drag: neither format has the model's linear drag, so ``Vehicle.from_urdf`` and
  ``Vehicle.from_sdf`` apply the presets' rule (``quadcog.vehicles.vehicle.preset_drag``) unless ``drag`` is
  given.

The functions here return the ``Vehicle`` fields (this module sits below ``vehicle.py``);
``Vehicle.from_urdf``, ``Vehicle.from_sdf`` and ``Vehicle.from_file`` make the vehicle.

A needed value that is missing, not a number or out of its range raises ``VehicleFileError``
naming the value (its element path) and the file; so does what the reader would otherwise
read as something else: an element it reads given twice, an attribute it does not read
(``unit``, ``relative_to``, ``auto``), a ``<!DOCTYPE>``, a xacro element, a nested SDF
``<model>`` (lengths, masses and inertias beyond the
model's scale ``LARGEST`` too: their sums overflowed to a NaN that named no value); so does a
URDF whose links are not one tree of uniquely named links, an SDF whose ``<include>`` s loop
or copy more than ``MAX_INCLUDED_ELEMENTS`` elements, and links whose mass lies farther than
``PAYLOAD_REACH`` arm lengths from their CoG (root mean square: an inertia in the wrong
unit). A read costs time linear in the files' size: each file is parsed once, each URDF joint
read once.
"""
from dataclasses import dataclass, field
import math
import os
from pathlib import Path
import re
from typing import Any
import xml.etree.ElementTree as ET

import numpy as np
import numpy.typing as npt

from quadcog.errors import InputError, VehicleFileError
from quadcog.files import input_file
from quadcog.model.inertial_parameters import check_physically_consistent, inertial_parameters
from quadcog.model.parameters import LARGEST, SMALLEST
from quadcog.validate import fail, flag, plain, real

__all__ = ["urdf_fields", "sdf_fields", "file_fields", "GYM_PYBULLET_DIRECTIONS",
           "RPM_PER_RAD_S", "GAZEBO_PATH_VARIABLES", "MAX_INCLUDE_DEPTH", "MAX_INCLUDED_ELEMENTS",
           "THRUST_TO_WEIGHT", "MAX_MOMENT_CONSTANT", "MAX_MOTOR_TIME_CONSTANT", "PAYLOAD_REACH",
           "check_options"]

# gym-pybullet-drones, BaseAviary._physics: z_torque = -t0 + t1 - t2 + t3 with t_i = KM rpm_i^2,
# and the torques negated for DroneModel.RACE (whose URDF is racer.urdf); the file has no
# directions, that code has them
GYM_PYBULLET_DIRECTIONS = {"": (-1, 1, -1, 1), "racer": (1, -1, 1, -1)}
# gym-pybullet-drones' kf, km are per squared rotor speed in revolutions per minute
RPM_PER_RAD_S = 60.0 / (2.0 * math.pi)
# where Gazebo looks for model:// URIs (gz sim; Gazebo classic's name second)
GAZEBO_PATH_VARIABLES = ("GZ_SIM_RESOURCE_PATH", "GAZEBO_MODEL_PATH")
# SDF <include>s: how deep they may nest, and how many links, joints and plugins they may
# copy into the model in all (each copy counted at every level it is copied through). PX4's
# X500 copies 9. A file included k times at each of d levels copies k^d times: the limit
# keeps a read linear in the files' size (each file is also parsed only once).
MAX_INCLUDE_DEPTH = 8
MAX_INCLUDED_ELEMENTS = 10_000
# The rotors' largest total thrust over the weight: above 1, or the vehicle cannot hover;
# racing quadrotors reach about 20, a file beyond 100 states impossible rotors.
THRUST_TO_WEIGHT = (1.0, 100.0)
# Drag moment over thrust of a rotor (m): about the propeller's radius times its drag over
# lift ratio, 0.006 m (Crazyflie) to 0.025 m (gym-pybullet-drones); 1 m is no propeller.
MAX_MOMENT_CONSTANT = 1.0
# A motor's spin-up time constant (s): real ones take 0.01 to 0.1 s; a motor much slower
# than 10 s cannot hold a quadrotor's attitude at all.
MAX_MOTOR_TIME_CONSTANT = 10.0
# What a vehicle carries is on it: a payload's centre at most this many arm lengths from O (a
# sling load hangs a few arm lengths below; 100 km away is a typing error, refused;
# quadcog.vehicles.payload.check_reach), and a file's links' mass within as many arm lengths
# of their CoG (root mean square: an inertia in g mm^2 read as kg m^2 puts a Crazyflie's 27 g
# 30 m out).
PAYLOAD_REACH = 10.0


# -- XML reading -----------------------------------------------------------------------------

def _file_path(path: object, where: str) -> Path:
    """``path`` as a Path if it is a str or os.PathLike naming a file that is not a folder,
    a FIFO or a device (quadcog.files.input_file), else a VehicleFileError."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)) or \
            not str(os.fspath(path)).strip():
        fail(where, "a vehicle file's path (a str or os.PathLike, .urdf or .sdf)", path,
             VehicleFileError)
    return input_file(path, "a vehicle file (.urdf or .sdf)", VehicleFileError, where)


def check_options(reader: Any, options: dict[str, Any], where: str) -> None:
    """Refuse keyword options that a vehicle-file reader does not take, before the file is
    read (Python's own TypeError named the function's internals).

    Parameters
    ----------
    reader : callable
        ``urdf_fields`` or ``sdf_fields``: its keyword-only parameters are the options.
    options : dict of str to Any
        The options given (``Vehicle.from_urdf(path, **options)``).
    where : str
        The start of the message (the method called).

    Raises
    ------
    quadcog.InputError
        Naming the unknown options and the ones the reader takes.
    """
    import inspect
    known = [n for n, q in inspect.signature(reader).parameters.items()
             if q.kind is inspect.Parameter.KEYWORD_ONLY]
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise InputError(f"{where}: expected options among {', '.join(known)}, got unknown "
                         f"{', '.join(map(repr, unknown))}")


class _NoDoctype(ET.TreeBuilder):
    """The tree of a file without a DTD: neither format has one, and PyBullet's and Gazebo's
    readers expand no entities, so a ``<!DOCTYPE>`` (entities, default attributes, an
    external DTD) would make the file mean one thing to quadcog and another to them."""

    def doctype(self, name: str, pubid: str | None, system: str | None) -> None:
        raise _DoctypeError(name)


class _DoctypeError(Exception):
    pass


def _parse(path: Path) -> ET.Element:
    input_file(path, "a vehicle file (.urdf or .sdf)", VehicleFileError)   # included ones too
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        raise VehicleFileError(f"{path}: no such file") from None
    except OSError as e:
        raise VehicleFileError(f"{path}: not readable ({e})") from None
    parser = ET.XMLParser(target=_NoDoctype())
    try:
        # fed at once: fed in chunks (ET.parse), expat re-scans a token that spans them, and a
        # 50 MB attribute took 30 s
        parser.feed(data)
        return parser.close()
    except _DoctypeError as e:
        raise VehicleFileError(f"{path}: <!DOCTYPE {plain(str(e))}>: a document type "
                               "declaration; expected a URDF or SDF file without one (neither "
                               "format has entities or a DTD)") from None
    except (ET.ParseError, LookupError) as e:       # LookupError: an unknown encoding
        raise VehicleFileError(f"{path}: not readable as XML ({e})") from None


def _one(parent: ET.Element, tag: str, what: str, path: Path) -> ET.Element | None:
    """The child ``tag`` of ``parent`` (None if it has none), refused if it has several: the
    formats allow one, and reading the first dropped the others' numbers silently."""
    found = parent.findall(tag)
    if len(found) > 1:
        raise VehicleFileError(f"{path}: {what} has {len(found)} <{tag}> elements; expected "
                               "at most one")
    return found[0] if found else None


def _text(parent: ET.Element, tag: str, what: str, path: Path) -> str | None:
    node = _one(parent, tag, what, path)
    return None if node is None else (node.text or "")


def _attributes(node: ET.Element, known: tuple[str, ...], what: str, path: Path) -> None:
    """Refuse attributes of ``node`` that quadcog does not read: each changes what the numbers
    mean (``<mass value="27" unit="g">``, ``<pose relative_to=...>``, ``<inertial
    auto="true">``), and none is in the formats as quadcog reads them."""
    unknown = sorted(set(node.attrib) - set(known))
    if unknown:
        raise VehicleFileError(
            f"{path}: {what} has attribute(s) {', '.join(f'{a}={node.get(a)!r}' for a in unknown)}"
            f"; expected {'only ' + ', '.join(known) if known else 'none'} (quadcog reads no "
            "other: SI units, poses in their parent's frame)")


# xsd:double as URDF and SDF write numbers; Python's float() also takes "1_000", "inf" and
# non-ASCII digits, which no XML reader of these formats does
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")


def _numbers(text: str | None, what: str, path: Path, n: int,
             scale: bool = False) -> npt.NDArray[np.float64]:
    """``n`` finite numbers; with ``scale`` each within +-LARGEST (the model's scale in SI
    units: a length, a mass or an inertia beyond it overflows the sums of the parallel-axis
    theorem, and a NaN named no value of the file)."""
    if text is None:
        raise VehicleFileError(f"{path}: {what} is missing; expected {n} number(s)")
    words = text.split()
    values = (np.array([float(t) for t in words]) if len(words) == n and
              all(_NUMBER.fullmatch(t) for t in words) else np.array([]))
    if values.shape != (n,) or not np.isfinite(values).all():
        raise VehicleFileError(f"{path}: {what} = {plain(text.strip())}; expected {n} finite "
                               "number(s)")
    if scale and not np.abs(values).max() <= LARGEST:
        raise VehicleFileError(f"{path}: {what} = {plain(text.strip())}; expected {n} "
                               f"number(s) within +-{LARGEST:g} (SI units, the model's scale)")
    return values


def _number(text: str | None, what: str, path: Path, scale: bool = False) -> float:
    return float(_numbers(text, what, path, 1, scale)[0])


def _within_scale(pose: "_Pose", what: str, path: Path) -> npt.NDArray[np.float64]:
    """The translation of a composed pose (a link's frame down a chain of joints), refused
    beyond LARGEST m from the model's origin (each offset is within it, their sum need not)."""
    if not np.abs(pose.t).max() <= LARGEST:
        raise VehicleFileError(f"{path}: {what} is at {plain(pose.t.tolist())} m from the "
                               f"model's origin; expected within +-{LARGEST:g} m (the model's "
                               "scale)")
    return pose.t


def _bounded(value: float, what: str, path: Path, lo: float, hi: float, unit: str,
             lo_open: bool = True) -> float:
    """``value`` if it lies in (lo, hi] (``lo_open``) or [lo, hi], else a VehicleFileError
    naming the file, the value's element path and the range."""
    if not ((lo < value if lo_open else lo <= value) and value <= hi):
        expected = (f"a number {'>' if lo_open else '>='} {lo:g}" if hi == math.inf else
                    f"a number in {'(' if lo_open else '['}{lo:g}, {hi:g}]")
        raise VehicleFileError(f"{path}: {what} = {value:g}; expected {expected} ({unit})")
    return value


def _check_lift(fields: dict[str, Any], source: str, path: Path) -> None:
    """Refuse rotors whose largest total thrust does not lift the vehicle, or is beyond any
    rotor's (``THRUST_TO_WEIGHT``); ``source`` says which of the file's values give it."""
    lo, hi = THRUST_TO_WEIGHT
    ratio = 4.0 * fields["max_rotor_thrust"] / (fields["m"] * fields["g"])
    if not lo < ratio <= hi:        # NaN and inf fail too
        raise VehicleFileError(
            f"{path}: {source} gives a largest rotor thrust of {fields['max_rotor_thrust']:.4g} N, "
            f"a thrust-to-weight ratio of {ratio:.4g} for the {fields['m']:.4g} kg vehicle; "
            f"expected a ratio in ({lo:g}, {hi:g}] (above 1 the rotors lift the vehicle)")


def _rotation(rpy: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """Rz(yaw) Ry(pitch) Rx(roll): the fixed-axis roll, pitch, yaw of URDF and SDF poses."""
    r, p, y = np.asarray(rpy, dtype=float)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


@dataclass(frozen=True)
class _Pose:
    R: npt.NDArray[np.float64]
    t: npt.NDArray[np.float64]

    def then(self, inner: "_Pose") -> "_Pose":
        return _Pose(self.R @ inner.R, self.R @ inner.t + self.t)


_IDENTITY = _Pose(np.eye(3), np.zeros(3))


def _sdf_pose(element: ET.Element | None, what: str, path: Path) -> _Pose:
    node = None if element is None else _one(element, "pose", what, path)
    if node is None:
        return _IDENTITY
    _attributes(node, ("degrees",), f"{what}/pose", path)
    # sdformat's bool: true or 1, false or 0 ("yes" was read as false: degrees as radians)
    degrees = node.get("degrees", "false").strip().lower()
    if degrees not in ("true", "1", "false", "0"):
        raise VehicleFileError(f"{path}: {what}/pose@degrees = {plain(degrees)}; expected "
                               "true, 1, false or 0")
    if not (node.text or "").strip():
        return _IDENTITY
    v = _numbers(node.text, f"{what}/pose", path, 6)
    if not np.abs(v[:3]).max() <= LARGEST:
        raise VehicleFileError(f"{path}: {what}/pose = {plain((node.text or '').strip())}; expected "
                               f"x y z within +-{LARGEST:g} m (the model's scale) and roll "
                               "pitch yaw")
    rpy = np.radians(v[3:]) if degrees in ("true", "1") else v[3:]
    return _Pose(_rotation(rpy), v[:3])


def _urdf_origin(element: ET.Element | None, what: str, path: Path) -> _Pose:
    node = None if element is None else _one(element, "origin", what, path)
    if node is None:
        return _IDENTITY
    _attributes(node, ("xyz", "rpy"), f"{what}/origin", path)
    xyz = _numbers(node.get("xyz", "0 0 0"), f"{what}/origin@xyz", path, 3, scale=True)
    rpy = _numbers(node.get("rpy", "0 0 0"), f"{what}/origin@rpy", path, 3)
    return _Pose(_rotation(rpy), xyz)


_INERTIA_KEYS = ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")   # products default to 0


def _inertia_matrix(values: dict[str, float]) -> npt.NDArray[np.float64]:
    g = values.get
    return np.array([[g("ixx", 0.0), g("ixy", 0.0), g("ixz", 0.0)],
                     [g("ixy", 0.0), g("iyy", 0.0), g("iyz", 0.0)],
                     [g("ixz", 0.0), g("iyz", 0.0), g("izz", 0.0)]])


@dataclass(frozen=True)
class _Body:
    """One link's inertial in model axes: mass (kg), CoG (m), inertia about its CoG (kg m^2)."""
    m: float
    r: npt.NDArray[np.float64]
    I_G: npt.NDArray[np.float64]


def _body(m: float, where: _Pose, I_G: npt.NDArray[np.float64], what: str, path: Path) -> _Body:
    """A link's inertial, its inertia about its CoG turned to model axes; refused when no
    rigid body has it (the pseudo-inertia, quadcog.model.inertial_parameters)."""
    I_model = where.R @ I_G @ where.R.T
    check_physically_consistent(inertial_parameters(m, np.zeros(3), I_model, what),
                                f"{path}: {what}")
    return _Body(m, _within_scale(where, f"{what}: its CoG", path), I_model)


def _whole(bodies: list[_Body], path: Path) -> tuple[float, npt.NDArray[np.float64],
                                                      npt.NDArray[np.float64]]:
    """Mass, CoG and inertia about the CoG of the links together (the parallel-axis theorem
    about the common CoG, so one link comes back exactly as the file states it)."""
    m = sum(b.m for b in bodies)
    cog = sum((b.m * b.r for b in bodies), np.zeros(3)) / m
    I_G = np.zeros((3, 3))
    for b in bodies:
        d = b.r - cog
        I_G = I_G + b.I_G + b.m * (float(d @ d) * np.eye(3) - np.outer(d, d))
    check_physically_consistent(inertial_parameters(m, np.zeros(3), I_G, "the links"),
                                f"{path}: the links together")
    return m, cog, I_G


# -- the vehicle from its parts --------------------------------------------------------------

def _assemble(path: Path, name: str, bodies: list[_Body],
              rotors: npt.NDArray[np.float64], directions: tuple[int, ...],
              thrust_constant: float, moment_constant: float, max_rotor_thrust: float,
              motor_time_constant: float, g: float) -> dict[str, Any]:
    """The Vehicle of the summed links (pi about the model frame's origin) and the rotors'
    positions in the model frame: O on the rotors' axis at the CoG's height."""
    if not bodies:
        raise VehicleFileError(f"{path}: no link has a mass (<inertial>); expected the "
                               "vehicle's body")
    m, cog, I_G = _whole(bodies, path)
    centre = rotors[:, :2].mean(axis=0)
    arm = float(np.max(np.hypot(*(rotors[:, :2] - centre).T)))
    spread = math.sqrt(float(np.trace(I_G)) / (2.0 * m))    # rms distance of the mass from the CoG
    if arm > 0 and not spread <= PAYLOAD_REACH * arm:     # arm 0: Vehicle names the mixer
        raise VehicleFileError(
            f"{path}: the links' inertia about their CoG (trace {float(np.trace(I_G)):.4g} kg "
            f"m^2 for {m:.4g} kg) puts their mass {spread:.3g} m from the CoG (root mean square), "
            f"beyond {PAYLOAD_REACH:g} arm lengths ({PAYLOAD_REACH * arm:.3g} m) of a vehicle "
            "whose rotors are "
            f"{arm:.3g} m from its axis; expected inertias in kg m^2 and masses in kg (not g "
            "mm^2, kg cm^2 or g)")
    r_G = np.array([cog[0] - centre[0], cog[1] - centre[1], 0.0])
    I_O = I_G + m * (float(r_G @ r_G) * np.eye(3) - np.outer(r_G, r_G))
    return dict(
        name=name, m=float(m), g=g, Ixx=float(I_O[0, 0]), Iyy=float(I_O[1, 1]),
        Izz=float(I_O[2, 2]), rotor_positions=tuple((float(x), float(y)) for x, y in rotors[:, :2] - centre),
        rotor_directions=directions, thrust_constant=thrust_constant,
        moment_constant=moment_constant, max_rotor_thrust=max_rotor_thrust,
        motor_time_constant=motor_time_constant, x_G=float(r_G[0]), y_G=float(r_G[1]),
        z_G=0.0)


def _check_axis(axis: npt.NDArray[np.float64], what: str, path: Path) -> None:
    unit = axis / max(float(np.linalg.norm(axis)), 1e-300)
    if not abs(abs(unit[2]) - 1.0) < 1e-6:
        raise VehicleFileError(f"{path}: {what} = {axis.tolist()} is not along body z; "
                               "expected rotors that push along body z (quadcog's model)")


# -- URDF ------------------------------------------------------------------------------------

def urdf_fields(path: str | os.PathLike[str], *,
                rotor_directions: tuple[int, ...] | None = None, g: float = 9.81,
                name: str | None = None) -> dict[str, Any]:
    """The fields of a vehicle (all but the drag) from a URDF file of gym-pybullet-drones' kind
    (``cf2x.urdf``, ``cf2p.urdf``, ``racer.urdf``).

    Read as gym-pybullet-drones' ``BaseAviary`` reads it: the mass and inertia of the links'
    ``<inertial>`` tags; the rotors at the CoG frames of the links ``prop0_link`` ..
    ``prop3_link`` (PyBullet applies each rotor's force there); from ``<properties>``: ``kf``
    and ``km`` (thrust and drag moment per squared rotor speed in rpm, so
    ``thrust_constant = kf (60 / 2 pi)^2`` N/(rad/s)^2 and ``moment_constant = km / kf`` m)
    and ``thrust2weight`` (the largest thrust of a rotor is ``thrust2weight m g / 4``). The
    file states no motor lag (``motor_time_constant = 0``) and no linear drag.

    Parameters
    ----------
    path : str or os.PathLike
        The URDF file.
    rotor_directions : tuple of 4 int, optional
        The signs d_i of ``Vehicle.rotor_directions``. The file has none; by default those of
        ``BaseAviary._physics`` (``GYM_PYBULLET_DIRECTIONS``): (-1, 1, -1, 1), and (1, -1, 1,
        -1) for a file named ``racer.urdf`` (BaseAviary negates the racer's torques).
    g : float, default 9.81
        Gravitational acceleration (m/s^2); also sets the largest thrust.
    name : str, optional
        The vehicle's name; default the ``<robot name>`` and the file name.

    Returns
    -------
    dict of str to Any
        ``Vehicle`` fields but the six drag coefficients (not validated: ``Vehicle`` does).

    Raises
    ------
    VehicleFileError
        A missing file, a ``<!DOCTYPE>`` or xacro element, an element read given twice, an
        attribute of ``<inertial>``, ``<mass>``, ``<inertia>`` or ``<origin>`` that is not
        read, a needed value missing or not a number, ``kf`` or ``km`` not > 0, a
        drag moment per thrust ``km / kf`` above ``MAX_MOMENT_CONSTANT``, ``thrust2weight``
        outside ``THRUST_TO_WEIGHT`` (at most 1: the rotors cannot lift the vehicle), a link
        or joint without a name or named twice, a joint naming a link that does not exist, a
        link with two parents, several root links, joints that loop, a length, mass or
        inertia beyond +-LARGEST, or links whose mass lies farther than ``PAYLOAD_REACH`` arm
        lengths from their CoG (named with the file).
    InputError
        ``g`` not a number in [SMALLEST, LARGEST] m/s^2 (``quadcog.model.parameters``), or
        ``rotor_directions`` not None or a tuple.
    PhysicalConsistencyError
        A link whose mass and inertia no rigid body has.
    """
    path = _file_path(path, "path (Vehicle.from_urdf)")
    g = real(g, "g (Vehicle.from_urdf)", lo=SMALLEST, hi=LARGEST, unit="m/s^2")
    if rotor_directions is not None and not isinstance(rotor_directions,
                                                       (list, tuple, np.ndarray)):
        # the signs themselves are checked by Vehicle; tuple(5) was a raw TypeError
        fail("rotor_directions (Vehicle.from_urdf)", "None or 4 signs +1 or -1 (a tuple)",
             rotor_directions)
    root = _parse(path)
    if root.tag != "robot":
        raise VehicleFileError(f"{path}: the root element is <{root.tag}>; expected <robot> "
                               "(URDF)")
    for element in root.iter():
        # xacro's macros, properties and includes are expanded by xacro, not by PyBullet or
        # quadcog: the links and masses they make were left out silently
        if element.tag.startswith("{") and "xacro" in element.tag.partition("}")[0]:
            raise VehicleFileError(f"{path}: <xacro:{element.tag.partition('}')[2]}> is a xacro "
                                   "macro; expected a URDF (expand it first: xacro "
                                   "FILE.urdf.xacro > FILE.urdf)")
    links = _urdf_links(root, path)
    link_pose = _urdf_link_poses(root, links, path)
    bodies = []
    for link_name, link in links.items():
        inertial = _one(link, "inertial", f"link {link_name!r}", path)
        if inertial is None:
            continue
        what = f"link {link_name!r} <inertial>"
        _attributes(inertial, (), what, path)
        mass = _one(inertial, "mass", what, path)
        if mass is not None:
            _attributes(mass, ("value",), f"{what}/mass", path)
        m = _number(None if mass is None else mass.get("value"), f"{what}/mass@value", path,
                    scale=True)
        if m == 0.0:
            continue
        node = _one(inertial, "inertia", what, path)
        if node is None:
            raise VehicleFileError(f"{path}: {what}/inertia is missing; expected ixx, iyy, "
                                   f"izz (kg m^2) of a link of mass {m:g} kg")
        _attributes(node, _INERTIA_KEYS, f"{what}/inertia", path)
        values = {k: _number(node.get(k, "0" if k[1] != k[2] else None),
                             f"{what}/inertia@{k}", path, scale=True) for k in _INERTIA_KEYS}
        where = link_pose[link_name].then(_urdf_origin(inertial, what, path))
        bodies.append(_body(m, where, _inertia_matrix(values), what, path))

    rotors = []
    for i in range(4):
        link_name = f"prop{i}_link"
        if link_name not in links:
            raise VehicleFileError(f"{path}: link {link_name!r} is missing; expected the four "
                                   "rotor links prop0_link .. prop3_link (gym-pybullet-drones)")
        rotors.append(_within_scale(link_pose[link_name].then(
            _urdf_origin(_one(links[link_name], "inertial", f"link {link_name!r}", path),
                         f"link {link_name!r} <inertial>",
                         path)), f"rotor link {link_name!r}", path))
    props = _one(root, "properties", "<robot>", path)
    if props is None:
        raise VehicleFileError(f"{path}: <properties> is missing; expected kf, km and "
                               "thrust2weight (gym-pybullet-drones)")
    kf = _bounded(_number(props.get("kf"), "<properties>@kf", path), "<properties>@kf", path,
                  0.0, LARGEST / RPM_PER_RAD_S ** 2, "N/rpm^2")
    km = _bounded(_number(props.get("km"), "<properties>@km", path), "<properties>@km", path,
                  0.0, LARGEST, "N m/rpm^2")
    if not km / kf <= MAX_MOMENT_CONSTANT:
        raise VehicleFileError(f"{path}: <properties>@km / @kf = {km:g} / {kf:g} = "
                               f"{km / kf:g} m; expected a drag moment per thrust in (0, "
                               f"{MAX_MOMENT_CONSTANT:g}] m")
    t2w = _number(props.get("thrust2weight"), "<properties>@thrust2weight", path)
    lo, hi = THRUST_TO_WEIGHT
    if not lo < t2w <= hi:
        raise VehicleFileError(f"{path}: <properties>@thrust2weight = {t2w:g}; expected a "
                               f"number in ({lo:g}, {hi:g}] (above 1 the rotors lift the "
                               "vehicle)")
    m_total = sum(b.m for b in bodies)
    if rotor_directions is None:
        rotor_directions = GYM_PYBULLET_DIRECTIONS.get(path.stem, GYM_PYBULLET_DIRECTIONS[""])
    return _assemble(path, name or f"{root.get('name', path.stem)} ({path.name})", bodies,
                     np.array(rotors), tuple(rotor_directions), kf * RPM_PER_RAD_S ** 2,
                     km / kf, t2w * m_total * g / 4.0, 0.0, g)


def _urdf_links(root: ET.Element, path: Path) -> dict[str, ET.Element]:
    """The ``<link>`` elements by name; a link without a name, or a name given twice (which
    would leave one of the two out of the vehicle), is refused."""
    links: dict[str, ET.Element] = {}
    for k, link in enumerate(root.findall("link")):
        link_name = link.get("name")
        if not link_name:
            raise VehicleFileError(f"{path}: <link> number {k + 1} has no name; expected "
                                   "<link name=...> (URDF)")
        if link_name in links:
            raise VehicleFileError(f"{path}: link {link_name!r} is declared twice; expected "
                                   "each link name once (URDF)")
        links[link_name] = link
    return links


def _urdf_link_poses(root: ET.Element, links: dict[str, ET.Element],
                     path: Path) -> dict[str, _Pose]:
    """Each link's pose in the root link's frame, in one pass down the joint tree.

    A URDF's links and joints form one tree (PyBullet refuses other files): every joint
    names an existing parent and child link, no link has two parents, one link has none (the
    root) and no chain of joints loops. Anything else is refused with the joint or links
    named, so no link's pose is a guess."""
    parent_of: dict[str, tuple[str, str]] = {}        # child: (parent link, joint)
    children: dict[str, list[tuple[str, ET.Element]]] = {name: [] for name in links}
    joint_names: set[str] = set()
    for k, joint in enumerate(root.findall("joint")):
        joint_name = joint.get("name")
        if not joint_name:
            raise VehicleFileError(f"{path}: <joint> number {k + 1} has no name; expected "
                                   "<joint name=...> (URDF)")
        what = f"joint {joint_name!r}"
        if joint_name in joint_names:
            raise VehicleFileError(f"{path}: {what} is declared twice; expected each joint "
                                   "name once (URDF)")
        joint_names.add(joint_name)
        ends = []
        for end in ("parent", "child"):
            node = _one(joint, end, what, path)
            link_name = None if node is None else node.get("link")
            if link_name is None:
                raise VehicleFileError(f"{path}: {what}/{end}@link is missing; expected the "
                                       "name of a link")
            if link_name not in links:
                raise VehicleFileError(f"{path}: {what}/{end}@link = {link_name!r} is not a "
                                       f"link; expected one of the file's {len(links)} "
                                       "<link name>s")
            ends.append(link_name)
        parent, child = ends
        if child in parent_of:
            raise VehicleFileError(f"{path}: link {child!r} is the child of two joints "
                                   f"({parent_of[child][1]!r} and {joint_name!r}); expected one "
                                   "parent per link (a URDF is a tree)")
        parent_of[child] = (parent, joint_name)
        children[parent].append((child, joint))
    roots = [name for name in links if name not in parent_of]
    if len(roots) > 1:
        raise VehicleFileError(f"{path}: links {roots[0]!r} and {roots[1]!r}"
                               f"{f' (and {len(roots) - 2} more)' if len(roots) > 2 else ''} "
                               "have no parent joint; expected one root link (a URDF is a "
                               "tree)")
    poses: dict[str, _Pose] = {}
    stack = [(roots[0], _IDENTITY)] if roots else []
    while stack:                     # each link once: linear in the links and joints
        link_name, pose = stack.pop()
        poses[link_name] = pose
        stack += [(child, pose.then(_urdf_origin(joint, f"joint {joint.get('name')!r}", path)))
                  for child, joint in children[link_name]]
    if len(poses) < len(links):
        # a link off the root's tree has a parent, and so has that one: the parents loop
        link_name = next(name for name in links if name not in poses)
        loop: list[str] = []
        seen: set[str] = set()
        while link_name not in seen:
            seen.add(link_name)
            loop.append(link_name)
            link_name = parent_of[link_name][0]
        loop = loop[loop.index(link_name):] + [link_name]
        shown = " -> ".join([repr(n) for n in loop] if len(loop) <= 6 else
                            [repr(n) for n in loop[:5]] + ["..."])
        raise VehicleFileError(f"{path}: the joints make a loop: link {shown} (each the "
                               f"parent of the one before, {len(loop) - 1} link(s)); expected "
                               "a tree of links from one root (URDF)")
    return poses


# -- SDF -------------------------------------------------------------------------------------

def _model_folder(uri: str, beside: Path, model_paths: tuple[Path, ...], path: Path) -> Path:
    """The folder of ``model://NAME`` as Gazebo finds it: the given paths, then Gazebo's
    variables, then the folder beside the including model's."""
    name = uri.removeprefix("model://").strip("/").split("/")[0]
    search = list(model_paths)
    for variable in GAZEBO_PATH_VARIABLES:
        search += [Path(p) for p in os.environ.get(variable, "").split(os.pathsep) if p]
    search.append(beside)
    for folder in search:
        if (folder / name).is_dir():
            return folder / name
    raise VehicleFileError(f"{path}: <include><uri>{uri}</uri>: no folder {name!r} in "
                           f"{[str(f) for f in search]}; expected the model beside this one, "
                           f"or its parent folder in model_paths or {GAZEBO_PATH_VARIABLES[0]}")


@dataclass
class _SdfRead:
    """One SDF read's memo and bounds: each file parsed once, each model's includes resolved
    once (a model included many times over costs one read), the chain of includes being
    resolved (a loop is named), and the elements the includes copied so far
    (``MAX_INCLUDED_ELEMENTS``)."""
    model_paths: tuple[Path, ...]
    roots: dict[str, ET.Element] = field(default_factory=dict)
    models: dict[str, "_SdfModel"] = field(default_factory=dict)
    chain: list[Path] = field(default_factory=list)
    copied: int = 0

    def parse(self, path: Path) -> ET.Element:
        key = os.path.realpath(path)       # one file by any of its names
        if key not in self.roots:
            self.roots[key] = _parse(path)
        return self.roots[key]


@dataclass(frozen=True)
class _SdfModel:
    """A model with its includes resolved: name, pose (its ``<model><pose>``), [(link, pose
    in the model frame)], joints, plugins."""
    name: str
    pose: _Pose
    links: list[tuple[ET.Element, _Pose]]
    joints: list[ET.Element]
    plugins: list[ET.Element]


def _model_file(folder: Path, read: _SdfRead) -> Path:
    config = folder / "model.config"
    if config.is_file():
        sdf = _one(read.parse(config), "sdf", "model.config", config)
        if sdf is not None and (sdf.text or "").strip():
            return folder / (sdf.text or "").strip()
    return folder / "model.sdf"


def _sdf_model(path: Path, read: _SdfRead) -> _SdfModel:
    """The SDF model of ``path``, its ``<include>`` s resolved (memoised in ``read``)."""
    key = os.path.realpath(path)
    if key in read.models:
        return read.models[key]
    root = read.parse(path)
    model = _one(root, "model", "<sdf>", path) if root.tag == "sdf" else None
    if model is None:
        raise VehicleFileError(f"{path}: no <sdf><model>; expected an SDF model file")
    nested = model.find("model")
    if nested is not None:
        # its links would weigh in Gazebo and be left out here
        raise VehicleFileError(f"{path}: <model> holds a nested <model name="
                               f"{plain(nested.get('name', ''))}>; expected the model's own "
                               "links and <include>s (quadcog reads no nested models)")
    links = [(link, _sdf_pose(link, f"link {link.get('name')!r}", path))
             for link in model.findall("link")]
    joints, plugins = model.findall("joint"), model.findall("plugin")
    read.chain.append(path)
    for include in model.findall("include"):
        if len(read.chain) > MAX_INCLUDE_DEPTH:
            raise VehicleFileError(f"{path}: <include> nested deeper than {MAX_INCLUDE_DEPTH}; "
                                   "expected no loop")
        uri = (_text(include, "uri", "<include>", path) or "").strip()
        if not uri:
            raise VehicleFileError(f"{path}: <include><uri> is missing")
        target = (_model_file(_model_folder(uri, path.parent.parent, read.model_paths, path),
                              read)
                  if uri.startswith("model://") else (path.parent / uri))
        if any(os.path.realpath(p) == os.path.realpath(target) for p in read.chain):
            loop = " -> ".join(str(p) for p in read.chain + [target])
            raise VehicleFileError(f"{path}: <include><uri>{uri}</uri> includes a model that "
                                   f"includes this one ({loop}); expected includes without a "
                                   "loop")
        inner = _sdf_model(target, read)
        read.copied += len(inner.links) + len(inner.joints) + len(inner.plugins)
        if read.copied > MAX_INCLUDED_ELEMENTS:
            raise VehicleFileError(f"{path}: <include><uri>{uri}</uri>: the includes copy more "
                                   f"than {MAX_INCLUDED_ELEMENTS:,} links, joints and plugins "
                                   "into the model; expected a vehicle's model (is a model "
                                   "included many times at several levels?)")
        placed = _sdf_pose(include, "<include>", path) if include.find("pose") is not None \
            else inner.pose
        links += [(link, placed.then(pose)) for link, pose in inner.links]
        joints += inner.joints
        plugins += inner.plugins
    read.chain.pop()
    resolved = _SdfModel(model.get("name", path.stem), _sdf_pose(model, "<model>", path),
                         links, joints, plugins)
    read.models[key] = resolved
    return resolved


def sdf_fields(path: str | os.PathLike[str], *,
               model_paths: tuple[str | os.PathLike[str], ...] = (), g: float = 9.81,
               name: str | None = None, rotor_links: bool = True) -> dict[str, Any]:
    """The fields of a vehicle (all but the drag) from an SDF model (Gazebo; PX4's ``x500/model.sdf``).

    ``<include>`` s are resolved as Gazebo does: ``model://NAME`` is the folder NAME in
    ``model_paths``, then in ``GZ_SIM_RESOURCE_PATH`` (or ``GAZEBO_MODEL_PATH``), then beside
    the including model's folder; its ``model.config`` names the file (default
    ``model.sdf``). The rotors are the ``MulticopterMotorModel`` plugins in ``motorNumber``
    order: position from the pose of their ``linkName``, the spin axis of their ``jointName``
    (along body z), ``turningDirection`` (ccw seen from above: d_i = -1), ``motorConstant``
    (N/(rad/s)^2), ``momentConstant`` (m), ``maxRotVelocity`` (rad/s; the largest thrust is
    ``motorConstant maxRotVelocity^2``) and ``timeConstantUp`` (s).

    Parameters
    ----------
    path : str or os.PathLike
        The model's SDF file.
    model_paths : tuple of str or os.PathLike, default ()
        Folders that hold models named by ``model://`` URIs, searched first.
    g : float, default 9.81
        Gravitational acceleration (m/s^2).
    name : str, optional
        The vehicle's name; default the model's name and the file's path.
    rotor_links : bool, default True
        Count the rotor links' masses in the body (Gazebo flies them); False takes the other
        links only, as quadcog's X500 preset does (4 x 16 g, 3 % of the mass, left out).

    Returns
    -------
    dict of str to Any
        ``Vehicle`` fields but the six drag coefficients (not validated: ``Vehicle`` does).

    Raises
    ------
    VehicleFileError
        A missing file or included model, a ``<!DOCTYPE>``, a nested ``<model>``, an element
        read given twice, an attribute of ``<pose>`` other than ``degrees`` (true, 1, false
        or 0) or one of ``<inertial>``, includes that loop, nest deeper than
        ``MAX_INCLUDE_DEPTH`` or copy more than ``MAX_INCLUDED_ELEMENTS`` links, joints and
        plugins, a needed value missing or not a number, a rotor axis that is not along body
        z, a ``motorNumber`` that is not one of 0..3 or is given twice, a constant out of its
        range (``motorConstant``, ``maxRotVelocity`` > 0, ``momentConstant`` in (0,
        ``MAX_MOMENT_CONSTANT``] m, ``timeConstantUp`` in [0, ``MAX_MOTOR_TIME_CONSTANT``] s),
        a largest thrust whose ratio to the weight is outside ``THRUST_TO_WEIGHT``, a length,
        mass or inertia beyond +-LARGEST, or links whose mass lies farther than
        ``PAYLOAD_REACH`` arm lengths from their CoG (named with the file).
    InputError
        ``g`` not a number in [SMALLEST, LARGEST] m/s^2 (``quadcog.model.parameters``),
        ``model_paths`` not a tuple of paths, ``rotor_links`` not a bool.
    PhysicalConsistencyError
        A link whose mass and inertia no rigid body has.
    """
    path = _file_path(path, "path (Vehicle.from_sdf)")
    g = real(g, "g (Vehicle.from_sdf)", lo=SMALLEST, hi=LARGEST, unit="m/s^2")   # the weight
    rotor_links = flag(rotor_links, "rotor_links (Vehicle.from_sdf)")
    # a str is iterable too: its letters would be searched as folders
    if not isinstance(model_paths, (tuple, list)) or not all(
            isinstance(p, (str, os.PathLike)) and not isinstance(p, bytes) for p in model_paths):
        fail("model_paths (Vehicle.from_sdf)", "a tuple of folders (str or os.PathLike)",
             model_paths)
    model = _sdf_model(path, _SdfRead(tuple(Path(p) for p in model_paths)))
    links, joints = model.links, model.joints
    motors = [p for p in model.plugins if "MulticopterMotorModel" in (p.get("name", "")
                                                                     + p.get("filename", ""))]
    if len(motors) != 4:
        raise VehicleFileError(f"{path}: {len(motors)} MulticopterMotorModel plugin(s); "
                               "expected 4 (one per rotor)")
    poses: dict[str, _Pose] = {}
    named_twice: set[str] = set()
    for link, pose in links:
        link_name = link.get("name", "")
        if link_name in poses:
            named_twice.add(link_name)
        poses[link_name] = pose
    joint_of = {j.get("name", ""): j for j in joints}

    def text(plugin: ET.Element, tag: str) -> str | None:
        return _text(plugin, tag, "a MulticopterMotorModel plugin", path)

    # Gazebo hands motor k the k-th rotor command: the numbers order the rotors, so each of
    # 0..3 must be given once, written as an integer (1.5 or 1e300 orders nothing)
    numbered: dict[int, ET.Element] = {}
    for plugin in motors:
        number = (text(plugin, "motorNumber") or "").strip()
        what = (f"MulticopterMotorModel of link {(text(plugin, 'linkName') or '').strip()!r}: "
                "motorNumber")
        if not (re.fullmatch(r"[+-]?[0-9]{1,9}", number) and 0 <= int(number) <= 3):
            raise VehicleFileError(f"{path}: {what} = {plain(number)}; expected an integer "
                                   "0..3 (the motor's command index)")
        if int(number) in numbered:
            raise VehicleFileError(f"{path}: {what} = {int(number)} is also the motorNumber of "
                                   "another MulticopterMotorModel; expected each of 0..3 once")
        numbered[int(number)] = plugin
    rotors: list[npt.NDArray[np.float64]] = []
    directions: list[int] = []
    rotor_names: set[str] = set()
    constants: dict[str, list[float]] = {k: [] for k in (
        "motorConstant", "momentConstant", "maxRotVelocity", "timeConstantUp")}
    # sign and scale of each constant: (lo, hi, lo excluded, unit); the largest thrust's
    # scale is checked on the whole (_check_lift)
    ranges = {"motorConstant": (0.0, LARGEST, True, "N/(rad/s)^2"),
              "momentConstant": (0.0, MAX_MOMENT_CONSTANT, True, "m"),
              "maxRotVelocity": (0.0, math.inf, True, "rad/s"),
              "timeConstantUp": (0.0, MAX_MOTOR_TIME_CONSTANT, False, "s")}
    for k in range(4):
        plugin = numbered[k]
        what = f"MulticopterMotorModel of motor {k}"
        link_name = (text(plugin, "linkName") or "").strip()
        if link_name not in poses:
            listed = (sorted(poses) if len(poses) <= 8 else
                      f"the model's {len(poses)} links")
            raise VehicleFileError(f"{path}: {what}: linkName {link_name!r} is not a link; "
                                   f"expected one of {listed}")
        if link_name in named_twice:
            raise VehicleFileError(f"{path}: {what}: linkName {link_name!r} names more than "
                                   "one link (the model's and its includes'); expected one")
        rotor_names.add(link_name)
        rotors.append(_within_scale(poses[link_name], f"{what}: link {link_name!r}", path))
        joint = joint_of.get((text(plugin, "jointName") or "").strip())
        if joint is not None and joint.find("axis/xyz") is not None:
            axis = _numbers(joint.findtext("axis/xyz"), f"joint {joint.get('name')!r} "
                            "axis/xyz", path, 3)
            _check_axis(poses[link_name].R @ axis, f"joint {joint.get('name')!r} axis", path)
        spin = (text(plugin, "turningDirection") or "").strip().lower()
        if spin not in ("cw", "ccw"):
            raise VehicleFileError(f"{path}: {what}: turningDirection = {plain(spin)}; "
                                   "expected 'cw' or 'ccw'")
        directions.append(-1 if spin == "ccw" else 1)
        for key, values in constants.items():
            lo, hi, lo_open, unit = ranges[key]
            values.append(_bounded(_number(text(plugin, key), f"{what}/{key}", path),
                                   f"{what}/{key}", path, lo, hi, unit, lo_open))
    for key, values in constants.items():
        if max(values) != min(values):
            raise VehicleFileError(f"{path}: {key} differs between the rotors ({values}); "
                                   "expected one value (quadcog's rotors are alike)")
    bodies = []
    for link, pose in links:
        link_name = link.get("name", "")
        inertial = _one(link, "inertial", f"link {link_name!r}", path)
        if inertial is None or (not rotor_links and link_name in rotor_names):
            continue
        what = f"link {link_name!r} <inertial>"
        # auto="false" (SDF 1.11's default) says the numbers are as written; auto="true"
        # asks Gazebo to compute them from the collisions, which quadcog does not
        manual = inertial.get("auto", "false").strip().lower() in ("false", "0")
        _attributes(inertial, ("auto",) if manual else (), what, path)
        m = _number(_text(inertial, "mass", what, path), f"{what}/mass", path, scale=True)
        if m == 0.0:
            continue
        node = _one(inertial, "inertia", what, path)
        if node is None:
            raise VehicleFileError(f"{path}: {what}/inertia is missing; expected ixx, iyy, "
                                   f"izz (kg m^2) of a link of mass {m:g} kg")
        inertia = {k: _number(_text(node, k, f"{what}/inertia", path) or
                             ("0" if k[1] != k[2] else None),
                             f"{what}/inertia/{k}", path, scale=True) for k in _INERTIA_KEYS}
        where = pose.then(_sdf_pose(inertial, what, path))
        bodies.append(_body(m, where, _inertia_matrix(inertia), what, path))
    c = {k: v[0] for k, v in constants.items()}
    # a product, not ** 2: a float's power raises OverflowError where this gives inf
    max_thrust = c["motorConstant"] * c["maxRotVelocity"] * c["maxRotVelocity"]
    fields = _assemble(path, name or f"{model.name} ({path})", bodies, np.array(rotors),
                       tuple(directions), c["motorConstant"], c["momentConstant"],
                       max_thrust, c["timeConstantUp"], g)
    _check_lift(fields, f"motorConstant {c['motorConstant']:g} N/(rad/s)^2 x maxRotVelocity "
                f"{c['maxRotVelocity']:g} rad/s squared", path)
    return fields


def file_fields(path: str | os.PathLike[str], **options: Any) -> dict[str, Any]:
    """The fields of a vehicle from a URDF (``.urdf``) or SDF (``.sdf``) file, by its suffix.

    Parameters
    ----------
    path : str or os.PathLike
        The file.
    **options
        Passed on to ``urdf_fields`` or ``sdf_fields``.

    Returns
    -------
    dict of str to Any
        ``Vehicle`` fields but the drag.

    Raises
    ------
    VehicleFileError
        A suffix other than ``.urdf`` or ``.sdf``, or what the reader raises.
    InputError
        An option the reader does not take (``check_options``).
    """
    path = _file_path(path, "path (Vehicle.from_file)")
    if path.suffix.lower() == ".urdf":
        check_options(urdf_fields, options, "Vehicle.from_file (a .urdf file)")
        return urdf_fields(path, **options)
    if path.suffix.lower() == ".sdf":
        check_options(sdf_fields, options, "Vehicle.from_file (an .sdf file)")
        return sdf_fields(path, **options)
    raise VehicleFileError(f"{path}: suffix {path.suffix!r}; expected a .urdf or .sdf vehicle "
                           "file")

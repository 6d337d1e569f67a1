"""PX4's x500 airframe and quadcog's X500: the parameters PX4 flies with, and PX4's motor
outputs as rotor thrusts.

quadcog starts PX4 with the external-simulator airframe 10016 (``none_iris``: PX4 talks to a
simulator over MAVLink) and gives it the parameters of PX4's own x500 airframe
(``ROMFS/px4fmu_common/init.d-posix/airframes/4001_gz_x500``: the control allocator's rotor
geometry ``CA_ROTOR*``, ``MPC_THR_HOVER``, ...), read from the tree, as ``PX4_PARAM_<name>``
environment variables (rcS applies them after the airframe). The ``SIM_GZ_*`` entries are the
Gazebo bridge's, not parameters of this interface: ``SIM_GZ_EC_MIN{i}`` and
``SIM_GZ_EC_MAX{i}`` are the rotor speeds (rad/s) that motor output 0 and 1 mean, so PX4's
motor output ``u`` in [0, 1] is the rotor speed ``omega = min + (max - min) u`` and the thrust
``k omega^2`` with the X500's ``thrust_constant`` k, as in the gz model that quadcog's preset
copies (``quadcog.vehicles.vehicle.X500``). A disarmed PX4 sends zeros: the rotors stand.

``check_rotors`` holds the preset against the airframe: rotor ``i`` of the preset must be PX4's
motor ``i`` (the same quadrant of the body, the same spin: ``-sign(CA_ROTOR{i}_KM)``, KM > 0
for a counter-clockwise rotor, as ``quadcog.logs.ulog`` reads it).
"""
from dataclasses import dataclass
from pathlib import Path
import re

import numpy as np
import numpy.typing as npt

from quadcog.errors import Px4Error
from quadcog.vehicles.vehicle import N_ROTORS, Vehicle

__all__ = ["AIRFRAME", "X500_AIRFRAME", "SIM_AIRFRAME", "SIM_MODEL", "read_airframe",
           "RotorMap", "rotor_map", "check_rotors", "px4_parameters"]

AIRFRAME = "ROMFS/px4fmu_common/init.d-posix/airframes"
X500_AIRFRAME = "4001_gz_x500"
SIM_AIRFRAME = 10016               # none_iris: the MAVLink external-simulator airframe
SIM_MODEL = "none_iris"
_PARAM = re.compile(r"^\s*param\s+set-default\s+(\w+)\s+(\S+)", re.M)


def read_airframe(tree: Path, name: str = X500_AIRFRAME) -> dict[str, float]:
    """The ``param set-default`` lines of one of the tree's SITL airframe files.

    Parameters
    ----------
    tree : pathlib.Path
        The PX4-Autopilot source folder.
    name : str
        The airframe file's name.

    Returns
    -------
    dict of str to float
        Parameter name -> value.

    Raises
    ------
    quadcog.Px4Error
        When the file is missing or sets nothing.
    """
    path = tree / AIRFRAME / name
    try:
        text = path.read_text()
    except OSError as e:
        raise Px4Error(f"{path}: cannot read PX4's airframe file ({e.strerror})") from None
    params = {k: float(v) for k, v in _PARAM.findall(text)}
    if not params:
        raise Px4Error(f"{path}: no `param set-default` lines: not a PX4 airframe file")
    return params


@dataclass(frozen=True)
class RotorMap:
    """PX4's motor outputs to rotor thrusts.

    Parameters
    ----------
    omega_min : tuple of 4 float
        Rotor speed (rad/s) at output 0, per motor.
    omega_max : tuple of 4 float
        Rotor speed (rad/s) at output 1, per motor.
    thrust_constant : float
        k in ``f = k omega^2`` (N s^2/rad^2).
    """
    omega_min: tuple[float, ...]
    omega_max: tuple[float, ...]
    thrust_constant: float

    def thrust(self, u: npt.ArrayLike, armed: bool) -> npt.NDArray[np.float64]:
        """Rotor thrusts for PX4's outputs.

        Parameters
        ----------
        u : (4,) array_like
            Motor outputs, PX4's order (clipped to [0, 1]).
        armed : bool
            False: the rotors stand (zero thrust).

        Returns
        -------
        (4,) numpy.ndarray
            Thrust per rotor (N), quadcog's rotor order (the same as PX4's for the X500).
        """
        if not armed:
            return np.zeros(N_ROTORS)
        u = np.clip(np.asarray(u, float)[:N_ROTORS], 0.0, 1.0)
        lo, hi = np.asarray(self.omega_min), np.asarray(self.omega_max)
        omega = lo + (hi - lo) * u
        return self.thrust_constant * omega * omega


def rotor_map(params: dict[str, float], vehicle: Vehicle) -> RotorMap:
    """The motor-output-to-thrust map of the airframe's ``SIM_GZ_EC_MIN/MAX`` and the
    vehicle's thrust constant.

    Parameters
    ----------
    params : dict
        ``read_airframe``'s.
    vehicle : Vehicle
        Its ``thrust_constant`` (N s^2/rad^2).

    Returns
    -------
    RotorMap
        The map.

    Raises
    ------
    quadcog.Px4Error
        When the airframe has no ``SIM_GZ_EC_MIN/MAX`` for a motor, or the vehicle no thrust
        constant.
    """
    try:
        lo = tuple(params[f"SIM_GZ_EC_MIN{i + 1}"] for i in range(N_ROTORS))
        hi = tuple(params[f"SIM_GZ_EC_MAX{i + 1}"] for i in range(N_ROTORS))
    except KeyError as e:
        raise Px4Error(f"the airframe {X500_AIRFRAME} has no {e.args[0]}: expected the rotor "
                       f"speed range of each motor (SIM_GZ_EC_MIN1..4, SIM_GZ_EC_MAX1..4)") \
            from None
    k = vehicle.thrust_constant
    if not k or not k > 0:
        raise Px4Error(f"vehicle {vehicle.name!r} has no thrust_constant (got {k!r}): "
                       f"expected k > 0 in f = k omega^2 to map PX4's motor outputs")
    return RotorMap(lo, hi, float(k))


def check_rotors(params: dict[str, float], vehicle: Vehicle) -> None:
    """Refuse a vehicle whose rotors are not PX4's motors in PX4's order.

    Parameters
    ----------
    params : dict
        ``read_airframe``'s (``CA_ROTOR{i}_PX``, ``_PY`` in FRD, ``_KM``).
    vehicle : Vehicle
        Its ``rotor_positions`` (FLU) and ``rotor_directions``.

    Raises
    ------
    quadcog.Px4Error
        Naming the first rotor whose quadrant or spin differs.
    """
    for i in range(N_ROTORS):
        try:
            px, py, km = (params[f"CA_ROTOR{i}_{k}"] for k in ("PX", "PY", "KM"))
        except KeyError as e:
            raise Px4Error(f"the airframe {X500_AIRFRAME} has no {e.args[0]}") from None
        x, y = vehicle.rotor_positions[i]
        if np.sign(x) != np.sign(px) or np.sign(y) != np.sign(-py):
            raise Px4Error(f"vehicle {vehicle.name!r}: rotor {i + 1} at ({x:g}, {y:g}) m "
                           f"(FLU) is not PX4's motor {i + 1} at ({px:g}, {-py:g}) m of "
                           f"{X500_AIRFRAME}: expected the rotors in PX4's motor order (PX4 "
                           f"flies the X500: vehicle.preset = \"x500\")")
        if vehicle.rotor_directions[i] != -np.sign(km):
            raise Px4Error(f"vehicle {vehicle.name!r}: rotor {i + 1} turns "
                           f"{vehicle.rotor_directions[i]:+d} but PX4's motor {i + 1} has "
                           f"CA_ROTOR{i}_KM = {km:g} (expected direction {-np.sign(km):+.0f})")


def px4_parameters(params: dict[str, float]) -> dict[str, str]:
    """The airframe's parameters as PX4 takes them from the environment.

    Parameters
    ----------
    params : dict
        ``read_airframe``'s.

    Returns
    -------
    dict of str to str
        ``PX4_PARAM_<name>`` -> value, without the Gazebo bridge's ``SIM_GZ_*``.
    """
    return {f"PX4_PARAM_{k}": f"{v:g}" for k, v in params.items() if not k.startswith("SIM_GZ")}

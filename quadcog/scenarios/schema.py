"""The schema of a scenario file: every key and the kind of value it takes.

The settings of ``[trajectory]`` and ``[controller_params]`` are not listed here: they are read
from the constructors' annotations through the registries (``quadcog.trajectories.registry``,
``quadcog.controllers.registry``), so a setting added to a constructor is a scenario key at
once. Each entry's check is a token of ``quadcog.scenarios.scenario``'s checker: a Python type,
``NUMBER`` or a string naming an array shape.
"""
import functools
import inspect
from typing import Any

from quadcog.controllers.registry import CONTROLLERS, controller_names, controller_settings
from quadcog.kinds import Kind
from quadcog.trajectories.registry import TRAJECTORIES, trajectory_kinds, trajectory_settings
from quadcog.vehicles.vehicle import FIELD_NAMES

__all__ = ["NUMBER", "CHECK", "TOP", "VEHICLE", "TRUTH", "STACK", "STACKS", "SENSING", "LIMITS", "COG", "PAYLOAD",
           "DISTURBANCE", "controller_params", "trajectory_schema"]

NUMBER = (int, float)
# the check of each kind of setting
CHECK: dict[Kind, Any] = {
    Kind.NUMBER: NUMBER, Kind.FLAG: bool, Kind.STRING: str, Kind.VEC3: "vec3",
    Kind.VECTOR: "vec", Kind.POINTS: "points", Kind.PAIRS4: "pairs4",
    Kind.NUMBER_OR_VEC3: "number_or_vec3", Kind.NUMBER_OR_FALSE: "number_or_false",
}
TOP = {"name": str, "description": str, "controller": str, "duration": NUMBER, "dt": NUMBER,
       "path": str, "trajectory": dict, "cog": list, "payload": list, "disturbance": list,
       "vehicle": dict,
       "controller_model": dict, "controller_params": dict, "truth": dict, "limits": dict,
       "sensing": dict, "initial_offset": "vec3", "stack": dict}
# every Vehicle field, and a preset to start from
VEHICLE = {name: {"rotor_positions": "pairs4", "rotor_directions": "vec",
                  "name": str, "rotor_model": str, "payloads": list}.get(name, NUMBER)
           for name in FIELD_NAMES}
VEHICLE["preset"] = str
VEHICLE["identified"] = str         # the JSON of `quadcog identify --json`: its r_G
VEHICLE["file"] = str               # a URDF or SDF file (quadcog.vehicles.description)
# a flight stack instead of quadcog's law (quadcog.crazyflie): its name and its own settings
STACK = {"name": str, "controller": str, "propellers": str, "battery_voltage": NUMBER}
STACKS = ("crazyflie",)
TRUTH = {"parallel_axis": bool, "rotor_saturation": bool, "motor_lag": bool, "quaternion": bool}
SENSING = {"noise": bool, "delay": bool, "seed": NUMBER, "position": NUMBER, "velocity": NUMBER,
           "attitude": NUMBER, "gyro_density": NUMBER, "gyro_bias": NUMBER,
           "accel_density": NUMBER, "accel_bias": NUMBER}
LIMITS = {"max_position_error": NUMBER, "max_tilt_deg": NUMBER}
COG = {"t": NUMBER, "r": "vec3", "ramp": NUMBER}
PAYLOAD = {"t": NUMBER, "action": str, "name": str, "mass": NUMBER, "position": "vec3",
           "size": "vec3", "ramp": NUMBER}
DISTURBANCE = {"t": NUMBER, "duration": NUMBER, "force": "vec3", "moment": "vec3"}


def _takes(cls: type, name: str) -> bool:
    """Whether ``cls``'s constructor (or a base's) has a parameter ``name``."""
    return _takes_once(cls, name)


@functools.lru_cache(maxsize=None)          # signatures do not change; sweeps ask per flight
def _takes_once(cls: type, name: str) -> bool:
    return any(name in inspect.signature(k.__dict__["__init__"]).parameters
               for k in cls.__mro__ if "__init__" in k.__dict__)


def controller_params() -> dict[str, dict[str, Any]]:
    """The keys of ``[controller_params]`` for each controller.

    Returns
    -------
    dict of str to dict
        {controller: {key: check}}: the constructor's settings, and ``Q_scale`` (files give
        the Lyapunov weight Q as a multiple of the identity) where the constructor takes Q.
    """
    out = {}
    for name in controller_names():
        keys = {k: CHECK[kind] for k, kind in controller_settings(name).items()}
        if _takes(CONTROLLERS[name], "Q"):
            keys["Q_scale"] = NUMBER
        out[name] = keys
    return out


def trajectory_schema() -> dict[str, tuple[type, dict[str, Any]]]:
    """The kinds of ``[trajectory]`` and their keys.

    Returns
    -------
    dict of str to (type, dict)
        {kind: (class, {key: check})}, read from the registry.
    """
    return {kind: (TRAJECTORIES[kind],
                   {k: CHECK[v] for k, v in trajectory_settings(kind).items()})
            for kind in trajectory_kinds()}

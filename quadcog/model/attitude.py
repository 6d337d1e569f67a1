"""The attitude on SE(3) at run time (docs/model.md sec. 8): the checks of a rotation matrix and
a unit quaternion, and the two maps between the ZYX Euler chart and the quaternion that the
quaternion truth plant and the tests use.

The quaternion is ``[q_w, q_x, q_y, q_z]`` (Hamilton, scalar first, body to ground); R(q) is the
generated ``quaternion_rotation``. ``quaternion_of_euler`` and ``euler_of_rotation`` are written
once for numpy and CasADi alike (``ops`` is the module: ``numpy`` or ``casadi``).
"""
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog import validate
from quadcog.errors import AttitudeError

__all__ = ["ATTITUDE_TOLERANCE", "QUATERNION", "check_rotation", "check_unit_quaternion",
           "quaternion_of_euler", "euler_of_rotation"]

# |R^T R - I| (largest entry), |det R - 1| and ||q| - 1| above this are refused: far above the
# rounding of a float64 rotation (1e-16), below any attitude a caller means
ATTITUDE_TOLERANCE = 1e-6
# the entries of the quaternion in the state on SE(3) [x, y, z, q_w, q_x, q_y, q_z, nu]
QUATERNION = slice(3, 7)
# below this, cos(theta) counts as zero in euler_of_rotation (gimbal lock: only phi -+ psi is
# defined there, and psi = 0 is taken)
_GIMBAL = 1e-12


def check_rotation(R: npt.ArrayLike, where: str) -> npt.NDArray[np.float64]:
    """``R`` as a (3, 3) float array if it is a rotation matrix, else AttitudeError.

    Parameters
    ----------
    R : (3, 3) array_like
        A rotation matrix (body to ground).
    where : str
        The name the caller knows it by (an argument, a scenario key).

    Returns
    -------
    (3, 3) numpy.ndarray
        R.

    Raises
    ------
    quadcog.InputError
        Not a finite (3, 3) array.
    quadcog.errors.AttitudeError
        ``R^T R`` differs from I, or ``det R`` from 1, by more than ATTITUDE_TOLERANCE (a
        reflection has det -1).
    """
    R = validate.array(R, where, (3, 3), what="a finite (3, 3) rotation matrix")
    off = float(np.abs(R.T @ R - np.eye(3)).max())
    if off > ATTITUDE_TOLERANCE:
        raise AttitudeError(f"{where}: expected a rotation matrix (R^T R = I within "
                            f"{ATTITUDE_TOLERANCE:g}), got one with |R^T R - I| = {off:.3g}: "
                            f"{validate.plain(R.round(6).tolist())}")
    det = float(np.linalg.det(R))
    if abs(det - 1.0) > ATTITUDE_TOLERANCE:
        raise AttitudeError(f"{where}: expected a rotation matrix (det R = 1), got det R = "
                            f"{det:.6g} (a reflection)")
    return R


def check_unit_quaternion(q: npt.ArrayLike, where: str) -> npt.NDArray[np.float64]:
    """``q`` as a (4,) float array if it is a unit quaternion, else AttitudeError.

    Parameters
    ----------
    q : (4,) array_like
        ``[q_w, q_x, q_y, q_z]``.
    where : str
        The name the caller knows it by.

    Returns
    -------
    (4,) numpy.ndarray
        q.

    Raises
    ------
    quadcog.InputError
        Not 4 finite numbers.
    quadcog.errors.AttitudeError
        ``|q|`` differs from 1 by more than ATTITUDE_TOLERANCE (a zero quaternion has no
        attitude; normalize with q / |q|).
    """
    q = validate.vector(q, where, 4)
    norm = float(np.linalg.norm(q))
    if not abs(norm - 1.0) <= ATTITUDE_TOLERANCE:
        raise AttitudeError(f"{where}: expected a unit quaternion [q_w, q_x, q_y, q_z] (|q| = 1 "
                            f"within {ATTITUDE_TOLERANCE:g}), got |q| = {norm:.6g} for "
                            f"{validate.plain(q.tolist())}"
                            + ("" if norm == 0 else "; normalize it (q / |q|)"))
    return q


def quaternion_of_euler(phi: Any, theta: Any, psi: Any, ops: ModuleType = np) -> Any:
    """The unit quaternion of R = Rz(psi) Ry(theta) Rx(phi): q_z(psi) q_y(theta) q_x(phi).

    Parameters
    ----------
    phi : float, numpy.ndarray or casadi.SX
        Roll, the ZYX Euler angle about x (rad).
    theta : float, numpy.ndarray or casadi.SX
        Pitch, the ZYX Euler angle about y (rad).
    psi : float, numpy.ndarray or casadi.SX
        Yaw, the ZYX Euler angle about z (rad).
    ops : module
        ``numpy`` (default) or ``casadi``: where sin and cos come from.

    Returns
    -------
    (4,) numpy.ndarray or list of 4 casadi.SX
        ``[q_w, q_x, q_y, q_z]`` (for numpy, a stacked array: (4,) or (4, N)).
    """
    cx, sx = ops.cos(phi / 2), ops.sin(phi / 2)
    cy, sy = ops.cos(theta / 2), ops.sin(theta / 2)
    cz, sz = ops.cos(psi / 2), ops.sin(psi / 2)
    q = [cz * cy * cx + sz * sy * sx, cz * cy * sx - sz * sy * cx,
         cz * sy * cx + sz * cy * sx, sz * cy * cx - cz * sy * sx]
    return np.array(q) if ops is np else q


def euler_of_rotation(R: Any, ops: ModuleType = np) -> tuple[Any, Any, Any]:
    """The ZYX Euler angles of a rotation matrix: the chart the Euler laws see.

    theta = atan2(-R31, |(R11, R21)|) in [-pi/2, pi/2], phi = atan2(R32, R33) and
    psi = atan2(R21, R11) in (-pi, pi]; at gimbal lock (cos theta below 1e-12) psi = 0 and
    phi is read from R12 and R22, so that R(phi, theta, psi) is R there too.

    Parameters
    ----------
    R : (3, 3) numpy.ndarray or casadi.SX
        A rotation matrix, body to ground.
    ops : module
        ``numpy`` (default) or ``casadi``.

    Returns
    -------
    phi, theta, psi : float or casadi.SX
        Roll, pitch, yaw (rad).
    """
    c = ops.sqrt(R[0, 0] * R[0, 0] + R[1, 0] * R[1, 0])
    theta = ops.arctan2(-R[2, 0], c) if ops is np else ops.atan2(-R[2, 0], c)
    atan2 = np.arctan2 if ops is np else ops.atan2
    regular_phi, regular_psi = atan2(R[2, 1], R[2, 2]), atan2(R[1, 0], R[0, 0])
    # at theta = +-pi/2, R = [[0, s, c], [0, c, -s], [-1, 0, 0]] (or its mirror) for psi = 0
    locked_phi = atan2(-R[2, 0] * R[0, 1], R[1, 1])
    if ops is np:
        locked = c < _GIMBAL
        return (np.where(locked, locked_phi, regular_phi), theta,
                np.where(locked, 0.0, regular_psi))
    locked = c < _GIMBAL
    return (ops.if_else(locked, locked_phi, regular_phi), theta,
            ops.if_else(locked, 0, regular_psi))

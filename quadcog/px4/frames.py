"""quadcog's frames and PX4's, and the one conversion between them.

quadcog's truth model flies in a z-up ground frame and a body frame x forward, y left, z up
(FLU). PX4 works in NED (north, east, down) and FRD (forward, right, down). The map between
them is the half turn about x, ``T = diag(1, -1, -1)``, the convention of the ULog reader
(``quadcog.logs.ulog``): NED -> x north, y west, z up; FRD -> FLU. So the plant's ground x
axis is north and its y axis west, and a ULog PX4 wrote while flying quadcog's plant reads back
in the frame the plant flew in. ``T`` is its own inverse, so one function maps both ways:
a vector ``v`` in one frame is ``T v`` in the other, a rotation ``R`` is ``T R T``.
"""
import numpy as np
import numpy.typing as npt

__all__ = ["FLIP", "flip", "flip_rotation"]

# the half turn about x: FLU <-> FRD (body) and NWU <-> NED (ground); its own inverse
FLIP = np.array([1.0, -1.0, -1.0])
FLIP.setflags(write=False)


def flip(v: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A vector (or a stack of them) in the other convention: ``T v``.

    FLU body components <-> FRD, z-up ground (north, west, up) <-> NED.

    Parameters
    ----------
    v : (..., 3) array_like
        Components in one convention (any unit).

    Returns
    -------
    (..., 3) numpy.ndarray
        The same vector's components in the other: ``[v0, -v1, -v2]``.
    """
    return np.asarray(v, dtype=float) * FLIP


def flip_rotation(R: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A body-to-ground rotation in the other convention: ``T R T``.

    quadcog's ``rotation_matrix(phi, theta, psi)`` (FLU -> z-up ground) becomes PX4's FRD ->
    NED rotation and back; its ZYX angles become ``(phi, -theta, -psi)``.

    Parameters
    ----------
    R : (3, 3) array_like
        Rotation body -> ground in one convention.

    Returns
    -------
    (3, 3) numpy.ndarray
        The rotation in the other.
    """
    return np.asarray(R, dtype=float) * FLIP[:, None] * FLIP[None, :]

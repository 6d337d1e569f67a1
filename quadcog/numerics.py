"""Numerical helpers of the floor: fast forms that round exactly as numpy's general ones."""
import numpy as np
import numpy.typing as npt

__all__ = ["row_norms"]


def row_norms(v: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The Euclidean norms of the rows of an (N, 3) array, ``np.linalg.norm(v, axis=1)``.

    The same sums in the same order, ``sqrt((v0^2 + v1^2) + v2^2)``, so the same bits, in a
    quarter of the time: numpy's reduction over a short last axis loops per row.

    Parameters
    ----------
    v : (N, 3) numpy.ndarray
        The vectors.

    Returns
    -------
    (N,) numpy.ndarray
        Their norms (inf where a square overflows, quietly).
    """
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    with np.errstate(over="ignore", invalid="ignore"):
        return np.sqrt(x * x + y * y + z * z)

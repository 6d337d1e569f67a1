"""Parameter vectors p (the 14 entries of the generated functions, order: docs/model.md sec.
1.2) and which of them the model accepts (sec. 1.4), in one place. The vehicle they come from
is ``quadcog.vehicles.vehicle.Vehicle``.

Which parameter sets the model accepts (docs/model.md sec. 1.4), with a margin that has a
meaning: the inertia about the CoG must keep at least ``MARGIN`` of the inertia about O in
every direction,

    u^T I_G u >= MARGIN * u^T I_O u   for every unit vector u,

i.e. the smallest eigenvalue of ``I_O^-1/2 I_G I_O^-1/2`` (the *inertia ratio*, 1 for a CoG at
O, 0 on the rim where M turns singular) is at least ``MARGIN``. Below it, M^-1 (formed by block
elimination through I_G^-1) loses digits as 1 / ratio does, and at the rim itself the
generated dynamics return NaN. Each parameter must also lie within a sane scale (SMALLEST,
LARGEST below), so that the model's products and inverses stay finite. Every runtime check of
parameters uses this module.
"""
from typing import Any

import numpy as np
import numpy.typing as npt

from quadcog.errors import ParameterError
from quadcog.model.conventions import IDX, LARGEST, N_PARAM, PARAM_NAMES, R_G, SMALLEST
from quadcog.validate import array, fail, vector

__all__ = ["SMALLEST", "LARGEST", "MARGIN", "inertia_about_cog", "inertia_ratio",
           "admissible_radius", "is_admissible", "with_cog", "check_parameters"]

# 1 %: I_G^-1 is then at most 100x I_O^-1, and the admissible radius of the default vehicle
# shrinks by only 0.5 % (from 10.15 cm to 10.09 cm).
MARGIN = 0.01


def inertia_about_cog(p: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """I_G = I_O - m (|r_G|^2 I - r_G r_G^T), the inertia about the CoG.

    Parameters
    ----------
    p : (14,) or (..., 14) array_like
        Parameter vector (SI units, order ``PARAM_NAMES``), or a stack of them.

    Returns
    -------
    (3, 3) or (..., 3, 3) numpy.ndarray
        I_G in kg m^2, body axes.

    Raises
    ------
    ParameterError
        ``p`` is not an array of finite numbers whose last axis has 14 entries, or I_G
        overflows the float range (a CoG offset of 1e200 m gave inf).
    """
    p = array(p, "p", error=ParameterError)
    if p.ndim == 0 or p.shape[-1] != N_PARAM:
        fail("p", f"an array of shape ({N_PARAM},) or (..., {N_PARAM})",
             f"an array of shape {p.shape}", ParameterError)
    inertia = _inertia_about_cog(p)
    if not np.isfinite(inertia).all():
        raise ParameterError(f"p: the inertia about the CoG overflows the float range (largest "
                             f"|entry| of p: {float(np.abs(p).max()):.3g}); expected a CoG "
                             f"offset and a mass within the model's scale (docs/model.md sec. "
                             f"1.4)")
    return inertia


def _inertia_about_cog(p: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``inertia_about_cog`` unchecked: inf or NaN where the numbers overflow."""
    p = np.asarray(p, dtype=float)
    r = p[..., R_G]
    with np.errstate(over="ignore", invalid="ignore"):
        if p.ndim == 1:
            return (np.diag(p[IDX["Ixx"]:IDX["Izz"] + 1])
                    - p[IDX["m"]] * (r @ r * np.eye(3) - np.outer(r, r)))
        # a stack (a plot's fine grid): the same formula, broadcast
        inertia = p[..., IDX["Ixx"]:IDX["Izz"] + 1, None] * np.eye(3)
        rr = np.sum(r * r, axis=-1)[..., None, None]
        return inertia - p[..., IDX["m"], None, None] * (rr * np.eye(3)
                                                         - r[..., :, None] * r[..., None, :])


def inertia_ratio(p: npt.ArrayLike) -> Any:
    """Smallest eigenvalue of I_O^-1/2 I_G I_O^-1/2.

    Parameters
    ----------
    p : (14,) or (..., 14) array_like
        Parameter vector (SI units), or a stack of them; requires Ixx, Iyy, Izz > 0.

    Returns
    -------
    float or numpy.ndarray
        The least fraction of the inertia about O that the inertia about the CoG keeps over
        all directions (dimensionless; 1 for a CoG at O); NaN when the numbers overflow. One
        per parameter vector of a stack.
    """
    p = np.asarray(p, dtype=float)
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        scale = 1.0 / np.sqrt(p[..., IDX["Ixx"]:IDX["Izz"] + 1])
        S = scale[..., :, None] * _inertia_about_cog(p) * scale[..., None, :]
    finite = np.isfinite(S).all(axis=(-2, -1))
    S = np.where(finite[..., None, None], S, 0.0)
    ratio = np.where(finite, np.linalg.eigvalsh(0.5 * (S + np.swapaxes(S, -1, -2)))[..., 0],
                     np.nan)
    return float(ratio) if p.ndim == 1 else ratio


def admissible_radius(p: npt.ArrayLike) -> float:
    """The CoG offset below which every direction is admissible.

    Parameters
    ----------
    p : (14,) array_like
        Parameter vector (SI units); its mass and inertia about O are used.

    Returns
    -------
    float
        sqrt((1 - MARGIN) min(Ixx, Iyy, Izz) / m) (m): every CoG offset shorter than this is
        admissible, whatever its direction (since m (|r|^2 I - r r^T) <= m |r|^2 I).
    """
    p = np.asarray(p, dtype=float)
    return float(np.sqrt((1 - MARGIN) * np.min(p[IDX["Ixx"]:IDX["Izz"] + 1]) / p[IDX["m"]]))


def is_admissible(p: npt.ArrayLike) -> bool:
    """Whether the model accepts the CoG offset of ``p``.

    Parameters
    ----------
    p : (14,) array_like
        Parameter vector (SI units), mass and inertia assumed positive and finite
        (quadcog.model.parameters.check_parameters checks those first).

    Returns
    -------
    bool
        True when the inertia ratio of ``p`` is at least MARGIN.
    """
    ratio = inertia_ratio(p)
    return bool(np.isfinite(ratio) and ratio >= MARGIN)


def with_cog(p: npt.ArrayLike, r_G: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """A copy of ``p`` with the CoG offset replaced by ``r_G``.

    Parameters
    ----------
    p : (14,) array_like
        Parameter vector (SI units).
    r_G : (3,) array_like
        The new CoG offset from O (m, body axes).

    Returns
    -------
    (14,) numpy.ndarray
        A new parameter vector.

    Raises
    ------
    InputError
        ``p`` is not 14 finite numbers or ``r_G`` not 3 (a string or two numbers raised
        ValueError, NaN was copied in).
    """
    p = vector(p, "p", N_PARAM)
    p[R_G] = vector(r_G, "r_G", 3)
    return p


def check_parameters(p: npt.ArrayLike, name: str = "p") -> npt.NDArray[np.float64]:
    """Check that ``p`` is an admissible parameter vector (docs/model.md sec. 1.4).

    Parameters
    ----------
    p : (14,) array_like
        Parameter vector (SI units, order ``PARAM_NAMES``).
    name : str, optional
        What to call it in messages.

    Returns
    -------
    (14,) numpy.ndarray
        ``p`` as a new float array.

    Raises
    ------
    ParameterError
        A non-finite entry, m, g or inertia not > 0, a negative drag coefficient, an entry
        out of scale, or a CoG too far from O (margin ``quadcog.model.parameters.MARGIN``).
    """
    p = vector(p, name, N_PARAM, finite=False, error=ParameterError)
    bad = np.flatnonzero(~np.isfinite(p))
    if bad.size:
        k = bad[0]
        raise ParameterError(f"{name}[{k}] ({PARAM_NAMES[k]}) = {p[k]} is not finite")
    for k in ("m", "g", "Ixx", "Iyy", "Izz"):
        if p[IDX[k]] <= 0:
            raise ParameterError(f"{name}: {k} = {p[IDX[k]]} must be > 0")
    for k in ("c_x", "c_y", "c_z", "c_phi", "c_theta", "c_psi"):
        if p[IDX[k]] < 0:
            raise ParameterError(f"{name}: {k} = {p[IDX[k]]} must be >= 0")
    for k in PARAM_NAMES[:IDX["c_psi"] + 1]:
        lo = 0.0 if k.startswith("c_") else SMALLEST
        if not lo <= p[IDX[k]] <= LARGEST:
            raise ParameterError(f"{name}: {k} = {p[IDX[k]]} is out of scale: expected a "
                                 f"number in [{lo:g}, {LARGEST:g}] (SI units, docs/model.md "
                                 f"sec. 1.4)")
    ratio = inertia_ratio(p)
    if not ratio >= MARGIN:             # NaN (overflow) fails too
        where = (f"{name}: r_G = {p[R_G].tolist()} m is too far from O for m = "
                 f"{p[IDX['m']]:g} kg and I_O = diag("
                 f"{', '.join(f'{v:g}' for v in p[IDX['Ixx']:IDX['Izz'] + 1])})")
        if np.isnan(ratio):
            raise ParameterError(f"{where}: the inertia about the CoG overflows the float "
                                 "range (docs/model.md sec. 1.4)")
        raise ParameterError(
            f"{where}: the inertia about the CoG keeps only {ratio:.3g} of I_O in its weakest "
            f"direction (expected >= {MARGIN:g}, docs/model.md sec. 1.4); the mass matrix M "
            "with this CoG is " + ("not positive definite (no rigid body has it)"
                                   if not ratio > 0 else "nearly singular"))
    return p

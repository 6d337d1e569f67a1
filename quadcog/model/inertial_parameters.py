"""The ten inertial parameters of a rigid body about O, and their physical consistency
(docs/model.md sec. 7).

``pi = [m, m x_G, m y_G, m z_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (kg, kg m, kg m^2): the mass,
the first moment of mass ``h = m r_G`` and the entries of the inertia matrix about O in body
axes (the matrix entries, so ``Ixy`` is ``-integral of x y dm``), in the order of Pinocchio's
``Inertia.toDynamicParameters``. The generated ``inertial_regressor``, ``inertial_mass_matrix``
and ``inertial_dynamics`` take it; the order is read from the contract (derive/contract.py).

pi is additive: mass, first moment and inertia are integrals over the body, so the pi of a
body made of parts is the sum of the parts' pi, all taken about the same point O
(``combine``). A pi is physically consistent, the pi of some rigid body of positive volume,
exactly when its pseudo-inertia matrix is positive definite (Wensing, Kim, Slotine, "Linear
Matrix Inequalities for Physically Consistent Inertial Parameter Identification: A
Statistical Perspective on the Mass Distribution", IEEE RA-L 3(1), 2018; arXiv 2017):

    J = [[Sigma, h], [h^T, m]],   Sigma = 0.5 tr(I_O) I_3 - I_O = integral of r r^T dm.

Its Schur complement is ``Sigma - h h^T / m``, the second moment about the CoG, whose
eigenvalues are ``(I_j + I_k - I_i) / 2`` for the principal inertias ``I_1, I_2, I_3`` about
the CoG: J > 0 exactly when m > 0 and those satisfy the strict triangle inequalities (which
also makes them positive, so the mass matrix M is positive definite).
"""
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike

from quadcog.errors import InputError, ParameterError, PhysicalConsistencyError
from quadcog.model.conventions import CONTRACT, IDX
from quadcog.model.parameters import check_parameters
from quadcog.validate import array, plain, positive, real, vector

__all__ = ["PI_NAMES", "N_PI", "TOLERANCE", "inertial_parameters", "from_inertial_parameters",
           "inertial_arguments", "parallel_axis", "point_mass", "box", "combine",
           "pseudo_inertia", "inertia_about_cog", "is_physically_consistent",
           "check_physically_consistent", "placed", "symmetric_inertia"]

PI_NAMES = CONTRACT.vectors["pi"]
N_PI = len(PI_NAMES)
_M = PI_NAMES.index("m")
_H = [PI_NAMES.index(f"m{a}_G") for a in "xyz"]
# (index in pi, row, column) of each inertia entry, from its name "I" + two axes.
_I = [(k, "xyz".index(n[1]), "xyz".index(n[2])) for k, n in enumerate(PI_NAMES)
      if n.startswith("I")]

# J counts as positive definite when its smallest eigenvalue exceeds TOLERANCE times its
# largest: below that the sign is within the round-off of J's entries.
TOLERANCE = 1e-12


def _shift(m: float, r: np.ndarray) -> np.ndarray:
    """m (|r|^2 I - r r^T): the parallel-axis term (kg m^2) of mass m at r (m)."""
    return m * (r @ r * np.eye(3) - np.outer(r, r))


def _inertia_matrix(pi: np.ndarray) -> np.ndarray:
    I = np.empty((3, 3))
    for k, i, j in _I:
        I[i, j] = I[j, i] = pi[k]
    return I


def symmetric_inertia(value: ArrayLike, where: str) -> np.ndarray:
    """A 3x3 inertia matrix checked to be real, finite and symmetric (to 1e-12 relative).

    Parameters
    ----------
    value : (3, 3) array_like
        The inertia matrix (kg m^2).
    where : str
        Where it came from (an argument, a scenario key), put first in the message.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Its symmetric part, float64.

    Raises
    ------
    InputError
        Not a (3, 3) matrix of finite real numbers, or not symmetric.
    """
    I = array(value, where, (3, 3))
    if not np.allclose(I, I.T, rtol=1e-12, atol=0):
        raise InputError(f"{where}: expected a symmetric 3x3 inertia matrix (kg m^2), got "
                         f"{plain(I.tolist())}")
    return 0.5 * (I + I.T)


def _pi(value: ArrayLike, where: str) -> np.ndarray:
    """pi as a (10,) float array: shape checked (InputError), every entry finite
    (ParameterError naming the entry)."""
    pi = vector(value, where, N_PI, finite=False)
    bad = np.flatnonzero(~np.isfinite(pi))
    if bad.size:
        k = bad[0]
        raise ParameterError(f"{where}[{k}] ({PI_NAMES[k]}) = {plain(pi[k])} is not finite")
    return pi


def inertial_parameters(m: float, r_G: ArrayLike, I_O: ArrayLike,
                        where: str = "inertial_parameters") -> np.ndarray:
    """The ten inertial parameters of a rigid body from its mass, CoG and inertia about O.

    Parameters
    ----------
    m : float
        Mass (kg).
    r_G : array_like, shape (3,)
        Position of the CoG from O in body axes (m).
    I_O : array_like, shape (3, 3)
        Inertia matrix about O in body axes (kg m^2), symmetric.
    where : str, optional
        Name of the caller's value in messages.

    Returns
    -------
    numpy.ndarray, shape (10,)
        ``pi = [m, m r_G, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` (kg, kg m, kg m^2). Not checked for
        physical consistency (``check_physically_consistent`` does that).
    """
    m = real(m, f"{where}: m", unit="kg")
    r = vector(r_G, f"{where}: r_G", 3)
    I = symmetric_inertia(I_O, f"{where}: I_O")
    pi = np.empty(N_PI)
    pi[_M] = m
    pi[_H] = m * r
    for k, i, j in _I:
        pi[k] = I[i, j]
    return pi


def from_inertial_parameters(pi: ArrayLike,
                             where: str = "pi") -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, CoG and inertia about O of the ten inertial parameters ``pi``.

    Parameters
    ----------
    pi : array_like, shape (10,)
        Inertial parameters (kg, kg m, kg m^2); m must be > 0 (r_G = h / m).
    where : str, optional
        Name of the value in messages.

    Returns
    -------
    m : float
        Mass (kg).
    r_G : numpy.ndarray, shape (3,)
        CoG from O in body axes (m).
    I_O : numpy.ndarray, shape (3, 3)
        Inertia matrix about O in body axes (kg m^2).

    Raises
    ------
    PhysicalConsistencyError
        When m <= 0.
    """
    pi = _pi(pi, where)
    m = float(pi[_M])
    if not m > 0:
        raise PhysicalConsistencyError(f"{where}: m = {plain(m)} kg must be > 0 (the CoG "
                                       f"r_G = h / m is not defined)")
    return m, pi[_H] / m, _inertia_matrix(pi)


def inertial_arguments(p: ArrayLike, where: str = "p") -> tuple[np.ndarray, float, np.ndarray]:
    """The arguments ``(pi, g, c)`` of ``inertial_dynamics`` for the paper's 14-entry ``p``.

    The paper's model is the special case ``pi = [m, m r_G, Ixx, 0, Iyy, 0, 0, Izz]`` (I_O
    diagonal and held, whatever r_G is): ``inertial_dynamics(x, U, pi, g, c)`` equals
    ``dynamics(x, U, p)``.

    Parameters
    ----------
    p : array_like, shape (14,)
        An admissible parameter vector (docs/model.md sec. 1.2, 1.4).
    where : str, optional
        Name of the value in messages.

    Returns
    -------
    pi : numpy.ndarray, shape (10,)
        Inertial parameters (kg, kg m, kg m^2).
    g : float
        Gravitational acceleration (m/s^2).
    c : numpy.ndarray, shape (6,)
        Drag coefficients ``[c_x, c_y, c_z]`` (N s/m) and ``[c_phi, c_theta, c_psi]``
        (N m s/rad).
    """
    p = check_parameters(p, where)
    I_O = np.diag(p[IDX["Ixx"]:IDX["Izz"] + 1])
    r_G = p[[IDX["x_G"], IDX["y_G"], IDX["z_G"]]]
    pi = inertial_parameters(p[IDX["m"]], r_G, I_O, where)
    return pi, float(p[IDX["g"]]), p[IDX["c_x"]:IDX["c_psi"] + 1].copy()


def parallel_axis(I_G: ArrayLike, m: float, r: ArrayLike) -> np.ndarray:
    """Inertia about O of a body of mass ``m`` whose CoG is at ``r`` from O (parallel-axis
    theorem): ``I_G + m (|r|^2 I_3 - r r^T)``.

    Parameters
    ----------
    I_G : array_like, shape (3, 3)
        Inertia about the body's own CoG, in body axes (kg m^2), symmetric.
    m : float
        Mass (kg), >= 0.
    r : array_like, shape (3,)
        CoG from O in body axes (m).

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        Inertia about O (kg m^2).
    """
    I_G = symmetric_inertia(I_G, "parallel_axis: I_G")
    m = real(m, "parallel_axis: m", lo=0.0, unit="kg")
    r = vector(r, "parallel_axis: r", 3)
    return I_G + _shift(m, r)


def point_mass(m: float, position: ArrayLike) -> np.ndarray:
    """pi of a point mass.

    Parameters
    ----------
    m : float
        Mass (kg), > 0.
    position : array_like, shape (3,)
        Where it sits, from O in body axes (m).

    Returns
    -------
    numpy.ndarray, shape (10,)
        Its inertial parameters about O. A point mass alone is not physically consistent
        (its pseudo-inertia has rank 1); added to a body of positive volume it is.
    """
    m = positive(m, "point_mass: m", unit="kg")
    r = vector(position, "point_mass: position", 3)
    return inertial_parameters(m, r, _shift(m, r), "point_mass")


def box(m: float, size: ArrayLike, position: ArrayLike) -> np.ndarray:
    """pi of a solid homogeneous box with edges along the body axes.

    Parameters
    ----------
    m : float
        Mass (kg), > 0.
    size : array_like, shape (3,)
        Edge lengths along body x, y, z (m), >= 0.
    position : array_like, shape (3,)
        Its centre (its CoG) from O in body axes (m).

    Returns
    -------
    numpy.ndarray, shape (10,)
        Its inertial parameters about O: inertia about its centre
        ``m / 12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)`` moved to O by ``parallel_axis``.
    """
    m = positive(m, "box: m", unit="kg")
    a, b, c = vector(size, "box: size", 3)
    if min(a, b, c) < 0:
        raise InputError(f"box: size: expected three edge lengths >= 0 (m), got "
                         f"{plain([a, b, c])}")
    r = vector(position, "box: position", 3)
    I_G = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    return inertial_parameters(m, r, parallel_axis(I_G, m, r), "box")


def combine(bodies: Sequence[ArrayLike]) -> np.ndarray:
    """pi of rigid bodies fastened together: the sum of their pi, all about O.

    Parameters
    ----------
    bodies : sequence of array_like, each shape (10,)
        Inertial parameters about the same point O in the same axes (``point_mass``,
        ``box``, a vehicle's pi, ...). Mass, first moment and inertia are integrals over the
        body, so they add.

    Returns
    -------
    numpy.ndarray, shape (10,)
        The combined body's inertial parameters about O (not checked for consistency).
    """
    if isinstance(bodies, np.ndarray) and bodies.ndim == 2:
        bodies = list(bodies)
    if not isinstance(bodies, (list, tuple)) or not bodies:
        raise InputError(f"combine: bodies: expected a non-empty list of (10,) inertial "
                         f"parameter vectors, got {plain(bodies)}")
    return np.sum([_pi(b, f"combine: bodies[{k}]") for k, b in enumerate(bodies)], axis=0)


def pseudo_inertia(pi: ArrayLike) -> np.ndarray:
    """The pseudo-inertia matrix of ``pi`` (Wensing, Kim, Slotine 2017).

    Parameters
    ----------
    pi : array_like, shape (10,)
        Inertial parameters (kg, kg m, kg m^2).

    Returns
    -------
    numpy.ndarray, shape (4, 4)
        ``J = [[0.5 tr(I_O) I_3 - I_O, h], [h^T, m]]``, the second moments of mass
        ``integral of [r; 1][r; 1]^T dm`` about O (kg m^2, kg m, kg). Positive definite
        exactly when ``pi`` is physically consistent.
    """
    pi = _pi(pi, "pi")
    I = _inertia_matrix(pi)
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(I) * np.eye(3) - I
    J[:3, 3] = J[3, :3] = pi[_H]
    J[3, 3] = pi[_M]
    return J


def inertia_about_cog(pi: ArrayLike) -> np.ndarray:
    """Inertia about the CoG of ``pi``: ``I_O - (|h|^2 I_3 - h h^T) / m``.

    Parameters
    ----------
    pi : array_like, shape (10,)
        Inertial parameters; m must be > 0.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        I_G in body axes (kg m^2), the Schur complement of the m I block of M.
    """
    m, r_G, I_O = from_inertial_parameters(pi)
    return I_O - _shift(m, r_G)


def _consistency(pi: np.ndarray) -> tuple[float, np.ndarray, bool]:
    """(smallest eigenvalue of J, all eigenvalues, consistent?) of a finite (10,) pi."""
    eig = np.linalg.eigvalsh(pseudo_inertia(pi))
    return eig[0], eig, bool(eig[0] > TOLERANCE * max(abs(eig[-1]), np.finfo(float).tiny))


def is_physically_consistent(pi: ArrayLike) -> bool:
    """Whether ``pi`` is the inertial parameters of a rigid body of positive volume.

    Parameters
    ----------
    pi : array_like, shape (10,)
        Inertial parameters (kg, kg m, kg m^2).

    Returns
    -------
    bool
        True when the pseudo-inertia matrix is positive definite (its smallest eigenvalue
        above ``TOLERANCE`` times its largest); False also for non-finite entries.
    """
    pi = vector(pi, "pi", N_PI, finite=False)
    return bool(np.isfinite(pi).all()) and _consistency(pi)[2]


def _g(values: Sequence[float] | np.ndarray) -> str:
    return "(" + ", ".join(f"{v:.6g}" for v in values) + ")"


def check_physically_consistent(pi: ArrayLike, where: str = "pi") -> np.ndarray:
    """``pi`` as a float array, or an error that says why no rigid body has it.

    Parameters
    ----------
    pi : array_like, shape (10,)
        Inertial parameters (kg, kg m, kg m^2).
    where : str, optional
        Where the value came from (an argument, a scenario key), put first in the message.

    Returns
    -------
    numpy.ndarray, shape (10,)
        ``pi`` as float64.

    Raises
    ------
    InputError
        Wrong shape or type.
    ParameterError
        A non-finite entry.
    PhysicalConsistencyError
        The pseudo-inertia J is not positive definite; the message gives its smallest
        eigenvalue and the reason: m <= 0, a principal inertia about the CoG <= 0, or the
        principal inertias about the CoG breaking the triangle inequality.
    """
    pi = _pi(pi, where)
    lowest, eig, ok = _consistency(pi)
    if ok:
        return pi
    head = (f"{where} = [{_g(pi)[1:-1]}] is not physically consistent: its "
            f"pseudo-inertia J (Wensing, Kim, Slotine 2017) is not positive definite, smallest "
            f"eigenvalue {lowest:.6g} (eigenvalues {_g(eig)}; expected all > 0, docs/model.md "
            f"sec. 7.2)")
    m = float(pi[_M])
    if not m > 0:
        raise PhysicalConsistencyError(f"{head}: the mass m = {plain(m)} kg is not > 0")
    principal = np.linalg.eigvalsh(inertia_about_cog(pi))
    if not principal[0] > 0:
        raise PhysicalConsistencyError(
            f"{head}: the inertia about the CoG has a principal inertia {principal[0]:.6g} "
            f"kg m^2 <= 0 (principal inertias {_g(principal)} kg m^2; a point mass or a rod "
            f"alone has zero ones: combine it with a body of positive volume)")
    a, b, c = principal
    if not c < a + b:
        raise PhysicalConsistencyError(
            f"{head}: the principal inertias about the CoG {_g(principal)} kg m^2 break the "
            f"triangle inequality, {c:.6g} >= {a:.6g} + {b:.6g} = {a + b:.6g} (no mass "
            f"distribution has a largest principal inertia as large as the sum of the other "
            f"two)")
    # Within round-off of the rim: J is only semidefinite to working precision.
    raise PhysicalConsistencyError(f"{head}: the mass distribution is flat (on a plane, a "
                                   f"line or a point) to working precision")


def placed(m: float, I_G: ArrayLike, positions: ArrayLike) -> np.ndarray:
    """pi about O of one body placed with its CoG at many positions (vectorized).

    Parameters
    ----------
    m : float
        Its mass (kg), > 0.
    I_G : array_like, shape (3, 3)
        Its inertia about its CoG in body axes (kg m^2), symmetric.
    positions : array_like, shape (N, 3)
        Where its CoG is, from O in body axes (m), one row per placement.

    Returns
    -------
    numpy.ndarray, shape (N, 10)
        One pi per row: ``[m, m r, I_G + m (|r|^2 I_3 - r r^T)]`` in ``PI_NAMES`` order (the
        parallel-axis theorem).
    """
    m = positive(m, "placed: m", unit="kg")
    I_G = symmetric_inertia(I_G, "placed: I_G")
    r = array(positions, "placed: positions", (None, 3))
    out = np.empty((r.shape[0], N_PI))
    out[:, _M] = m
    out[:, _H] = m * r
    r2 = np.einsum("ni,ni->n", r, r)
    for k, i, j in _I:
        out[:, k] = I_G[i, j] + m * ((r2 if i == j else 0.0) - r[:, i] * r[:, j])
    return out

"""Parameter vectors p (the 14 entries of the generated functions, order: docs/model.md sec.
1.2) and their admissibility check (sec. 1.4). The vehicle they come from is
``quadcog.vehicle.Vehicle``."""
import numpy as np

from .conventions import IDX, N_PARAM, PARAM_NAMES, R_G
from .errors import InputError, ParameterError

def with_cog(p, r_G):
    """A copy of ``p`` (14,) with the CoG offset replaced by ``r_G`` (3,), in m."""
    p = np.array(p, dtype=float)
    p[R_G] = r_G
    return p


def inertia_about_cog(p):
    """I_G = I_O - m (|r_G|^2 I - r_G r_G^T), 3x3 in kg m^2."""
    p = np.asarray(p, dtype=float)
    r = p[R_G]
    return np.diag(p[IDX["Ixx"]:IDX["Izz"] + 1]) - p[IDX["m"]] * (r @ r * np.eye(3) - np.outer(r, r))


def check_parameters(p, name="p"):
    """Raise ParameterError unless ``p`` is an admissible (14,) parameter vector."""
    p = np.asarray(p, dtype=float)
    if p.shape not in ((N_PARAM,), (N_PARAM, 1)):
        raise InputError(f"{name} must have shape ({N_PARAM},) ordered {PARAM_NAMES}, "
                         f"got shape {p.shape}")
    p = p.reshape(-1)
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
    eig = np.linalg.eigvalsh(inertia_about_cog(p))
    if eig[0] <= 0:
        raise ParameterError(
            f"{name}: r_G = {p[R_G].tolist()} m is too far from O for m = {p[IDX['m']]:g} kg and "
            f"I_O = diag({', '.join(f'{v:g}' for v in p[IDX['Ixx']:IDX['Izz'] + 1])}): the "
            f"inertia about the CoG has "
            f"eigenvalue {eig[0]:.3g} (expected > 0), so M is not positive definite")
    return p

"""Parameter vectors p (order: docs/model.md sec. 1.2), the default vehicle (sec. 6), and
admissibility checks (sec. 1.4)."""
import numpy as np

from .conventions import IDX, N_PARAM, PARAM_NAMES, R_G
from .errors import InputError, ParameterError

# AscTec Hummingbird as in the ETH RotorS simulator (docs/model.md sec. 6). The drag
# coefficients are this project's own choice (the paper gives no numbers): small linear
# drag, so that the zero dynamics decay slowly (c_x / m = 0.15 1/s).
HUMMINGBIRD = {
    "m": 0.68, "g": 9.81, "Ixx": 0.007, "Iyy": 0.007, "Izz": 0.012,
    "c_x": 0.1, "c_y": 0.1, "c_z": 0.1, "c_phi": 0.001, "c_theta": 0.001, "c_psi": 0.001,
    "x_G": 0.0, "y_G": 0.0, "z_G": 0.0,
}
ARM_LENGTH = 0.17                  # m, "+" layout
THRUST_CONSTANT = 8.54858e-6       # N / (rad/s)^2
MOMENT_CONSTANT = 0.016            # m (rotor drag moment = MOMENT_CONSTANT * thrust)
MAX_ROTOR_SPEED = 838.0            # rad/s


def default_parameters(**overrides):
    """The default vehicle as a (14,) array, with entries replaced by name.

    Example: ``default_parameters(x_G=0.03, m=0.8)``. Unknown names raise InputError.
    """
    values = dict(HUMMINGBIRD)
    for name, value in overrides.items():
        if name not in values:
            raise InputError(f"unknown parameter {name!r}; expected one of {PARAM_NAMES}")
        values[name] = float(value)
    p = np.array([values[n] for n in PARAM_NAMES], dtype=float)
    check_parameters(p)
    return p


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

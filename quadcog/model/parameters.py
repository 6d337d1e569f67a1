"""Parameter vectors p (the 14 entries of the generated functions, order: docs/model.md sec.
1.2) and their admissibility check (sec. 1.4). The vehicle they come from is
``quadcog.vehicles.vehicle.Vehicle``."""
import numpy as np

from quadcog.model.admissibility import LARGEST, MARGIN, SMALLEST, inertia_about_cog, inertia_ratio
from quadcog.model.conventions import IDX, N_PARAM, PARAM_NAMES, R_G
from quadcog.errors import ParameterError
from quadcog.validate import vector


def with_cog(p, r_G):
    """A copy of ``p`` (14,) with the CoG offset replaced by ``r_G`` (3,), in m."""
    p = np.array(p, dtype=float)
    p[R_G] = r_G
    return p


def check_parameters(p, name="p"):
    """Raise ParameterError unless ``p`` is an admissible (14,) parameter vector (docs/model.md
    sec. 1.4; the margin is ``quadcog.model.admissibility.MARGIN``); returns it as a float array."""
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
        raise ParameterError(
            f"{name}: r_G = {p[R_G].tolist()} m is too far from O for m = {p[IDX['m']]:g} kg and "
            f"I_O = diag({', '.join(f'{v:g}' for v in p[IDX['Ixx']:IDX['Izz'] + 1])}): the "
            f"inertia about the CoG keeps only {ratio:.3g} of I_O in its weakest direction "
            f"(expected >= {MARGIN:g}, docs/model.md sec. 1.4); M is "
            + ("not positive definite" if not ratio > 0 else "nearly singular"))
    return p

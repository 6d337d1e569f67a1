"""Use an identification: its CoG seeds a controller's estimate and sets a vehicle's CoG.

``identified_cog(source)`` reads the r_G of an ``Identification`` or of the JSON that
``quadcog identify --json`` writes. ``Vehicle.with_cog(identified_cog(...))`` is then the
vehicle as identified; given to a controller as its model, it is where the adaptive laws start
their estimate (``AdaptiveFeedbackLinearization.initial_state``: r_hat(0) is the model's r_G).
Scenario files say ``[vehicle] identified = "file.json"`` (the truth) or ``[controller_model]
identified = "file.json"`` (the seed); ``quadcog run SCENARIO --identified FILE`` sets both.
"""
import json
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from quadcog.errors import IdentificationError

if TYPE_CHECKING:
    from quadcog.identification.core import Identification

__all__ = ["identified_cog"]


def identified_cog(source: "Identification | str | Path") -> npt.NDArray[np.float64]:
    """The CoG offset r_G (3,) (m, body frame) of an identification.

    Parameters
    ----------
    source : Identification, str or Path
        A result of ``quadcog.identify`` or the JSON file of ``quadcog identify --json``
        (keys ``quadcog.identification.JSON_KEYS``).

    Returns
    -------
    numpy.ndarray, shape (3,)
        r_G (m). With a baseline it is the shift relative to the baseline flights.

    Raises
    ------
    IdentificationError
        A file that cannot be read, is not JSON, or lacks a ``r_G`` of 3 finite numbers.
    """
    from quadcog.identification.core import Identification
    if isinstance(source, Identification):
        return np.array(source.r_G, dtype=float)
    path = Path(source)
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except OSError as e:
        raise IdentificationError(f"{path}: cannot read the identification ({e.strerror})") \
            from None
    except (json.JSONDecodeError, UnicodeDecodeError) as e:
        raise IdentificationError(f"{path}: not the JSON of `quadcog identify --json` ({e})") \
            from None
    r = data.get("r_G") if isinstance(data, dict) else None
    ok = (isinstance(r, list) and len(r) == 3 and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v) for v in r))
    if not ok:
        raise IdentificationError(f"{path}: key 'r_G': expected 3 finite numbers (m), got "
                                  f"{r!r}")
    return np.array(r, dtype=float)

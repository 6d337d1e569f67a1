"""Use an identification: its CoG seeds a controller's estimate and sets a vehicle's CoG.

``identified_cog(source)`` reads the r_G of an ``Identification`` or of the JSON that
``quadcog identify --json`` writes. ``Vehicle.with_cog(identified_cog(...))`` is then the
vehicle as identified; given to a controller as its model, it is where the adaptive laws start
their estimate (``AdaptiveFeedbackLinearization.initial_state``: r_hat(0) is the model's r_G).
Scenario files say ``[vehicle] identified = "file.json"`` (the truth) or ``[controller_model]
identified = "file.json"`` (the seed); ``quadcog run SCENARIO --identified FILE`` sets both.
"""
import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from quadcog.errors import IdentificationError
from quadcog.files import read_json
from quadcog.model.parameters import LARGEST
from quadcog.validate import fail, real, vector

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
        A file that cannot be read, is not JSON, lacks a ``r_G`` of 3 finite numbers, or
        holds a ``mass`` that no vehicle has (not a number in (0, ``LARGEST``] kg; null or
        absent is accepted: only r_G is used, but a file with an impossible mass is not an
        identification to trust).
    """
    from quadcog.identification.core import Identification
    if isinstance(source, Identification):
        return np.array(source.r_G, dtype=float)
    if isinstance(source, bytes) or not isinstance(source, (str, os.PathLike)) or not str(source):
        # "" too: Path("") is the current folder, which would be named '.'
        fail("identified_cog", "an Identification or the path of the JSON of `quadcog "
             "identify --json`", source, IdentificationError)
    path = Path(source)
    if path.is_dir():
        raise IdentificationError(f"{path}: is a folder; expected the JSON file of `quadcog "
                                  "identify --json`")
    data = read_json(path, "identification (the JSON of `quadcog identify --json`)",
                     IdentificationError)
    r = data.get("r_G") if isinstance(data, dict) else None
    where, what = f"{path}: key 'r_G'", "3 finite numbers (m)"
    # a JSON list of 3 numbers, as `quadcog identify --json` writes: a column [[x], [y], [z]]
    # (which vector() takes from Python) is not that file's shape
    if not isinstance(r, list) or any(isinstance(v, (list, dict)) for v in r):
        fail(where, what, r, IdentificationError)
    try:
        r_G = vector(r, where, 3, error=IdentificationError)
    except IdentificationError:
        fail(where, what, r, IdentificationError)
    if not np.abs(r_G).max() <= LARGEST:
        fail(where, f"3 numbers within +-{LARGEST:g} m", r, IdentificationError)
    mass = data.get("mass")
    if mass is not None:
        # within the model's scale, as every vehicle's mass (a mass of 1e300 kg was accepted)
        real(mass, f"{path}: key 'mass'", lo=0.0, lo_open=True, hi=LARGEST, unit="kg",
             error=IdentificationError)
    return r_G

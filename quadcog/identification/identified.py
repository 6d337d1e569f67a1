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
from quadcog.validate import fail

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
        A file that cannot be read, is not JSON, is not an object, repeats a key (JSON
        keeps only the last: which one was meant?), lacks a ``r_G`` of 3 finite numbers
        within +-LARGEST m, or holds another key of ``JSON_KEYS`` that no identification has
        (checked as ``Identification`` checks its fields: a ``mass`` not in (0, LARGEST]
        kg, a negative half-width, ...; null or absent is accepted: only r_G is used, but a
        file with an impossible value is not an identification to trust).
    """
    from quadcog.identification.core import JSON_CHECKS, Identification
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
    what = "identification (the JSON of `quadcog identify --json`)"
    data = read_json(path, what, IdentificationError)
    if not isinstance(data, dict):
        fail(f"{path}", f"the {what}: an object with the key 'r_G'", data, IdentificationError)
    # a JSON list of 3 numbers, as `quadcog identify --json` writes (not a column [[x], [y],
    # [z]]), within the model's scale: the r_G of an Identification
    r_G = JSON_CHECKS["r_G"](data.get("r_G"), f"{path}: key 'r_G'")
    for key, check in JSON_CHECKS.items():
        if key != "r_G" and data.get(key) is not None:
            check(data[key], f"{path}: key {key!r}")
    return np.array(r_G, dtype=float)


"""Which flights of a sweep fly in one batch, and the controller each batch shares.

Flights that differ only in their truth CoG fly together through the vector kernel; the
controller of such a group is designed once per process (while the sweep file is validated, so
that a design the controller refuses is an error before any flight, and again in each worker).
"""
import copy
import json
from typing import Any

__all__ = ["CONTROLLERS_BY_GROUP", "group_key"]

CONTROLLERS_BY_GROUP: dict[str, Any] = {}       # group key -> controller, per process


def group_key(data: dict[str, Any]) -> str:
    """What flights must share to fly in one batch: all but the truth CoG.

    Parameters
    ----------
    data : dict
        A flight's parsed scenario.

    Returns
    -------
    str
        The scenario without the vehicle's x_G, y_G, z_G and the ``r`` of each CoG change, as
        canonical JSON.
    """
    d = copy.deepcopy(data)
    for k in ("x_G", "y_G", "z_G"):
        d.get("vehicle", {}).pop(k, None)
    for change in d.get("cog", []):
        change.pop("r", None)
    return json.dumps(d, sort_keys=True)

"""PX4 in the loop: PX4's estimator and controllers fly quadcog's truth plant in lockstep
(docs/px4.md). ``fly`` flies a scenario; ``quadcog.px4.tree`` finds and builds PX4."""
from quadcog.px4.flight import Px4Flight, fly, mission_of, write_px4_outputs
from quadcog.px4.mission import Mission, Waypoint

__all__ = ["fly", "Px4Flight", "Mission", "Waypoint", "mission_of", "write_px4_outputs",
           "scenario_path"]


def scenario_path(name: str) -> str:
    """A PX4 scenario shipped with quadcog.px4 (``px4-hover``, ``px4-payload``,
    ``px4-mission``, ``px4-cog-step``), or ``name``.

    Parameters
    ----------
    name : str
        A shipped PX4 scenario's name, or any scenario name or file.

    Returns
    -------
    str
        The shipped file's path, else ``name`` unchanged.
    """
    from pathlib import Path
    shipped = Path(__file__).resolve().parent / "scenarios" / f"{name}.toml"
    return str(shipped) if shipped.is_file() else name

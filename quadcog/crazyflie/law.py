"""A quadcog law in the firmware loop: its out-of-tree app (``write_crazyflie_app``) written
for the vehicle flown into the cache, and the folder of the app's C that the host compiles.

``simulate(controller="composite", ...)`` flies the app's float32 C exactly as the firmware
would call it: ``controllerOutOfTree`` every tick (the app runs the law on the 500 Hz ticks),
its ``controlModeForceTorque`` command through the firmware's ``powerDistributionForceTorque``,
capping, battery compensation and thrust map. The law is designed, as ``quadcog.simulate``
designs it by default, for the airframe of the vehicle flown with its CoG at the geometric
centre: it knows neither the CoG offset nor what the vehicle carries.
"""
import hashlib
import os
from pathlib import Path
import shutil
import tempfile

import numpy as np

from quadcog.controllers.registry import CONTROLLERS as LAWS
from quadcog.embedded.crazyflie_app import write_crazyflie_app
from quadcog.paths import cache_dir
from quadcog.vehicles.vehicle import Vehicle

__all__ = ["LAWS", "APP_TASK", "law_model", "law_sources"]

APP_TASK = "quadcog_cf_app.c"      # the app's FreeRTOS task: the firmware's, not the host's


def law_model(vehicle: Vehicle) -> Vehicle:
    """What the law is designed for: ``quadcog.simulate``'s default ``controller_model``.

    Parameters
    ----------
    vehicle : Vehicle
        The vehicle flown.

    Returns
    -------
    Vehicle
        Its airframe with the CoG at the geometric centre.
    """
    return vehicle.airframe.with_cog(np.zeros(3))


def _digest(folder: Path) -> str:
    h = hashlib.sha256()
    for p in sorted(folder.rglob("*")):
        if p.is_file():
            h.update(str(p.relative_to(folder)).encode() + b"\0" + p.read_bytes() + b"\0")
    return h.hexdigest()[:16]


def law_sources(name: str, vehicle: Vehicle) -> Path:
    """Write the law's app for ``vehicle`` into the cache; the folder of its host C.

    Parameters
    ----------
    name : str
        A key of ``quadcog.controllers.CONTROLLERS``.
    vehicle : Vehicle
        The vehicle flown (the law is designed for ``law_model(vehicle)``).

    Returns
    -------
    pathlib.Path
        ``<cache>/crazyflie/laws/<name>-<hash>/host``: the app's ``src/`` C and headers but
        the app task (``APP_TASK``), which needs FreeRTOS; the whole app is beside it in
        ``app/`` (build it into ``cf2.elf`` with ``quadcog.embedded.crazyflie_firmware``).

    Raises
    ------
    quadcog.errors.ExportError
        As ``write_crazyflie_app``.
    """
    root = cache_dir() / "crazyflie" / "laws"
    root.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}-", dir=root))
    try:
        write_crazyflie_app(name, tmp / "app", vehicle=law_model(vehicle),
                            command=f"quadcog.crazyflie.simulate({name!r})")
        host = tmp / "host"
        host.mkdir()
        for f in sorted((tmp / "app" / "src").iterdir()):
            if f.suffix in (".c", ".h") and f.name != APP_TASK:
                shutil.copy2(f, host / f.name)
        final = root / f"{name}-{_digest(tmp)}"
        if not final.is_dir():
            try:
                os.rename(tmp, final)
            except OSError:             # another process was first
                if not final.is_dir():
                    raise
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    return final / "host"

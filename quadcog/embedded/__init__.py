"""The controllers as self-contained C99 modules (float32 or double) for a flight controller,
and the tools that check them on a Cortex-M4 in QEMU (``make embedded``); the laws as
out-of-tree controller apps of the Crazyflie firmware (``crazyflie_app``, built by
``crazyflie_firmware``, checked by ``crazyflie_host`` and ``make crazyflie-app``)."""
from quadcog.embedded.controller_export import export_controller, render, short_name, step_function
from quadcog.embedded.emit import PRECISIONS
from quadcog.errors import ExportError

__all__ = ["PRECISIONS", "ExportError", "export_controller", "render", "short_name",
           "step_function"]

"""Layer stacks: the Crazyflie firmware's own controllers, power distribution, thrust map and
battery compensation, built from a firmware tree (``firmware``) and flown in quadcog's truth
plant at the firmware's rates (``loop.simulate``)."""
from quadcog.crazyflie.firmware import CONTROLLERS, PROPELLERS, build_firmware, constants, firmware_tree
from quadcog.crazyflie.loop import DEFAULT_LOG, simulate
from quadcog.crazyflie.scenario import run_scenario
from quadcog.sweeps.flights import register_stack

register_stack("crazyflie", run_scenario)     # sweeps fly scenarios with [stack] name = "crazyflie"

__all__ = ["CONTROLLERS", "PROPELLERS", "DEFAULT_LOG", "build_firmware", "constants",
           "firmware_tree", "simulate"]

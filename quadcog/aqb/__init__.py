"""AdaptiveQuadBench, the peer suite: its set-up, quadcog's laws as its controllers, and its
payload protocol on quadcog's physically consistent payload model (docs/aqb.md)."""
from quadcog.aqb.adapter import AQB_NAMES, QuadcogAQBController, aqb_controller_factory
from quadcog.aqb.convert import reference_row, state_vector, vehicle_from_quad_params
from quadcog.aqb.install import prepare, require_aqb

__all__ = ["AQB_NAMES", "QuadcogAQBController", "aqb_controller_factory", "reference_row",
           "state_vector", "vehicle_from_quad_params", "prepare", "require_aqb"]

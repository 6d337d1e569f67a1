"""Layer 5, controllers: the paper's three (cascade PD, feedback linearization, the adaptive
law) and three beyond it (feedback linearization with integral action, the composite adaptive
law, and the payload law that learns the mass with the CoG) and the geometric law on SE(3)
that flies past the Euler angles' reach, each a CasADi law, a compiled
call and a Python object. ``registry`` is the one table of them by short name; ``template``
states the interface a controller of your own implements."""
from quadcog.controllers.adaptive import AdaptiveFeedbackLinearization
from quadcog.controllers.base import Controller
from quadcog.controllers.cascade_pd import CascadePD
from quadcog.controllers.composite import CompositeAdaptive
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.controllers.fl_integral import FeedbackLinearizationIntegral
from quadcog.controllers.geometric import GeometricAdaptive
from quadcog.controllers.payload_adaptive import PayloadAdaptive
from quadcog.controllers.registry import CONTROLLERS, make_controller

BY_NAME = CONTROLLERS          # the name of earlier releases

__all__ = ["AdaptiveFeedbackLinearization", "BY_NAME", "CONTROLLERS", "CascadePD",
           "CompositeAdaptive", "Controller", "FeedbackLinearization",
           "FeedbackLinearizationIntegral", "PayloadAdaptive", "make_controller"]
__all__ += ["GeometricAdaptive"]

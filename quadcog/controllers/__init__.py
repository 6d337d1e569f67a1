"""The paper's three controllers and two beyond it (feedback linearization with integral action,
the composite adaptive law), each a CasADi law, a compiled call and a Python object."""
from quadcog.controllers.adaptive import AdaptiveFeedbackLinearization
from quadcog.controllers.base import Controller
from quadcog.controllers.cascade_pd import CascadePD
from quadcog.controllers.composite import CompositeAdaptive
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.controllers.fl_integral import FeedbackLinearizationIntegral

BY_NAME = {"pd": CascadePD, "fl": FeedbackLinearization, "adaptive": AdaptiveFeedbackLinearization,
           "fl_integral": FeedbackLinearizationIntegral, "composite": CompositeAdaptive}


def make_controller(kind, **params):
    """A controller by short name ('pd', 'fl', 'adaptive', 'fl_integral', 'composite') with
    keyword parameters."""
    from quadcog.errors import InputError
    if kind not in BY_NAME:
        raise InputError(f"unknown controller {kind!r}; expected one of {tuple(BY_NAME)}")
    return BY_NAME[kind](**params)

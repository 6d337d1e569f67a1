"""The paper's three controllers and two beyond it (feedback linearization with integral action,
the composite adaptive law), each a CasADi law, a compiled call and a Python object."""
from .adaptive import AdaptiveFeedbackLinearization
from .base import Controller
from .cascade_pd import CascadePD
from .composite import CompositeAdaptive
from .feedback_linearization import FeedbackLinearization
from .fl_integral import FeedbackLinearizationIntegral

BY_NAME = {"pd": CascadePD, "fl": FeedbackLinearization, "adaptive": AdaptiveFeedbackLinearization,
           "fl_integral": FeedbackLinearizationIntegral, "composite": CompositeAdaptive}


def make_controller(kind, **params):
    """A controller by short name ('pd', 'fl', 'adaptive', 'fl_integral', 'composite') with
    keyword parameters."""
    from ..errors import InputError
    if kind not in BY_NAME:
        raise InputError(f"unknown controller {kind!r}; expected one of {tuple(BY_NAME)}")
    return BY_NAME[kind](**params)

"""The one table of controllers by short name, and their settings read from the constructors.

The scenario schema, ``--set``, sweep keys, the embedded export and the studies take the names
and the settings of the controllers from here; nothing else lists them.
"""
from typing import Any

from quadcog import validate
from quadcog.controllers.adaptive import AdaptiveFeedbackLinearization
from quadcog.controllers.base import Controller
from quadcog.controllers.cascade_pd import CascadePD
from quadcog.controllers.composite import CompositeAdaptive
from quadcog.controllers.feedback_linearization import FeedbackLinearization
from quadcog.controllers.fl_integral import FeedbackLinearizationIntegral
from quadcog.controllers.geometric import GeometricAdaptive
from quadcog.controllers.payload_adaptive import PayloadAdaptive
from quadcog.kinds import Kind, settings_of

__all__ = ["CONTROLLERS", "controller_names", "controller_settings", "make_controller"]

CONTROLLERS: dict[str, type[Controller]] = {
    "pd": CascadePD,
    "fl": FeedbackLinearization,
    "adaptive": AdaptiveFeedbackLinearization,
    "fl_integral": FeedbackLinearizationIntegral,
    "composite": CompositeAdaptive,
    "payload_adaptive": PayloadAdaptive,
    "geometric": GeometricAdaptive,
}


def controller_names() -> tuple[str, ...]:
    """The short names of the controllers.

    Returns
    -------
    tuple of str
        In the order of ``CONTROLLERS``.
    """
    return tuple(CONTROLLERS)


def controller_settings(name: str) -> dict[str, Kind]:
    """The settings a controller's constructor takes, with the kind of value of each.

    Parameters
    ----------
    name : str
        A short name of ``CONTROLLERS``.

    Returns
    -------
    dict of str to quadcog.kinds.Kind
        {setting: kind}, read from the annotated keyword arguments of the constructor (and of
        its base classes); ``vehicle`` and ``model`` are not settings.

    Raises
    ------
    quadcog.InputError
        When ``name`` is not a controller's short name.
    """
    validate.choice(name, "controller", controller_names())
    return settings_of(CONTROLLERS[name], skip=("vehicle", "model"))


def make_controller(kind: str, **params: Any) -> Controller:
    """A controller by short name with keyword settings.

    Parameters
    ----------
    kind : str
        A short name of ``CONTROLLERS`` ('pd', 'fl', 'adaptive', 'fl_integral',
        'composite', 'payload_adaptive', 'geometric').
    **params
        The constructor's keyword arguments (``vehicle``, ``model`` and the settings).

    Returns
    -------
    quadcog.Controller
        The controller, designed for ``params['vehicle']`` (default: the Hummingbird).

    Raises
    ------
    quadcog.InputError
        When ``kind`` is unknown or a setting is refused by the constructor.
    """
    validate.choice(kind, "controller", controller_names())
    return CONTROLLERS[kind](**params)

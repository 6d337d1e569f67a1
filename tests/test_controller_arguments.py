"""Every controller refuses a ``model`` that is not a quadcog Model, and a ``vehicle`` that is
not a Vehicle, when it is made: ``model="abc"`` was kept and failed at the first flight with
AttributeError ('str' object has no attribute 'folder'), CascadePD raised AttributeError at
once, and a falsy one (``0``, ``""``) was replaced by ``quadcog.load()`` in silence."""
import numpy as np
import pytest

from quadcog import InputError
from quadcog.controllers.registry import CONTROLLERS
from quadcog.model.functions import load


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
@pytest.mark.parametrize("model", ["abc", 0, "", np.ones(3), {}, b"model"],
                         ids=["str", "zero", "empty", "array", "dict", "bytes"])
def test_a_model_that_is_not_a_model_is_refused(name, model):
    with pytest.raises(InputError, match=r"^model: expected a quadcog Model"):
        CONTROLLERS[name](model=model)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_a_vehicle_that_is_not_a_vehicle_is_refused_in_plain_words(name):
    with pytest.raises(InputError, match=r"^vehicle: expected a quadcog Vehicle .*, got "
                                         r"an array of shape \(14,\) and dtype float64$"):
        CONTROLLERS[name](vehicle=np.ones(14))


def test_the_model_given_is_the_model_used():
    model = load()
    for name in sorted(CONTROLLERS):
        assert CONTROLLERS[name](model=model).model is model

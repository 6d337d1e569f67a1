"""quadcog: a quadrotor whose centre of gravity moves, as verified, compiled code.

``quadcog.load()`` gives the generated functions (``dynamics``, ``mass_matrix``,
``coriolis``, ``damping``, ``gravity``, ``regressor``, ``decoupling``, ``drift``,
``linearization``) as fast numpy callables. This package never imports SymPy.
"""
from .conventions import FUNCTIONS, INPUT_NAMES, OUTPUT_NAMES, PARAM_NAMES, STATE_NAMES
from .errors import (CompileError, GeneratedFilesError, InputError, ParameterError,
                     QuadcogError, QuadcogWarning)
from .model import Linearization, Model, load
from .params import (ARM_LENGTH, HUMMINGBIRD, check_parameters, default_parameters,
                     inertia_about_cog, with_cog)

__version__ = "0.1.0"

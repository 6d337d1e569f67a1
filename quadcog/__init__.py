"""quadcog: a quadrotor whose centre of gravity moves, as verified, compiled code.

``quadcog.load()`` gives the generated functions (``dynamics``, ``mass_matrix``,
``coriolis``, ``damping``, ``gravity``, ``regressor``, ``decoupling``, ``drift``,
``linearization``) as fast numpy callables. This package never imports SymPy.
"""
from . import config
from .catalog import scenario_names, scenario_path, shipped_scenarios
from .conventions import (B_U, FUNCTIONS, INPUT_NAMES, OUTPUT_NAMES, OUTPUT_ROWS, PARAM_NAMES,
                          STATE_NAMES, hover_trim, rotation_matrix)
from .errors import (CompileError, EulerSingularityError, GeneratedFilesError, InputError,
                     ParameterError, QuadcogError, QuadcogWarning)
from .model import Linearization, Model, load
from .params import check_parameters, inertia_about_cog, with_cog
from .vehicle import (CRAZYFLIE, HUMMINGBIRD, Vehicle, default_parameters, plus_layout,
                      x_layout)
from .controllers import (AdaptiveFeedbackLinearization, CascadePD, CompositeAdaptive,
                          Controller, FeedbackLinearization, FeedbackLinearizationIntegral,
                          make_controller)
from .plant import TruthOptions
from .sensing import Sensed, Sensing
from .result import Metrics, SimulationResult
from .batch import BatchResult, simulate_batch
from .divergence import DivergenceCause, Limits
from .simulation import simulate
from .sweeps import sweep
from .timeline import CogChange, CogProfile, Disturbance
from .trajectory import Circle, Figure8, FromCallable, Helix, Hover, Trajectory
from .identification import Identification, identify

__version__ = "0.1.0"

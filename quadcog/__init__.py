"""quadcog: a quadrotor whose centre of gravity moves, as verified, compiled code.

``quadcog.load()`` gives the generated functions (``dynamics``, ``mass_matrix``,
``coriolis``, ``damping``, ``gravity``, ``regressor``, ``decoupling``, ``drift``,
``linearization``) as fast numpy callables. This package never imports SymPy.
"""
import quadcog._startup  # noqa: F401, I001  (first, before the heavy imports: Ctrl-C while starting)
from quadcog import config  # noqa: I001  (config imports validate, hence numpy)
from quadcog.controllers import (
                                 AdaptiveFeedbackLinearization,
                                 CascadePD,
                                 CompositeAdaptive,
                                 Controller,
                                 FeedbackLinearization,
                                 FeedbackLinearizationIntegral,
                                 PayloadAdaptive,
                                 make_controller,
)
from quadcog.errors import (
                                 CompileError,
                                 EulerSingularityError,
                                 GeneratedFilesError,
                                 InputError,
                                 ParameterError,
                                 PhysicalConsistencyError,
                                 QuadcogError,
                                 QuadcogWarning,
)
from quadcog.identification import Identification, identify
from quadcog.model.conventions import (
                                 B_U,
                                 FUNCTIONS,
                                 INPUT_NAMES,
                                 OUTPUT_NAMES,
                                 OUTPUT_ROWS,
                                 PARAM_NAMES,
                                 STATE_NAMES,
                                 hover_trim,
                                 rotation_matrix,
)
from quadcog.model.functions import Linearization, Model, load
from quadcog.model.parameters import check_parameters, inertia_about_cog, with_cog
from quadcog.scenarios.lookup import scenario_names, scenario_path, shipped_scenarios
from quadcog.sim.batch import BatchResult, simulate_batch
from quadcog.sim.divergence import DivergenceCause, Limits
from quadcog.sim.flight import simulate
from quadcog.sim.plant import TruthOptions
from quadcog.sim.result import Metrics, SimulationResult
from quadcog.sim.sensing import Sensed, Sensing
from quadcog.sim.timeline import CogChange, CogProfile, Disturbance
from quadcog.sweeps import sweep
from quadcog.trajectories.analytic import Circle, Figure8, FromCallable, Helix, Hover, Trajectory
from quadcog.vehicles import CRAZYFLIE, HUMMINGBIRD, X500, Vehicle
from quadcog.vehicles.vehicle import default_parameters, plus_layout, x_layout

__version__ = "0.1.0"

__all__ = [
    "config", "scenario_names", "scenario_path", "shipped_scenarios", "B_U", "FUNCTIONS",
    "INPUT_NAMES", "OUTPUT_NAMES", "OUTPUT_ROWS", "PARAM_NAMES", "STATE_NAMES", "hover_trim",
    "rotation_matrix", "CompileError", "EulerSingularityError", "GeneratedFilesError",
    "InputError", "ParameterError", "PhysicalConsistencyError", "QuadcogError", "QuadcogWarning",
    "Linearization", "Model",
    "load", "check_parameters", "inertia_about_cog", "with_cog", "CRAZYFLIE", "HUMMINGBIRD", "X500",
    "Vehicle", "default_parameters", "plus_layout", "x_layout", "AdaptiveFeedbackLinearization",
    "CascadePD", "CompositeAdaptive", "Controller", "FeedbackLinearization", "PayloadAdaptive",
    "FeedbackLinearizationIntegral", "make_controller", "TruthOptions", "Sensed", "Sensing",
    "Metrics", "SimulationResult", "BatchResult", "simulate_batch", "DivergenceCause", "Limits",
    "simulate", "sweep", "CogChange", "CogProfile", "Disturbance", "Circle", "Figure8",
    "FromCallable", "Helix", "Hover", "Trajectory", "Identification", "identify", "__version__",
]

"""A scenario with a ``[stack]`` table flown by the Crazyflie firmware: what ``quadcog run``
(``--stack crazyflie --controller pid``, or the scenario's own table) calls."""
from typing import Any

import numpy as np

from quadcog.crazyflie.loop import simulate
from quadcog.errors import InputError, ScenarioError, StackError
from quadcog.scenarios.scenario import Scenario
from quadcog.sim.prepare import start_at_reference
from quadcog.sim.result import SimulationResult

__all__ = ["run_scenario"]


def run_scenario(scenario: Scenario) -> SimulationResult:
    """Fly a scenario's reference, vehicle, CoG, payload, disturbance, truth, sensing and
    limits with the firmware controller its ``[stack]`` table names.

    Parameters
    ----------
    scenario : Scenario
        A loaded scenario with ``stack = {"name": "crazyflie", "controller": ...}``
        (controller default ``"pid"``; ``propellers``, ``battery_voltage`` optional).

    Returns
    -------
    SimulationResult
        As ``quadcog.crazyflie.simulate``'s; ``info["scenario"]`` is the scenario's name.

    Raises
    ------
    quadcog.ScenarioError
        A stack other than the Crazyflie's, or a setting the loop refuses (named with the
        scenario's file); a StackError (no firmware tree, a failed build) passes as it is.
    """
    stack: dict[str, Any] = dict(scenario.stack)
    if stack.get("name") != "crazyflie":
        raise ScenarioError(f"{scenario.source}: key 'stack.name': expected 'crazyflie', got "
                            f"{stack.get('name')!r}")
    x0 = None
    if any(scenario.initial_offset):
        x0 = start_at_reference(scenario.trajectory(0.0))
        x0[:3] += np.asarray(scenario.initial_offset)
    options = {k: stack[k] for k in ("propellers", "battery_voltage") if k in stack}
    try:
        result = simulate(stack.get("controller", "pid"), scenario.trajectory,
                          scenario.duration, vehicle=scenario.vehicle, cog=scenario.cog,
                          payloads=scenario.payloads, disturbances=scenario.disturbances,
                          truth=scenario.truth, x0=x0, limits=scenario.limits,
                          sensing=scenario.sensing, **options)
    except StackError:
        raise
    except InputError as e:     # the message names the argument or key it is about
        raise ScenarioError(f"{scenario.source}: {e}") from None
    result.info["scenario"] = scenario.name
    return result

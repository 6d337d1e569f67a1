"""The layers of the package, bottom to top: the one statement of its architecture.

A module may import from its own layer and from the layers before it, never from a layer after
it (``tests/test_architecture.py`` reads every import against this table and also refuses
import circles); the API reference of the docs has one page per layer, in this order. Data
only: this module imports nothing.
"""

__all__ = ["LAYERS"]

# (name, title, module prefixes); a module belongs to the layer of its longest prefix
LAYERS: tuple[tuple[str, str, tuple[str, ...]], ...] = (
    ("floor", "Foundations: errors, defaults, checks",
     ("quadcog.errors", "quadcog.config", "quadcog.validate", "quadcog.paths", "quadcog.files",
      "quadcog.kinds", "quadcog.interrupts", "quadcog.layers", "quadcog.numerics")),
    ("codegen", "codegen: compiled code", ("quadcog.codegen",)),
    ("model", "model: the generated functions", ("quadcog.model",)),
    ("vehicles", "vehicles", ("quadcog.vehicles",)),
    ("logs", "logs: flight logs in", ("quadcog.logs",)),
    ("trajectories", "trajectories", ("quadcog.trajectories",)),
    ("controllers", "controllers", ("quadcog.controllers",)),
    ("viz", "viz: figures and animation", ("quadcog.viz",)),
    ("sim", "sim: simulation", ("quadcog.sim",)),
    ("identification", "identification: CoG from logs", ("quadcog.identification",)),
    ("scenarios", "scenarios", ("quadcog.scenarios",)),
    ("sweeps", "sweeps", ("quadcog.sweeps",)),
    ("embedded", "embedded: C for a flight controller", ("quadcog.embedded",)),
    ("stacks", "stacks: flight stacks and peer suites in the loop",
     ("quadcog.stacks", "quadcog.crazyflie", "quadcog.px4", "quadcog.aqb")),
    ("studies", "studies: the paper, beyond, analysis", ("quadcog.studies",)),
    ("cli", "The command line", ("quadcog.cli", "quadcog.__main__", "quadcog")),
)

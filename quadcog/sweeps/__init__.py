"""Parameter sweeps: a sweep file (TOML) names a base scenario and the scenario keys to vary;
``sweep`` flies every combination (or seeded Monte-Carlo samples) in chunks, locally or on
Dask, and writes one table (Parquet and CSV), a summary and plots. ``quadcog sweep FILE --out
DIR`` on the command line; docs/reference/sweep-keys.md lists the keys."""
from quadcog.sweeps.runner import SweepResult, sweep
from quadcog.sweeps.spec import Sweep, SweepError, load_sweep, sweep_names, sweep_path

__all__ = ["Sweep", "SweepError", "SweepResult", "load_sweep", "sweep", "sweep_names",
           "sweep_path"]

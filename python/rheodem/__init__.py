"""rheodem from Python: discrete-element simulations of cohesive granular materials.

The native module (``rheodem._rheodem``, built from the Rust crate ``rheodem-py``) holds
the simulation; this package adds the set-up functions' results, the coarse-grained fields
and the results database in NumPy form (an ``xarray.Dataset`` and a ``pandas.DataFrame``
when those packages are installed). SI units throughout unless a docstring says otherwise.
The user's guide is docs/python.md in the repository.
"""

from __future__ import annotations

from ._rheodem import (
    COMMIT,
    RunError,
    Scenario,
    ScenarioError,
    Simulation,
    __version__,
    predict,
    setups,
)
from .fields import Fields, fields
from .results import import_results, results
from .runs import (
    Estimate,
    SetUpResult,
    chute,
    run_scenario,
    run_setup,
    shear_box,
    split_bottom,
)

__all__ = [
    "COMMIT",
    "Estimate",
    "Fields",
    "RunError",
    "Scenario",
    "ScenarioError",
    "SetUpResult",
    "Simulation",
    "__version__",
    "chute",
    "fields",
    "import_results",
    "predict",
    "results",
    "run_scenario",
    "run_setup",
    "setups",
    "shear_box",
    "split_bottom",
]

"""firefleet: teams of intelligent mobile robots for firefighting and disaster response.

The public surface is small; the subpackages hold the rest:
:mod:`firefleet.models` (plants), :mod:`firefleet.control` (controllers),
:mod:`firefleet.scenarios` (experiments), :mod:`firefleet.sim` (the simulator).

Examples
--------
>>> import firefleet
>>> scenario = firefleet.load_scenario("motor-open-loop")  # one of builtin_names()
>>> result = firefleet.simulate(scenario, record_every=100)
>>> metrics = firefleet.compute_metrics(result)
>>> all(claim.holds(metrics[claim.metric]) for claim in scenario.claims)
True
"""

from firefleet.errors import InputError
from firefleet.scenarios import Scenario, builtin_names, load_scenario
from firefleet.sim import SimResult, compute_metrics, simulate
from firefleet.sweep import sweep

__all__ = [
    "InputError",
    "Scenario",
    "SimResult",
    "builtin_names",
    "compute_metrics",
    "load_scenario",
    "simulate",
    "sweep",
]

__version__ = "0.1.0"

"""The simulator, its recorded result, and the metrics of a run."""

from firefleet.sim.engine import ProgressCallback, simulate
from firefleet.sim.metrics import compute_metrics, recovery_time, settling_time, step_response_info
from firefleet.sim.result import SimResult

__all__ = [
    "ProgressCallback",
    "SimResult",
    "compute_metrics",
    "recovery_time",
    "settling_time",
    "simulate",
    "step_response_info",
]

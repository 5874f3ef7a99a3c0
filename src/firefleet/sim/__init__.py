"""The simulator: the world loop, the registry of task kinds, the recorded result, and
the metrics of a run."""

from firefleet.sim.engine import ProgressCallback, simulate
from firefleet.sim.metrics import compute_metrics, recovery_time, settling_time, step_response_info
from firefleet.sim.registry import TaskKind, register, task_kind
from firefleet.sim.result import SimResult

__all__ = [
    "ProgressCallback",
    "SimResult",
    "TaskKind",
    "compute_metrics",
    "recovery_time",
    "register",
    "settling_time",
    "simulate",
    "step_response_info",
    "task_kind",
]

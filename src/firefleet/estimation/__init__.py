"""Estimation: Monte Carlo localisation, FastSLAM, SLAM logs (seed section 2.7.3).

Libraries first: the estimators take arrays (or a :class:`SlamLog`) and return arrays
or small typed results; the simulator feeds them, they never step it.
"""

from firefleet.estimation.fastslam import (
    FastSlamParams,
    FastSlamResult,
    FastSlamState,
    SensorView,
    fastslam_init,
    fastslam_step,
    run_fastslam,
    slam_claims,
    slam_summary,
)
from firefleet.estimation.logs import SlamLog, format_log, gtsam_text, read_log
from firefleet.estimation.particle_filter import MclParams, MclResult, OdometryNoise, run_mcl

__all__ = [
    "FastSlamParams",
    "FastSlamResult",
    "FastSlamState",
    "MclParams",
    "MclResult",
    "OdometryNoise",
    "SensorView",
    "SlamLog",
    "fastslam_init",
    "fastslam_step",
    "format_log",
    "gtsam_text",
    "read_log",
    "run_fastslam",
    "run_mcl",
    "slam_claims",
    "slam_summary",
]

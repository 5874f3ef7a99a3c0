"""FastSLAM's parameters: the filter's tuning and the sensor's field of view."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

from firefleet.errors import InputError, check_fields

__all__ = ["FastSlamParams", "SensorView", "default_n_particles"]


@dataclass(frozen=True)
class FastSlamParams:
    """Tuning of FastSLAM.

    Attributes
    ----------
    n_particles : int
        Number of particles P (>= 1). 100 here; ``firefleet slam`` runs
        :func:`default_n_particles` (300 with given association).
    version : {1, 2}
        FastSLAM 1.0 (motion-model proposal) or 2.0 (proposal with the observations).
    association : {"known", "unknown"}
        Use the log's landmark ids, or associate by maximum likelihood with a gate.
    resample_threshold : float
        Resample when the effective sample size falls below this fraction of P, (0, 1].
    gate_chi2 : float
        Squared Mahalanobis distance below which an observation may be associated with a
        landmark (unknown association). 13.8 is the chi-square 99.9 % point for 2 degrees
        of freedom.
    view_margin : float
        Share (0, 1] of the sensor's range and half field of view inside which a landmark
        not seen counts as a miss (negative evidence), away from the view's edges.
    odometry_noise_scale : float
        Factor on the log's odometry standard deviations (> 0). A log's per-step noise is
        white; real odometry errors are correlated over many steps (a wheel slipping in
        a turn), and a filter with few particles needs the wider spread to cover them.
        Default 2, with the calibration below (right for Victoria Park's real odometry,
        and better than 1 on the simulated loop; without calibration Victoria Park
        takes 4).
    heading_drift_sigma : float
        Prior standard deviation [rad/m] of a systematic heading drift per metre driven,
        estimated per particle (>= 0; 0 disables). Unequal wheel diameters turn a robot
        that odometry says drives straight (Borenstein and Feng 1996, "type B" error:
        ``dtheta_true = dtheta + k_d s``, s the signed distance of the step). Default
        0.003, on, since real odometry has this bias: Victoria Park's dead-reckoned
        heading drifts 412 degrees from GTSAM's over the 4 km (0.0018 rad/m); without
        it the default run's ATE there is 84-89 m (seeds 1-3).
    turn_scale_sigma : float
        Prior standard deviation [-] of a systematic error on the scale of turns,
        estimated per particle (>= 0; 0 disables): a wrong axle length in the odometry
        (Borenstein and Feng 1996, wheelbase error: ``dtheta_true = dtheta (1 + k_b)``).
        Default 0.05 (Victoria Park's turns are about 5 % short).
    new_landmark_chi2 : float
        Unknown association: an observation farther than this squared Mahalanobis
        distance from every landmark starts a new one; between ``gate_chi2`` and this it
        is ambiguous and skipped (two gates, as in Bailey's EKF-SLAM). 200 (about 14
        sigma): a landmark seen again after a loop is off by the drift gathered since it
        was last seen, which no particle's landmark covariance holds. On the simulated
        loop (4 drives x 3 seeds, 100 particles) 50 left duplicates at the loop's closure
        in 1 of 12 runs of FastSLAM 2.0 and 2 of 12 of 1.0; 200 leaves none. Two heat
        sources closer than this (about 1 m apart at 5 m with the simulated sensor) are
        mapped as one.
    confirm_evidence : int
        With unknown association, the final map keeps the landmarks whose evidence
        (times seen minus times missed in view) reached this count: a spurious detection
        at the edge of the view, never counted as missed, is seen once.

    Examples
    --------
    >>> from firefleet.estimation import FastSlamParams
    >>> params = FastSlamParams(n_particles=50, version=2)
    >>> params.n_particles, params.version, params.association
    (50, 2, 'known')
    """

    n_particles: int = 100
    version: Literal[1, 2] = 1
    association: Literal["known", "unknown"] = "known"
    resample_threshold: float = 0.5
    gate_chi2: float = 13.8
    view_margin: float = 0.9
    new_landmark_chi2: float = 200.0
    confirm_evidence: int = 3
    odometry_noise_scale: float = 2.0
    heading_drift_sigma: float = 0.003
    turn_scale_sigma: float = 0.05

    def __post_init__(self) -> None:
        if self.n_particles < 1:
            raise InputError(f"fastslam.n_particles must be >= 1, got {self.n_particles}")
        if self.version not in (1, 2):
            raise InputError(f"fastslam.version must be 1 or 2, got {self.version}")
        if self.association not in ("known", "unknown"):
            raise InputError(
                f"fastslam.association must be 'known' or 'unknown', got {self.association!r}"
            )
        check_fields(
            self,
            "fastslam",
            positive=("gate_chi2", "view_margin", "resample_threshold", "odometry_noise_scale"),
            non_negative=("heading_drift_sigma", "turn_scale_sigma"),
        )
        if self.resample_threshold > 1.0 or self.view_margin > 1.0:
            raise InputError("fastslam.resample_threshold and view_margin must be <= 1")


@dataclass(frozen=True)
class SensorView:
    """The sensor's field of view, for negative evidence (unknown association).

    Attributes
    ----------
    fov_rad : float
        Full horizontal field of view [rad], centred on the heading.
    max_range_m : float
        Detection range [m].

    Examples
    --------
    >>> import math
    >>> from firefleet.estimation import SensorView
    >>> view = SensorView(fov_rad=math.radians(51.0), max_range_m=12.0)
    >>> round(view.fov_rad, 4), view.max_range_m
    (0.8901, 12.0)
    """

    fov_rad: float
    max_range_m: float

    def __post_init__(self) -> None:
        check_fields(self, "sensor", positive=("fov_rad", "max_range_m"))


def default_n_particles(association: Literal["known", "unknown"]) -> int:
    """The number of particles ``firefleet slam`` runs by default.

    300 with given association (compiled: about 1 s for the whole of Victoria Park,
    whose ATE against GTSAM's optimum it brings from 3.9 m with 100 particles to 3.2 m,
    median of 20 seeds, worst 8 m instead of 23 m); 100 with unknown association, whose
    NumPy association costs about 3 ms per step with 100 particles.

    Examples
    --------
    >>> default_n_particles("known"), default_n_particles("unknown")
    (300, 100)
    """
    return 300 if association == "known" else 100

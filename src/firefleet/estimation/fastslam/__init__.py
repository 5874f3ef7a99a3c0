"""FastSLAM 1.0 and 2.0 with range-bearing landmarks, vectorised over particles.

The seed's particle-filter SLAM (section 2.7.3, ``p(x_t | o_t) ~ p(o_t | x_t)
p(x_t | x_{t-1})``) in its Rao-Blackwellised form: each particle is a robot path with its
own map of independent landmark Kalman filters (Montemerlo et al. 2002, 2003).

- FastSLAM 1.0 samples the pose from the odometry motion model and weights it by the
  observation likelihood ``N(z; h(x, m), H_m S H_m^T + R)``.
- FastSLAM 2.0 samples the pose from a proposal that also uses the current observations
  (an EKF step on the pose with each observed landmark), weighted by
  ``N(z; h(x_hat, m), H_x Sigma_x H_x^T + H_m S H_m^T + R)`` (Thrun et al. 2005,
  Table 13.3, observations fused one after another).
- Data association is given (the log's landmark ids) or unknown: per particle, the
  landmark of maximum likelihood among those whose Mahalanobis distance passes a chi-square
  gate, else a new landmark (weighted by the likelihood at the gate, ``p0``). A landmark
  that the sensor should have seen (inside its field of view and range, with a margin)
  and did not loses one point of evidence, one seen gains one; it is removed below zero
  (Montemerlo 2003, sec. 5.1.3, negative evidence): spurious detections leave no
  landmark behind.

- Odometry calibration (on by default; a prior sigma of 0 turns it off): each particle
  also carries the two systematic errors of differential-drive odometry (Borenstein and
  Feng 1996), a heading drift per metre and a turn scale error, drawn from a prior at
  the start and kept through resampling, so that the particles whose calibration
  explains the observations survive. White per-step noise cannot follow a bias that adds
  up over kilometres (Victoria Park's odometry under-reports its heading by about 0.0018
  rad per metre). The defaults (priors 0.003 rad/m and 0.05, the log's odometry sigmas
  x 2) are set for such real odometry; on the simulated loop, whose odometry is
  unbiased, they lower the median error and widen the spread a little.

State layout (the hot path loops over the observations of a step, never over
particles): poses ``(P, 3)``, log weights ``(P,)``, landmark means ``(P, C, 2)``,
covariances ``(P, C, 2, 2)``, ``active`` ``(P, C)`` and evidence ``(P, C)``, where C is
the number of landmark slots: the number of distinct ids with given association, the
largest map any particle holds (doubled when full) with unknown association. Memory is
O(P C), about 60 P C bytes.

References
----------
M. Montemerlo, S. Thrun, D. Koller, B. Wegbreit, "FastSLAM: A factored solution to the
simultaneous localization and mapping problem", AAAI 2002; "FastSLAM 2.0", IJCAI 2003.
M. Montemerlo, *FastSLAM*, PhD thesis, CMU-RI-TR-03-28, 2003.
S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005, ch. 13.
J. Borenstein, L. Feng, "Measurement and correction of systematic odometry errors in
mobile robots", IEEE Trans. Robotics and Automation 12(6), 1996.

The package's modules: ``_params`` (tuning), ``_state`` (particles), ``_kernel``
(compiled per-particle updates: the one definition of the landmark EKF update),
``_step`` (one step, given association), ``_association`` (unknown association),
``_run`` (a whole log), ``_summary`` (errors, claims, CSV).
"""

from firefleet.estimation.fastslam._params import FastSlamParams, SensorView, default_n_particles
from firefleet.estimation.fastslam._run import FastSlamResult, fastslam_memory_bytes, run_fastslam
from firefleet.estimation.fastslam._state import FastSlamState, fastslam_init
from firefleet.estimation.fastslam._step import fastslam_step
from firefleet.estimation.fastslam._summary import (
    BOUND_M,
    MATCH_RADIUS_M,
    dead_reckoning_landmarks,
    landmarks_csv,
    slam_claims,
    slam_summary,
    trajectory_csv,
)

__all__ = [
    "BOUND_M",
    "MATCH_RADIUS_M",
    "FastSlamParams",
    "FastSlamResult",
    "FastSlamState",
    "SensorView",
    "dead_reckoning_landmarks",
    "default_n_particles",
    "fastslam_init",
    "fastslam_memory_bytes",
    "fastslam_step",
    "landmarks_csv",
    "run_fastslam",
    "slam_claims",
    "slam_summary",
    "trajectory_csv",
]

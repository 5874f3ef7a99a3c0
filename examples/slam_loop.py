"""FastSLAM on a simulated drive: a robot maps the heat sources around a 100 m loop."""

import numpy as np

from firefleet.estimation import FastSlamParams, run_fastslam, slam_summary
from firefleet.sim.world import simulate_drive

drive = simulate_drive(np.random.default_rng(0))  # wheels, encoders, thermal detections
log = drive.log  # odometry, observations (range, bearing; no landmark ids used), truth
params = FastSlamParams(version=2, association="unknown")  # 100 particles
result = run_fastslam(log, np.random.default_rng(0), params=params)
s = slam_summary(log, result)  # errors against the simulator's ground truth
print(f"{log.n_poses} poses, {log.n_observations} detections, {s['landmarks']} landmarks")
print(f"position RMS {s['position_rms_m']:.3f} m", end=" ")
print(f"(odometry alone {s['odometry_position_rms_m']:.2f} m)")
print(f"landmark RMS {s['landmark_rms_m']:.3f} m, duplicates {s['duplicate_landmarks']}")

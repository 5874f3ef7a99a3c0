"""FastSLAM's particles: poses, weights, and one map of landmark Kalman filters each."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from firefleet._typing import BoolArray, FloatArray, IntArray
from firefleet.errors import InputError, as_float_array
from firefleet.estimation.particle_filter import normalise_log_weights

__all__ = ["FastSlamState", "fastslam_init", "grow", "particle_deltas"]


@dataclass
class FastSlamState:
    """The particles of FastSLAM (updated in place by :func:`fastslam_step`).

    Copying the map (``60 P C`` bytes) at every step would cost more than the update
    itself, so the step writes into these arrays; resampling replaces them.

    Attributes
    ----------
    poses : ndarray, shape (P, 3)
    log_w : ndarray, shape (P,)
        Unnormalised log weights.
    mu : ndarray, shape (P, C, 2)
        Landmark means x, y [m].
    sigma : ndarray, shape (P, C, 2, 2)
        Landmark covariances [m^2].
    active : ndarray of bool, shape (P, C)
        Whether a slot holds a landmark.
    evidence : ndarray of int64, shape (P, C)
        Seen minus missed-while-in-view count (unknown association).
    slot_ids : ndarray of int64, shape (C,)
        With given association, the landmark id of each slot (sorted); empty otherwise.
    calibration : ndarray, shape (P, 2), or None
        Each particle's odometry calibration: heading drift k_d [rad/m] and turn scale
        error k_b [-] (see :class:`FastSlamParams`); None when not estimated.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation import fastslam_init
    >>> state = fastslam_init(10, landmark_ids=np.array([3, 7]))
    >>> state.poses.shape, state.mu.shape, state.sigma.shape
    ((10, 3), (10, 2, 2), (10, 2, 2, 2))
    """

    poses: FloatArray
    log_w: FloatArray
    mu: FloatArray
    sigma: FloatArray
    active: BoolArray
    evidence: IntArray
    slot_ids: IntArray = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    calibration: FloatArray | None = None

    @property
    def n_particles(self) -> int:
        """P."""
        return int(self.poses.shape[0])

    @property
    def capacity(self) -> int:
        """C, the number of landmark slots."""
        return int(self.mu.shape[1])

    def weights(self) -> FloatArray:
        """Normalised weights ``(P,)``."""
        return normalise_log_weights(self.log_w)

    def best(self) -> int:
        """Index of the particle of largest weight."""
        return int(np.argmax(self.log_w))


def fastslam_init(
    n_particles: int,
    *,
    landmark_ids: IntArray | None = None,
    capacity: int = 16,
    pose: tuple[float, float, float] = (0.0, 0.0, 0.0),
    calibration: FloatArray | None = None,
) -> FastSlamState:
    """Particles at a known start pose with empty maps.

    Parameters
    ----------
    n_particles : int
    landmark_ids : ndarray of int, optional
        With given association, the landmark ids that may be observed (one slot each).
    capacity : int
        Initial number of slots with unknown association (grows as needed).
    pose : tuple of float
        The start pose x [m], y [m], theta [rad] (the log's frame: the origin).
    calibration : ndarray, shape (P, 2), optional
        Each particle's odometry calibration (heading drift [rad/m], turn scale error),
        e.g. drawn from the prior by :func:`run_fastslam`; None: not estimated.

    Returns
    -------
    FastSlamState

    Examples
    --------
    >>> from firefleet.estimation import fastslam_init
    >>> state = fastslam_init(4, pose=(1.0, 2.0, 0.5))
    >>> state.poses.tolist()[0], bool(state.active.any())
    ([1.0, 2.0, 0.5], False)
    """
    if n_particles < 1:
        raise InputError(f"n_particles must be >= 1, got {n_particles}")
    ids = np.zeros(0, dtype=np.int64) if landmark_ids is None else np.unique(landmark_ids)
    c = max(int(ids.size), 1) if landmark_ids is not None else max(capacity, 1)
    cal = None
    if calibration is not None:
        cal = as_float_array(calibration, "calibration", (n_particles, 2)).copy()
    return FastSlamState(
        poses=np.tile(np.asarray(pose, dtype=np.float64), (n_particles, 1)),
        log_w=np.zeros(n_particles),
        mu=np.zeros((n_particles, c, 2)),
        sigma=np.tile(np.eye(2), (n_particles, c, 1, 1)),
        active=np.zeros((n_particles, c), dtype=bool),
        evidence=np.zeros((n_particles, c), dtype=np.int64),
        slot_ids=ids.astype(np.int64),
        calibration=cal,
    )


def grow(state: FastSlamState) -> None:
    """Double the number of slots (unknown association)."""
    p, c = state.n_particles, state.capacity
    state.mu = np.concatenate([state.mu, np.zeros((p, c, 2))], axis=1)
    state.sigma = np.concatenate([state.sigma, np.tile(np.eye(2), (p, c, 1, 1))], axis=1)
    state.active = np.concatenate([state.active, np.zeros((p, c), dtype=bool)], axis=1)
    state.evidence = np.concatenate([state.evidence, np.zeros((p, c), dtype=np.int64)], axis=1)


def particle_deltas(state: FastSlamState, delta: FloatArray) -> FloatArray:
    """The measured motion ``(3,)`` as each particle's calibration corrects it, ``(P, 3)``.

    ``dtheta_i = dtheta (1 + k_b,i) + k_d,i s`` with s the step's signed distance
    (negative when driving backwards, where the drift of unequal wheels reverses).
    """
    d = np.empty((state.n_particles, 3))
    d[:] = delta
    cal = state.calibration
    if cal is not None:
        s = math.copysign(math.hypot(delta[0], delta[1]), delta[0])
        d[:, 2] = delta[2] * (1.0 + cal[:, 1]) + cal[:, 0] * s
    return d

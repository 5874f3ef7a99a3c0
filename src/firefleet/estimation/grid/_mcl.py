"""Monte Carlo localisation on a known occupancy grid (augmented MCL).

Particles ``(P, 3)`` move by the odometry increments with the motion noise of
:class:`GridMclParams`, are weighted by the likelihood field model
(:mod:`._likelihood`) and resampled (low-variance) when the effective sample size drops
below ``resample_ratio * P``. Recovery is augmented MCL (Thrun et al. 2005, Table 8.3):
short- and long-term averages of the measurement likelihood, ``w_fast`` and ``w_slow``;
when the short-term one falls below the long-term one (the robot was kidnapped, or the
filter converged on the wrong place), a share ``max(0, 1 - w_fast / w_slow)`` of the
particles is replaced by poses drawn uniformly over the free cells at the next
resampling. The averages are of the *per-beam* likelihood (the geometric mean over the
scan's beams) so that their scale does not depend on the beam count.

The particle count adapts at each resampling by KLD sampling (Fox 2003): as many
particles as keep the Kullback-Leibler divergence between the sample-based and the
true posterior below ``kld_error`` with probability ``kld_quantile``, counted over
bins of ``kld_bin_m`` x ``kld_bin_m`` x ``kld_bin_rad``, between ``min_particles`` and
``n_particles``. Global localisation starts from :func:`mcl_global`: ``n_particles``
uniform over the free cells and every heading. The floor ``min_particles`` = 5,000 is
what keeps the hypotheses of a building of identical rooms alive until the robot sees
what tells them apart (with 300 to 2,000, MCL locked onto the wrong room of the
built-in office in some seeded runs); tracking alone does with a few hundred.

The pose estimate is the weighted mean of the particles within ``cluster_radius_m``
of the heaviest mode (the mean of a multi-modal cloud would be in none of its modes).

References
----------
S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005: Table 8.2 (MCL),
Table 8.3 (augmented MCL), Table 6.3 (likelihood field), Table 4.4 (low-variance
sampler), Table 8.4 (KLD sampling). D. Fox, "Adapting the sample size in particle
filters through KLD-sampling", IJRR 22(12), 2003.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray, IntArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.estimation.grid._likelihood import LikelihoodField, field_log_likelihood
from firefleet.estimation.grid._mapping import Scanner, check_ranges
from firefleet.estimation.particle_filter import (
    compose,
    effective_sample_size,
    low_variance_resample,
    normalise_log_weights,
)
from firefleet.models.kinematics import wrap_angle

__all__ = [
    "GridMclParams",
    "MclState",
    "free_cell_poses",
    "mcl_estimate",
    "mcl_global",
    "mcl_step",
    "mcl_tracking",
    "sample_motion",
]


@dataclass(frozen=True)
class GridMclParams:
    """Parameters of grid MCL.

    Attributes
    ----------
    n_particles : int
        Particle count P at the start, and the most KLD sampling keeps.
    min_particles : int
        The fewest KLD sampling keeps.
    kld_error, kld_quantile_z : float
        KLD sampling's bound on the divergence and the standard normal quantile of the
        probability it holds with (2.33: 99 %).
    kld_bin_m, kld_bin_rad : float
        KLD sampling's bin size in x, y [m] and heading [rad].
    sigma_hit_m : float
        Standard deviation of the hit's distance to the nearest wall [m].
    z_hit, z_rand : float
        Weights of the hit and the random-return terms.
    max_beams : int
        At most this many beams per scan are used, evenly spread (their errors are
        correlated; more beams only sharpen the likelihood).
    trans_per_m, rot_per_rad, rot_per_m : float
        Motion noise: standard deviation of the travel per metre travelled, of the turn
        per radian turned [rad/rad], of the turn per metre travelled [rad/m].
    floor_m, floor_rad : float
        Standard deviations added every update [m], [rad].
    resample_ratio : float
        Resample when N_eff < resample_ratio * P.
    alpha_slow, alpha_fast : float
        Smoothing of the long- and short-term likelihood averages (0 < slow << fast).
    cluster_radius_m : float
        Radius of the cluster around the best particle that the estimate averages [m].
    """

    n_particles: int = 10000
    min_particles: int = 5000
    kld_error: float = 0.05
    kld_quantile_z: float = 2.33
    kld_bin_m: float = 0.2
    kld_bin_rad: float = 0.17
    sigma_hit_m: float = 0.2
    z_hit: float = 0.9
    z_rand: float = 0.1
    max_beams: int = 30
    trans_per_m: float = 0.1
    rot_per_rad: float = 0.1
    rot_per_m: float = 0.05
    floor_m: float = 0.01
    floor_rad: float = 0.01
    resample_ratio: float = 0.5
    alpha_slow: float = 0.001
    alpha_fast: float = 0.1
    cluster_radius_m: float = 0.75

    def __post_init__(self) -> None:
        check_fields(
            self,
            "mcl",
            positive=(
                "n_particles",
                "min_particles",
                "kld_error",
                "kld_bin_m",
                "kld_bin_rad",
                "sigma_hit_m",
                "max_beams",
                "cluster_radius_m",
            ),
            non_negative=(
                "z_hit",
                "z_rand",
                "trans_per_m",
                "rot_per_rad",
                "rot_per_m",
                "floor_m",
                "floor_rad",
                "alpha_slow",
                "alpha_fast",
                "resample_ratio",
            ),
        )
        if self.min_particles > self.n_particles:
            raise InputError(
                f"mcl.min_particles ({self.min_particles}) must be <= mcl.n_particles "
                f"({self.n_particles})"
            )
        if self.z_hit + self.z_rand <= 0.0:
            raise InputError("mcl.z_hit + mcl.z_rand must be > 0")
        if not self.alpha_slow < self.alpha_fast <= 1.0:
            raise InputError(
                f"mcl.alpha_slow ({self.alpha_slow}) must be < mcl.alpha_fast "
                f"({self.alpha_fast}) <= 1"
            )


@dataclass(frozen=True)
class MclState:
    """One robot's particle filter.

    Attributes
    ----------
    particles : ndarray, shape (P, 3)
        x [m], y [m], heading [rad].
    log_weights : ndarray, shape (P,)
        Unnormalised log weights.
    w_slow, w_fast : float
        Long- and short-term averages of the per-beam likelihood (0: not started).
    """

    particles: FloatArray
    log_weights: FloatArray
    w_slow: float = 0.0
    w_fast: float = 0.0


def free_cell_poses(field: LikelihoodField, n: int, rng: np.random.Generator) -> FloatArray:
    """``n`` poses uniform over the map's free cells (uniform inside each cell) and every
    heading, shape (n, 3)."""
    free = np.argwhere(field.grid.free)
    if free.size == 0:
        raise InputError(f"map {field.grid.name!r} has no free cell to localise in")
    cells = free[rng.integers(0, len(free), n)]
    xy = field.grid.center_of(cells) + field.grid.resolution_m * (rng.random((n, 2)) - 0.5)
    return np.column_stack([xy, rng.uniform(-np.pi, np.pi, n)])


def mcl_global(field: LikelihoodField, params: GridMclParams, rng: np.random.Generator) -> MclState:
    """Global localisation's start: P particles uniform over the free cells.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import GridMclParams, likelihood_field, mcl_global
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((4, 4), bool); occ[:, 0] = True
    >>> field = likelihood_field(OccupancyGrid(occ, ~occ, 0.5))
    >>> state = mcl_global(field, GridMclParams(100, 10), np.random.default_rng(0))
    >>> state.particles.shape, bool(state.particles[:, 0].min() >= 0.5)
    ((100, 3), True)
    """
    p = free_cell_poses(field, params.n_particles, rng)
    return MclState(particles=p, log_weights=np.zeros(params.n_particles))


def mcl_tracking(
    pose: ArrayLike,
    params: GridMclParams,
    rng: np.random.Generator,
    sigma_m: float = 0.05,
    sigma_rad: float = 0.05,
) -> MclState:
    """Tracking's start: P particles around a known pose (3,) (Gaussian, the given
    standard deviations)."""
    mu = as_float_array(pose, "pose", (3,))
    n = params.n_particles
    p = mu + rng.standard_normal((n, 3)) * np.array([sigma_m, sigma_m, sigma_rad])
    p[:, 2] = wrap_angle(p[:, 2])
    return MclState(particles=p, log_weights=np.zeros(n))


def sample_motion(
    particles: FloatArray, delta: FloatArray, params: GridMclParams, rng: np.random.Generator
) -> FloatArray:
    """Each particle moved by the odometry increment ``delta`` (3,) (dx, dy in the old
    pose's frame [m], dtheta [rad]) with noise drawn per particle, shape (P, 3)."""
    n = particles.shape[0]
    dist = float(np.hypot(delta[0], delta[1]))
    s_xy = params.trans_per_m * dist + params.floor_m
    s_th = params.rot_per_rad * abs(float(delta[2])) + params.rot_per_m * dist + params.floor_rad
    noisy = delta + rng.standard_normal((n, 3)) * np.array([s_xy, s_xy, s_th])
    out = compose(particles, noisy)
    out[:, 2] = wrap_angle(out[:, 2])
    return out


def _beams(scanner: Scanner, max_beams: int) -> FloatArray:
    b = scanner.bearings_rad.size
    return np.unique(np.linspace(0, b - 1, min(b, max_beams)).round().astype(np.int64))


def mcl_step(
    state: MclState,
    delta: ArrayLike,
    ranges_m: ArrayLike | None,
    field: LikelihoodField,
    scanner: Scanner,
    params: GridMclParams,
    rng: np.random.Generator,
) -> MclState:
    """One MCL update: move by the odometry, weigh by the scan, resample if needed.

    Parameters
    ----------
    state : MclState
    delta : array_like, shape (3,)
        Odometry increment since the last update: dx, dy [m] in the old pose's frame,
        dtheta [rad].
    ranges_m : array_like, shape (B,), or None
        The scan [m] (``inf``: no return); None: no scan, the motion alone.
    field : LikelihoodField
        The known map.
    scanner : Scanner
    params : GridMclParams
    rng : numpy.random.Generator

    Returns
    -------
    MclState

    Examples
    --------
    A 4 m square room with 0.1 m walls; four beams see the walls' faces 1.9 m away.

    >>> import numpy as np
    >>> from firefleet.estimation.grid import (GridMclParams, Scanner, likelihood_field,
    ...     mcl_estimate, mcl_step, mcl_tracking)
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((40, 40), bool); occ[[0, -1], :] = True; occ[:, [0, -1]] = True
    >>> field = likelihood_field(OccupancyGrid(occ, ~occ, 0.1))
    >>> scanner = Scanner.ring(4, 360.0, 5.0)
    >>> prm = GridMclParams(n_particles=500, min_particles=100)
    >>> rng = np.random.default_rng(0)
    >>> state = mcl_tracking([2.1, 1.9, 0.0], prm, rng, sigma_m=0.2)
    >>> for _ in range(5):
    ...     state = mcl_step(state, np.zeros(3), np.full(4, 1.9), field, scanner, prm, rng)
    >>> bool(np.hypot(*(mcl_estimate(state, prm)[:2] - 2.0)) < 0.1)
    True
    """
    d = as_float_array(delta, "delta", (3,))
    particles = sample_motion(state.particles, d, params, rng)
    log_w = state.log_weights
    w_slow, w_fast = state.w_slow, state.w_fast
    if ranges_m is None:
        return MclState(particles, log_w, w_slow, w_fast)
    z = check_ranges(np.reshape(ranges_m, (1, -1)), scanner, 1)[0]
    use = _beams(scanner, params.max_beams)
    z_use, b_use = z[use], scanner.bearings_rad[use]
    n_valid = int(np.count_nonzero(z_use < scanner.max_range_m))
    if n_valid == 0:
        return MclState(particles, log_w, w_slow, w_fast)
    lik = field_log_likelihood(
        field,
        particles,
        z_use,
        b_use,
        scanner.max_range_m,
        params.sigma_hit_m,
        params.z_hit,
        params.z_rand,
    )
    prior = normalise_log_weights(log_w)
    log_w = log_w + lik
    # the per-beam average likelihood: geometric mean over beams of the prior-weighted mean
    top = float(np.max(lik))
    w_avg = float(np.exp((top + np.log(prior @ np.exp(lik - top))) / n_valid))
    w_slow = w_avg if w_slow == 0.0 else w_slow + params.alpha_slow * (w_avg - w_slow)
    w_fast = w_avg if w_fast == 0.0 else w_fast + params.alpha_fast * (w_avg - w_fast)
    weights = normalise_log_weights(log_w)
    inject = max(0.0, 1.0 - w_fast / w_slow)
    n = particles.shape[0]
    if effective_sample_size(weights) < params.resample_ratio * n or inject > 0.05:
        particles = particles[low_variance_resample(weights, rng)]
        n = kld_count(particles, params)
        particles = (
            particles[rng.permutation(particles.shape[0])[:n]]
            if n <= len(particles)
            else particles[rng.integers(0, len(particles), n)]
        )
        fresh = rng.random(n) < inject
        if fresh.any():
            particles[fresh] = free_cell_poses(field, int(fresh.sum()), rng)
        log_w = np.zeros(n)
    return MclState(particles, log_w - np.max(log_w), w_slow, w_fast)


def _pack(keys: IntArray) -> IntArray:
    """Integer bin coordinates (P, D), each within +-2^20, as one int64 per row."""
    out = np.zeros(keys.shape[0], np.int64)
    for j in range(keys.shape[1]):
        out = (out << 21) + (keys[:, j] + (1 << 20))
    return out


def kld_count(particles: FloatArray, params: GridMclParams) -> int:
    """KLD sampling's particle count for a cloud (P, 3) (Fox 2003, eq. 12; Thrun et
    al. 2005, Table 8.4): ``(k - 1) / (2 eps) (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) z)^3``
    for ``k`` occupied bins, within ``[min_particles, n_particles]``.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import GridMclParams
    >>> from firefleet.estimation.grid._mcl import kld_count
    >>> prm = GridMclParams(min_particles=1)
    >>> kld_count(np.zeros((50, 3)), prm)  # one bin: the minimum
    1
    >>> kld_count(np.array([[0.0, 0, 0], [1.0, 0, 0]]), prm)  # two bins
    67
    """
    keys = np.floor(
        particles / np.array([params.kld_bin_m, params.kld_bin_m, params.kld_bin_rad])
    ).astype(np.int64)
    k = len(np.unique(_pack(keys)))
    if k <= 1:
        return params.min_particles
    a = 2.0 / (9.0 * (k - 1))
    n = (k - 1) / (2.0 * params.kld_error) * (1.0 - a + np.sqrt(a) * params.kld_quantile_z) ** 3
    return int(np.clip(np.ceil(n), params.min_particles, params.n_particles))


def mcl_estimate(state: MclState, params: GridMclParams) -> FloatArray:
    """The pose estimate (3,): the weighted mean of the particles within
    ``cluster_radius_m`` of the heaviest ``cluster_radius_m``-sided square's centroid."""
    w = normalise_log_weights(state.log_weights)
    p = state.particles
    r = params.cluster_radius_m
    _, bins = np.unique(_pack(np.floor(p[:, :2] / r).astype(np.int64)), return_inverse=True)
    mass = np.bincount(bins.ravel(), weights=w)
    top = bins.ravel() == int(np.argmax(mass))  # the heaviest r x r square
    centre = (w[top] @ p[top, :2]) / w[top].sum()
    near = np.hypot(p[:, 0] - centre[0], p[:, 1] - centre[1]) <= r
    wn = w * near
    wn /= wn.sum()
    th = np.arctan2(wn @ np.sin(p[:, 2]), wn @ np.cos(p[:, 2]))
    return np.array([wn @ p[:, 0], wn @ p[:, 1], th])

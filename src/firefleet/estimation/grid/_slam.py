"""Grid SLAM: a Rao-Blackwellised particle filter with per-particle occupancy maps
(GMapping, Grisetti, Stachniss and Burgard 2007).

Each particle holds a pose and its own log-odds map (float32, on the cells of a given
frame grid). For each scan:

1. every particle moves by the odometry increment with noise drawn per particle
   (:func:`._mcl.sample_motion`);
2. the *proposal*: the pose is refined by scan matching against the particle's own map
   (hill climbing to the mode of scan likelihood x motion model, :mod:`._scanmatch`);
   a match scoring under ``min_score`` (an empty or ambiguous map) keeps the odometry's
   sample;
3. the weight is multiplied by the scan's likelihood at the matched pose, tempered by
   ``1 / weight_gain`` (GMapping's ``lgain``: the beams' errors are not independent,
   and untempered weights collapse the cloud in a few scans);
4. the scan is written into the particle's map at that pose (:mod:`._mapping`'s
   inverse sensor model);
5. *adaptive resampling*: low-variance resampling only when the effective sample size
   drops below ``resample_ratio * P``; a copied particle copies its map.

The first ``warmup_scans`` scans only build the maps. Memory: P maps of H x W float32,
30 particles on a 20 m x 20 m floor at 0.05 m = 30 x 160,000 x 4 B = 19 MB (and as
much again during a resampling's copy); GMapping's shared tree of map patches saves
that copy, which this dense layout does not need at these sizes.

The pose estimate is the weighted mean of the particles' poses; the map is the
heaviest particle's.

References
----------
G. Grisetti, C. Stachniss, W. Burgard, "Improved techniques for grid mapping with
Rao-Blackwellized particle filters", IEEE Trans. Robotics 23(1), 2007.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError, as_float_array, check_fields
from firefleet.estimation.grid._mapping import LogOddsParams, Scanner, check_ranges
from firefleet.estimation.grid._mcl import GridMclParams, sample_motion
from firefleet.estimation.grid._rays import grid_frame, scan_update
from firefleet.estimation.grid._scanmatch import match_particles
from firefleet.estimation.particle_filter import (
    compose,
    effective_sample_size,
    low_variance_resample,
    normalise_log_weights,
)
from firefleet.world import OccupancyGrid

__all__ = ["GridSlamParams", "GridSlamState", "slam_estimate", "slam_init", "slam_map", "slam_step"]


@dataclass(frozen=True)
class GridSlamParams:
    """Parameters of grid SLAM.

    Attributes
    ----------
    n_particles : int
        Particle count P (fixed).
    max_beams : int
        At most this many beams per scan in the matcher and the weights (evenly
        spread); every beam goes into the maps.
    sigma_m : float
        Standard deviation of a beam end's distance to the map's wall [m].
    window : int
        The matcher looks for a wall this many cells around each beam's end.
    step_m, step_rad : float
        The matcher's first steps [m], [rad].
    refinements : int
        How often the matcher halves its steps.
    min_score_ratio : float
        A match counts when its score reaches this share of the beams used.
    z_hit, z_rand : float
        The likelihood's mixture weights (hit, random return).
    weight_gain : float
        The scan log likelihood is divided by this before it weighs a particle.
    resample_ratio : float
        Resample when N_eff < resample_ratio * P.
    warmup_scans : int
        Scans that only build the maps before matching starts.
    motion : GridMclParams
        The motion noise of the proposal's odometry sample (its other fields unused).
    mapping : LogOddsParams
        The maps' inverse sensor model.
    """

    n_particles: int = 30
    max_beams: int = 60
    sigma_m: float = 0.05
    window: int = 2
    step_m: float = 0.05
    step_rad: float = 0.05
    refinements: int = 4
    min_score_ratio: float = 0.3
    z_hit: float = 0.9
    z_rand: float = 0.1
    weight_gain: float = 3.0
    resample_ratio: float = 0.5
    warmup_scans: int = 3
    motion: GridMclParams = field(
        default_factory=lambda: GridMclParams(
            trans_per_m=0.05, rot_per_rad=0.05, rot_per_m=0.02, floor_m=0.005, floor_rad=0.005
        )
    )
    mapping: LogOddsParams = field(default_factory=LogOddsParams)

    def __post_init__(self) -> None:
        check_fields(
            self,
            "slam",
            positive=(
                "n_particles",
                "max_beams",
                "sigma_m",
                "step_m",
                "step_rad",
                "z_hit",
                "weight_gain",
            ),
            non_negative=(
                "window",
                "refinements",
                "min_score_ratio",
                "z_rand",
                "resample_ratio",
                "warmup_scans",
            ),
        )


@dataclass(frozen=True, eq=False)
class GridSlamState:
    """The particles of one robot's grid SLAM.

    Attributes
    ----------
    poses : ndarray, shape (P, 3)
        x [m], y [m], heading [rad].
    log_odds : ndarray of float32, shape (P, H, W)
        Each particle's map (updated in place by :func:`slam_step`).
    log_weights : ndarray, shape (P,)
    scans : int
        Scans integrated so far.
    resamplings : int
        Resamplings so far.
    """

    poses: FloatArray
    log_odds: NDArray[np.float32]
    log_weights: FloatArray
    scans: int = 0
    resamplings: int = 0


def slam_init(frame: OccupancyGrid, pose: ArrayLike, params: GridSlamParams) -> GridSlamState:
    """P particles at the start pose (3,) with empty maps on ``frame``'s cells (its
    contents unused: it sets the extent and resolution of the maps).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import GridSlamParams, slam_init
    >>> from firefleet.world import OccupancyGrid
    >>> frame = OccupancyGrid(np.zeros((40, 60), bool), np.ones((40, 60), bool), 0.05)
    >>> state = slam_init(frame, [1.0, 1.0, 0.0], GridSlamParams(n_particles=5))
    >>> state.poses.shape, state.log_odds.shape, state.log_odds.dtype.name
    ((5, 3), (5, 40, 60), 'float32')
    """
    mu = as_float_array(pose, "pose", (3,))
    if not frame.contains(mu[:2]):
        raise InputError(f"pose {mu.tolist()} is off the map {frame.name!r}")
    n = params.n_particles
    return GridSlamState(
        poses=np.tile(mu, (n, 1)),
        log_odds=np.zeros((n, *frame.shape), np.float32),
        log_weights=np.zeros(n),
    )


def slam_step(
    state: GridSlamState,
    delta: ArrayLike,
    ranges_m: ArrayLike,
    frame: OccupancyGrid,
    scanner: Scanner,
    params: GridSlamParams,
    rng: np.random.Generator,
) -> GridSlamState:
    """One grid SLAM update from an odometry increment and a scan.

    Parameters
    ----------
    state : GridSlamState
        Its maps are updated in place (and returned in the new state).
    delta : array_like, shape (3,)
        Odometry increment since the last scan: dx, dy [m] in the old pose's frame,
        dtheta [rad].
    ranges_m : array_like, shape (B,)
        The scan [m] (``inf``: no return).
    frame : OccupancyGrid
        The maps' cells (as given to :func:`slam_init`).
    scanner : Scanner
    params : GridSlamParams
    rng : numpy.random.Generator

    Returns
    -------
    GridSlamState

    Examples
    --------
    Standing still in a 4 m square room: the map fills in, the estimate stays put.

    >>> import numpy as np
    >>> from firefleet.estimation.grid import (GridSlamParams, Scanner, slam_estimate,
    ...     slam_init, slam_map, slam_step)
    >>> from firefleet.world import OccupancyGrid
    >>> frame = OccupancyGrid(np.zeros((40, 40), bool), np.ones((40, 40), bool), 0.1)
    >>> scanner = Scanner.ring(4, 360.0, 5.0)
    >>> prm = GridSlamParams(n_particles=5)
    >>> state = slam_init(frame, [2.0, 2.0, 0.0], prm)
    >>> rng = np.random.default_rng(0)
    >>> for _ in range(6):
    ...     state = slam_step(state, np.zeros(3), np.full(4, 1.9), frame, scanner, prm, rng)
    >>> bool(np.hypot(*(slam_estimate(state)[:2] - 2.0)) < 0.05), bool(slam_map(state)[19, 39] > 0)
    (True, True)
    """
    d = as_float_array(delta, "delta", (3,))
    z = check_ranges(np.reshape(ranges_m, (1, -1)), scanner, 1)[0]
    if state.log_odds.shape[1:] != frame.shape:
        raise InputError(f"the state's maps {state.log_odds.shape[1:]} are not on {frame.shape}")
    n = state.poses.shape[0]
    prior = compose(state.poses, d)  # the motion model's mean for each particle
    poses = sample_motion(state.poses, d, params.motion, rng)
    dist = float(np.hypot(d[0], d[1]))
    mo = params.motion
    sigma_xy = mo.trans_per_m * dist + mo.floor_m
    sigma_th = mo.rot_per_rad * abs(float(d[2])) + mo.rot_per_m * dist + mo.floor_rad
    log_w = state.log_weights
    ox, oy, res, _, _ = grid_frame(frame)
    use = np.unique(np.linspace(0, z.size - 1, min(z.size, params.max_beams)).round())
    use = use.astype(np.int64)
    ret = use[z[use] < scanner.max_range_m]
    if state.scans >= params.warmup_scans and ret.size > 0:
        matched = np.empty_like(poses)
        loglik = np.empty(n)
        match_particles(
            state.log_odds,
            poses,
            prior,
            np.ascontiguousarray(z[ret]),
            np.ascontiguousarray(scanner.bearings_rad[ret]),
            ox,
            oy,
            res,
            params.window,
            params.sigma_m,
            params.step_m,
            params.step_rad,
            params.refinements,
            params.min_score_ratio * ret.size,
            params.z_hit,
            params.z_rand,
            1.0 / params.weight_gain,
            sigma_xy,
            sigma_th,
            matched,
            loglik,
        )
        poses = matched
        log_w = log_w + loglik / params.weight_gain
        log_w = log_w - np.max(log_w)
    _integrate(state.log_odds, poses, z, frame, scanner, params.mapping)
    maps = state.log_odds
    resamplings = state.resamplings
    weights = normalise_log_weights(log_w)
    if effective_sample_size(weights) < params.resample_ratio * n:
        idx = low_variance_resample(weights, rng)
        poses, maps, log_w = poses[idx], maps[idx], np.zeros(n)
        resamplings += 1
    return GridSlamState(poses, maps, log_w, state.scans + 1, resamplings)


def _integrate(
    maps: NDArray[np.float32],
    poses: FloatArray,
    z: FloatArray,
    frame: OccupancyGrid,
    scanner: Scanner,
    prm: LogOddsParams,
) -> None:
    """Write one scan into every particle's map at its pose, in place."""
    hit = z < scanner.max_range_m
    dist = np.where(hit, z, scanner.max_range_m) + 1e-6  # as mapping_step's nudge
    ang = poses[:, 2:3] + scanner.bearings_rad
    xy = np.stack([poses[:, 0:1] + dist * np.cos(ang), poses[:, 1:2] + dist * np.sin(ang)], axis=-1)
    ends = frame.cell_of(xy)
    starts = frame.cell_of(poses[:, :2])
    keep = hit | (prm.no_return == "free")
    marks = np.zeros(frame.shape, np.int8)
    h_keep = np.ascontiguousarray(hit[keep])
    for p in range(poses.shape[0]):
        scan_update(
            maps[p],
            marks,
            int(starts[p, 0]),
            int(starts[p, 1]),
            np.ascontiguousarray(ends[p, keep, 0]),
            np.ascontiguousarray(ends[p, keep, 1]),
            h_keep,
            prm.l_free,
            prm.l_occ,
            -prm.clamp,
            prm.clamp,
        )


def slam_estimate(state: GridSlamState) -> FloatArray:
    """The pose estimate (3,): the particles' weighted mean (heading on the circle)."""
    w = normalise_log_weights(state.log_weights)
    p = state.poses
    return np.array(
        [w @ p[:, 0], w @ p[:, 1], np.arctan2(w @ np.sin(p[:, 2]), w @ np.cos(p[:, 2]))]
    )


def slam_map(state: GridSlamState) -> NDArray[np.float32]:
    """The heaviest particle's log-odds map (H, W)."""
    return np.asarray(state.log_odds[int(np.argmax(state.log_weights))], dtype=np.float32)

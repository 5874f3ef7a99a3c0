"""Occupancy mapping with known poses: log-odds grids from range scans.

Each cell holds the log odds ``l = log(p / (1 - p))`` of being occupied, 0 (p = 0.5)
before any observation. A scan adds the *inverse sensor model* (Thrun et al. 2005,
Table 9.1 and 9.2) to every cell it touches, once per scan:

- ``l_occ = logit(p_occupied)`` to the cell holding a beam's return (the hit);
- ``l_free = logit(p_free)`` to every cell a beam crosses before its hit;
- nothing beyond the hit.

A beam without a return (``inf``, or a range at or over the sensor's maximum) says the
space up to the maximum range was empty: with ``no_return="free"`` (the default) its
cells up to ``max_range_m`` are marked free, with ``"ignore"`` it adds nothing (for a
sensor whose dropouts are not reliable evidence of free space, such as an ultrasonic
ring at grazing incidence). A cell occupied by one beam of a scan and crossed by another
counts as occupied for that scan. Log odds are clamped to ``[-clamp, clamp]`` so that a
map can still change its mind (a door opened).

Several robots' maps merge by *summing* their log odds (less the prior, here 0): for
observations that are independent given the map, the log-odds posterior of all of them
is the sum of each one's contribution (Thrun et al. 2005, eq. 9.7), whichever robot made
them. The sum is the principled merge; it is not valid for observations that share an
error (two robots' maps built from the same wrong pose).

Sensors are taken at the robot's centre, bearings relative to its heading.

References
----------
S. Thrun, W. Burgard, D. Fox, *Probabilistic Robotics*, MIT Press 2005, ch. 9.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError, as_float_array
from firefleet.estimation.grid._rays import scan_update
from firefleet.world import OccupancyGrid

_NUDGE_M = 1e-6
"""Beam ends are moved this far along the beam [m], so that a range to a wall's face
(exact in simulation) lands in the wall's cell rather than on the rounding edge."""

__all__ = [
    "LogOddsParams",
    "Scanner",
    "map_agreement_pct",
    "mapping_step",
    "merge_log_odds",
    "occupancy_probability",
    "scan_endpoints",
]


@dataclass(frozen=True)
class LogOddsParams:
    """The inverse sensor model of a beam (Thrun et al. 2005, Table 9.2).

    Attributes
    ----------
    p_occupied : float
        Probability that the cell of a return is occupied, in (0.5, 1).
    p_free : float
        Probability that a cell a beam crossed is occupied, in (0, 0.5).
    clamp : float
        Bound on a cell's log odds (both signs).
    no_return : {"free", "ignore"}
        What a beam without a return says: free up to the maximum range, or nothing.
    """

    p_occupied: float = 0.7
    p_free: float = 0.3
    clamp: float = 10.0
    no_return: Literal["free", "ignore"] = "free"

    def __post_init__(self) -> None:
        if not 0.5 < self.p_occupied < 1.0:
            raise InputError(f"mapping.p_occupied must be in (0.5, 1), got {self.p_occupied}")
        if not 0.0 < self.p_free < 0.5:
            raise InputError(f"mapping.p_free must be in (0, 0.5), got {self.p_free}")
        if not (np.isfinite(self.clamp) and self.clamp > 0.0):
            raise InputError(f"mapping.clamp must be a positive number, got {self.clamp}")
        if self.no_return not in ("free", "ignore"):
            raise InputError(
                f"mapping.no_return must be 'free' or 'ignore', got {self.no_return!r}"
            )

    @property
    def l_occ(self) -> float:
        """Log odds added to a hit cell."""
        return float(np.log(self.p_occupied / (1.0 - self.p_occupied)))

    @property
    def l_free(self) -> float:
        """Log odds added to a crossed cell (negative)."""
        return float(np.log(self.p_free / (1.0 - self.p_free)))


@dataclass(frozen=True, eq=False)
class Scanner:
    """A range sensor's beams: bearings relative to the heading and the range limit.

    Attributes
    ----------
    bearings_rad : ndarray, shape (B,)
        Beam bearings [rad], counter-clockwise from the robot's heading.
    max_range_m : float
        Maximum range [m]: a reading at or beyond it (or ``inf``) is no return.
    """

    bearings_rad: FloatArray
    max_range_m: float

    def __post_init__(self) -> None:
        b = as_float_array(self.bearings_rad, "bearings_rad", (None,))
        if b.size == 0 or not np.all(np.isfinite(b)):
            raise InputError(f"bearings_rad must be finite and not empty, got {b.tolist()}")
        if not (np.isfinite(self.max_range_m) and self.max_range_m > 0.0):
            raise InputError(f"max_range_m must be a positive number, got {self.max_range_m}")
        b.setflags(write=False)
        object.__setattr__(self, "bearings_rad", b)
        object.__setattr__(self, "max_range_m", float(self.max_range_m))

    @classmethod
    def ring(cls, beams: int, fov_deg: float, max_range_m: float) -> Scanner:
        """``beams`` bearings spread evenly over ``fov_deg`` centred on the heading (a
        360-degree field of view does not repeat its first beam)."""
        if beams < 1:
            raise InputError(f"beams must be >= 1, got {beams}")
        fov = np.deg2rad(fov_deg)
        if fov_deg >= 360.0:
            b = -np.pi + fov / beams * np.arange(beams)
        else:
            b = np.linspace(-fov / 2, fov / 2, beams) if beams > 1 else np.zeros(1)
        return cls(b, max_range_m)


def check_ranges(ranges_m: ArrayLike, scanner: Scanner, lead: int) -> FloatArray:
    r = np.asarray(ranges_m, dtype=float)
    b = scanner.bearings_rad.size
    if r.ndim != 2 or r.shape != (lead, b):
        raise InputError(f"ranges_m must have shape ({lead}, {b}), got {r.shape}")
    if np.any(np.isnan(r)) or np.any(r < 0.0):
        raise InputError("ranges_m must be >= 0 or inf (no return), got NaN or a negative")
    return r


def scan_endpoints(
    poses: ArrayLike, ranges_m: ArrayLike, scanner: Scanner
) -> tuple[FloatArray, BoolArray]:
    """Where each beam ends, and whether it returned.

    Parameters
    ----------
    poses : array_like, shape (N, 3)
        x [m], y [m], heading [rad] of the sensor.
    ranges_m : array_like, shape (N, B)
        Ranges [m]; ``inf`` or ``>= max_range_m``: no return.
    scanner : Scanner

    Returns
    -------
    xy_m : ndarray, shape (N, B, 2)
        The hit, or for a no-return beam the point at the maximum range [m].
    hit : ndarray of bool, shape (N, B)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import Scanner, scan_endpoints
    >>> scanner = Scanner(np.array([0.0, np.pi / 2]), max_range_m=4.0)
    >>> xy, hit = scan_endpoints([[1.0, 0.0, 0.0]], [[2.0, np.inf]], scanner)
    >>> xy.round(12).tolist(), hit.tolist()
    ([[[3.0, 0.0], [1.0, 4.0]]], [[True, False]])
    """
    p = as_float_array(poses, "poses", (None, 3))
    r = check_ranges(ranges_m, scanner, p.shape[0])
    hit = r < scanner.max_range_m
    dist = np.where(hit, r, scanner.max_range_m)
    ang = p[:, 2:3] + scanner.bearings_rad
    xy = np.stack([p[:, 0:1] + dist * np.cos(ang), p[:, 1:2] + dist * np.sin(ang)], axis=-1)
    return xy, hit


def mapping_step(
    log_odds: NDArray[np.float32],
    poses: ArrayLike,
    ranges_m: ArrayLike,
    grid: OccupancyGrid,
    scanner: Scanner,
    params: LogOddsParams | None = None,
) -> NDArray[np.float32]:
    """Each robot's map after one scan from a known pose.

    Parameters
    ----------
    log_odds : ndarray of float32, shape (N, H, W)
        Each robot's log-odds map (zeros: nothing observed), on ``grid``'s cells.
    poses : array_like, shape (N, 3)
        The sensors' poses x [m], y [m], heading [rad].
    ranges_m : array_like, shape (N, B)
        The scans [m] (``inf``: no return).
    grid : OccupancyGrid
        Gives the cells (its contents are not used).
    scanner : Scanner
    params : LogOddsParams, optional

    Returns
    -------
    ndarray of float32, shape (N, H, W)
        The updated maps (a new array).

    Examples
    --------
    A beam from x = 0.25 m along a row of 0.5 m cells returns at 1 m (x = 1.25 m): two
    free cells, the hit, nothing beyond.

    >>> import numpy as np
    >>> from firefleet.estimation.grid import LogOddsParams, Scanner, mapping_step
    >>> from firefleet.world import OccupancyGrid
    >>> grid = OccupancyGrid(np.zeros((1, 4), bool), np.ones((1, 4), bool), 0.5)
    >>> scanner = Scanner(np.zeros(1), max_range_m=3.0)
    >>> maps = mapping_step(np.zeros((1, 1, 4), np.float32), [[0.25, 0.25, 0.0]],
    ...                     [[1.0]], grid, scanner)
    >>> np.sign(maps[0]).tolist()  # -1 free, +1 occupied, 0 unknown
    [[-1.0, -1.0, 1.0, 0.0]]
    """
    prm = params if params is not None else LogOddsParams()
    maps = np.asarray(log_odds, dtype=np.float32)
    p = as_float_array(poses, "poses", (None, 3))
    n = p.shape[0]
    if maps.shape != (n, *grid.shape):
        raise InputError(
            f"log_odds must have shape ({n}, {grid.shape[0]}, {grid.shape[1]}), got {maps.shape}"
        )
    xy, hit = scan_endpoints(p, ranges_m, scanner)
    ang = p[:, 2:3] + scanner.bearings_rad  # a hit on a cell's face belongs to the cell behind
    xy += _NUDGE_M * np.stack([np.cos(ang), np.sin(ang)], axis=-1)
    ends = grid.cell_of(xy)
    starts = grid.cell_of(p[:, :2])
    keep = hit | (prm.no_return == "free")
    out = maps.copy()
    marks = np.zeros(grid.shape, dtype=np.int8)
    for i in range(n):
        k = keep[i]
        scan_update(
            out[i],
            marks,
            int(starts[i, 0]),
            int(starts[i, 1]),
            np.ascontiguousarray(ends[i, k, 0]),
            np.ascontiguousarray(ends[i, k, 1]),
            np.ascontiguousarray(hit[i, k]),
            prm.l_free,
            prm.l_occ,
            -prm.clamp,
            prm.clamp,
        )
    return out


def merge_log_odds(log_odds: ArrayLike, clamp: float = 10.0) -> NDArray[np.float32]:
    """The team's map: the sum of the robots' log odds (prior 0), clamped.

    Parameters
    ----------
    log_odds : array_like, shape (N, H, W)
    clamp : float
        Bound on the merged log odds.

    Returns
    -------
    ndarray of float32, shape (H, W)

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import merge_log_odds
    >>> merge_log_odds([[[0.75, -0.5, 0.0]], [[0.75, 0.75, 0.0]]]).tolist()
    [[1.5, 0.25, 0.0]]
    """
    m = np.asarray(log_odds, dtype=np.float32)
    if m.ndim != 3:
        raise InputError(f"log_odds must have shape (N, H, W), got {m.shape}")
    return np.asarray(np.clip(m.sum(axis=0), -clamp, clamp), dtype=np.float32)


def occupancy_probability(log_odds: ArrayLike) -> FloatArray:
    """``p = 1 - 1 / (1 + exp(l))`` per cell, same shape (0.5: never observed).

    Examples
    --------
    >>> from firefleet.estimation.grid import occupancy_probability
    >>> occupancy_probability([0.0, 100.0, -100.0]).tolist()
    [0.5, 1.0, 0.0]
    """
    lo = np.asarray(log_odds, dtype=np.float64)
    return np.asarray(0.5 * (1.0 + np.tanh(0.5 * lo)), dtype=np.float64)


def map_agreement_pct(estimate: ArrayLike, truth: OccupancyGrid) -> float:
    """Share of the observed cells classified as the ground truth [%].

    Parameters
    ----------
    estimate : array_like, shape (H, W)
        Occupancy probability (0.5: not observed; above: occupied; below: free).
    truth : OccupancyGrid
        The ground truth on the same cells (an unknown cell counts as not occupied:
        sensors see through it).

    Returns
    -------
    float
        ``100 * #(observed cells whose class matches) / #(observed cells)``; NaN when no
        cell was observed.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import map_agreement_pct
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.array([[True, False, False, False]])
    >>> truth = OccupancyGrid(occ, ~occ, 0.1)
    >>> map_agreement_pct([[0.9, 0.1, 0.8, 0.5]], truth)  # 2 of the 3 observed cells
    66.66666666666667
    """
    p = np.asarray(estimate, dtype=np.float64)
    if p.shape != truth.shape:
        raise InputError(f"estimate must have the truth's shape {truth.shape}, got {p.shape}")
    observed = p != 0.5
    if not observed.any():
        return float("nan")
    agree = (p > 0.5) == truth.occupied
    return float(100.0 * np.count_nonzero(agree & observed) / np.count_nonzero(observed))

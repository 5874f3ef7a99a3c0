"""The likelihood field range model (Thrun et al. 2005, sec. 6.4, Table 6.3).

A beam's end point is scored by its distance ``d`` to the nearest occupied cell, read
from a distance transform of the map: ``p = z_hit N(d; 0, sigma_hit^2) + z_rand / z_max``
(the Gaussian is the hit, the uniform term random returns). Beams without a return add
nothing: a max-range reading says little in this model, and leaving them out is what
the model's authors do (Table 6.3, line 4). End points off the map score as the
farthest distance the field holds. A pose on an occupied or off-map cell is impossible
(log likelihood ``-inf`` made finite: ``IMPOSSIBLE``).

The kernel :func:`scan_log_likelihood` scores P poses against one scan; the same kernel
serves MCL's particles and the SLAM scan matcher's candidates.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from dataclasses import field as dataclass_field

import numpy as np
from numba import njit
from numpy.typing import NDArray
from scipy import ndimage

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.estimation.grid._rays import cell_rc, grid_frame
from firefleet.world import OccupancyGrid

__all__ = ["IMPOSSIBLE", "LikelihoodField", "likelihood_field"]

IMPOSSIBLE = -1e6
"""Log likelihood of a pose inside a wall or off the map."""


@dataclass(frozen=True, eq=False)
class LikelihoodField:
    """A map's distance transform and the cells a robot may stand on.

    Attributes
    ----------
    grid : OccupancyGrid
    distance_m : ndarray of float32, shape (H, W)
        Distance from each cell's centre to the nearest occupied cell's centre [m],
        capped at ``max_distance_m``.
    max_distance_m : float
    blocked : ndarray of bool, shape (H, W)
        Cells a robot cannot stand on (occupied or unknown).
    """

    grid: OccupancyGrid
    distance_m: NDArray[np.float32]
    max_distance_m: float
    blocked: NDArray[np.bool_]
    _tables: dict[tuple[float, float, float, float], NDArray[np.float64]] = dataclass_field(
        default_factory=dict, repr=False
    )

    def log_table(
        self, sigma_m: float, z_hit: float, z_rand: float, max_range_m: float
    ) -> NDArray[np.float64]:
        """Each cell's log likelihood of holding a beam's end, (H, W), computed once per
        model and kept: ``log(z_hit N(d; 0, sigma^2) + z_rand / max_range)``."""
        key = (float(sigma_m), float(z_hit), float(z_rand), float(max_range_m))
        if key not in self._tables:
            d = self.distance_m.astype(np.float64)
            norm = z_hit / (np.sqrt(2.0 * np.pi) * sigma_m)
            self._tables[key] = np.log(
                norm * np.exp(-0.5 * (d / sigma_m) ** 2) + z_rand / max_range_m
            )
        return self._tables[key]


def likelihood_field(grid: OccupancyGrid, max_distance_m: float = 2.0) -> LikelihoodField:
    """The distance transform of ``grid``'s occupied cells (exact Euclidean, scipy).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.estimation.grid import likelihood_field
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((1, 5), bool); occ[0, 0] = True
    >>> likelihood_field(OccupancyGrid(occ, ~occ, 0.5), 1.2).distance_m.tolist()
    [[0.0, 0.5, 1.0, 1.2000000476837158, 1.2000000476837158]]
    """
    if not (np.isfinite(max_distance_m) and max_distance_m > 0.0):
        raise InputError(f"max_distance_m must be a positive number, got {max_distance_m}")
    if grid.occupied.any():
        d = ndimage.distance_transform_edt(~grid.occupied) * grid.resolution_m
    else:
        d = np.full(grid.shape, max_distance_m)
    dist = np.minimum(d, max_distance_m).astype(np.float32)
    return LikelihoodField(
        grid=grid, distance_m=dist, max_distance_m=float(max_distance_m), blocked=~grid.free
    )


@njit(cache=True)
def scan_log_likelihood(
    poses: np.ndarray,
    ranges: np.ndarray,
    bearings: np.ndarray,
    table: np.ndarray,
    blocked: np.ndarray,
    ox: float,
    oy: float,
    res: float,
    max_range: float,
    off_map: float,
    out: np.ndarray,
) -> None:
    """``out[p]`` = the scan's log likelihood at ``poses[p]`` (P, 3) from the per-cell
    log likelihoods ``table`` (H, W) (``off_map`` for an end off the grid); ``blocked``
    (H, W) marks the cells a pose cannot be on."""
    h, w = table.shape
    for p in range(poses.shape[0]):
        x, y, th = poses[p, 0], poses[p, 1], poses[p, 2]
        r0, c0 = cell_rc(x, y, ox, oy, res, h)
        if r0 < 0 or r0 >= h or c0 < 0 or c0 >= w or blocked[r0, c0]:
            out[p] = IMPOSSIBLE
            continue
        total = 0.0
        for b in range(ranges.shape[0]):
            z = ranges[b]
            if not z < max_range:
                continue
            a = th + bearings[b]
            r, c = cell_rc(x + z * math.cos(a), y + z * math.sin(a), ox, oy, res, h)
            total += table[r, c] if 0 <= r < h and 0 <= c < w else off_map
        out[p] = total


def field_log_likelihood(
    field: LikelihoodField,
    poses: FloatArray,
    ranges_m: FloatArray,
    bearings_rad: FloatArray,
    max_range_m: float,
    sigma_m: float,
    z_hit: float,
    z_rand: float,
) -> FloatArray:
    """Log likelihood (P,) of one scan (B,) at each pose (P, 3) (see the module notes)."""
    ox, oy, res, _, _ = grid_frame(field.grid)
    table = field.log_table(sigma_m, z_hit, z_rand, max_range_m)
    dmax = field.max_distance_m
    off_map = float(
        np.log(
            z_hit / (np.sqrt(2 * np.pi) * sigma_m) * np.exp(-0.5 * (dmax / sigma_m) ** 2)
            + z_rand / max_range_m
        )
    )
    out = np.empty(poses.shape[0])
    scan_log_likelihood(
        np.ascontiguousarray(poses, dtype=np.float64),
        np.ascontiguousarray(ranges_m, dtype=np.float64),
        np.ascontiguousarray(bearings_rad, dtype=np.float64),
        table,
        field.blocked,
        ox,
        oy,
        res,
        max_range_m,
        off_map,
        out,
    )
    return out

"""The costmap A* plans on: the map inflated by the robot's disc, and a wall cost.

A cell is *blocked* when it is not free (occupied or unknown) or when its centre lies
within ``inflation_m`` (robot radius + margin) of the centre of a non-free cell: the
exact disc, from the Euclidean distance transform (``scipy.ndimage``), not a square
kernel. Every other cell costs ``1 + wall_weight * exp(-(c - inflation_m) / wall_decay_m)``
per metre travelled, with ``c`` its clearance (the same distance [m]): the cost falls
from ``1 + wall_weight`` at the edge of the inflated region to 1 in open space, so
robots keep off walls where there is room and still squeeze through doors (the shape of
ROS ``costmap_2d``'s inflation layer; the default decay, 0.1 m, is its default
``cost_scaling_factor`` of 10 per metre).

References
----------
Lu, Hershberger, Smart, "Layered costmaps for context-sensitive navigation", IROS 2014
(the inflation layer's exponential cost).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import ndimage

from firefleet._typing import BoolArray, FloatArray
from firefleet.errors import InputError
from firefleet.world import OccupancyGrid

__all__ = ["Costmap", "build_costmap"]


@dataclass(frozen=True, eq=False)
class Costmap:
    """A grid ready for planning.

    Attributes
    ----------
    grid : OccupancyGrid
        The map it was built from (the cell <-> metre conversion).
    clearance_m : ndarray, shape (H, W)
        Distance from each cell's centre to the nearest non-free cell's centre [m]
        (0 on non-free cells); the map's outside counts as non-free.
    blocked : ndarray of bool, shape (H, W)
        Cells the robot's centre may not enter: ``clearance_m <= inflation_m``.
    cost : ndarray, shape (H, W)
        Cost per metre of each unblocked cell (>= 1; ``inf`` where blocked).
    inflation_m : float
        Robot radius + margin [m].

    Notes
    -----
    :func:`~firefleet.control.navigation.astar` keeps the paths it found on a costmap
    in the costmap (``_astar_memo``, keyed by the start and goal cells, the last 64)
    when its ``cost`` cannot change (read-only, and so is the array holding its data,
    as in every costmap built here): the mission asks the same plan again and again (a
    robot retargeted to the goal it stands before, 10 times a second), each ~10 ms on
    the 0.05 m office.
    """

    grid: OccupancyGrid
    clearance_m: FloatArray
    blocked: BoolArray
    cost: FloatArray
    inflation_m: float
    _astar_memo: dict[Any, Any] = field(default_factory=dict, init=False, repr=False, compare=False)


def build_costmap(
    grid: OccupancyGrid,
    inflation_m: float,
    *,
    wall_weight: float = 2.0,
    wall_decay_m: float = 0.1,
) -> Costmap:
    """Inflate a map by the robot's disc and price the cells near walls.

    Parameters
    ----------
    grid : OccupancyGrid
        The map.
    inflation_m : float
        Robot radius + safety margin [m] (>= 0).
    wall_weight : float
        Extra cost per metre at the edge of the inflated region (>= 0; 0 plans the
        shortest path).
    wall_decay_m : float
        Distance over which the extra cost falls by e [m] (> 0).

    Returns
    -------
    Costmap

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> occ = np.zeros((5, 7), dtype=bool)
    >>> occ[:, 0] = True  # a wall down the left edge
    >>> cm = build_costmap(OccupancyGrid(occ, ~occ, 0.1), inflation_m=0.15)
    >>> cm.clearance_m[2].round(2).tolist()  # off the map counts as a wall
    [0.0, 0.1, 0.2, 0.3, 0.3, 0.2, 0.1]
    >>> cm.blocked[2].tolist()
    [True, True, False, False, False, False, True]
    """
    if not (np.isfinite(inflation_m) and inflation_m >= 0.0):
        raise InputError(f"inflation_m must be a number of metres >= 0, got {inflation_m!r}")
    if not (np.isfinite(wall_weight) and wall_weight >= 0.0):
        raise InputError(f"wall_weight must be >= 0, got {wall_weight!r}")
    if not (np.isfinite(wall_decay_m) and wall_decay_m > 0.0):
        raise InputError(f"wall_decay_m must be > 0, got {wall_decay_m!r}")
    # the map's outside counts as occupied (a map_server map ends where the known
    # world does; the collision metrics count it so): one occupied cell round the map
    free = np.pad(np.asarray(grid.free), 1, constant_values=False)
    clearance = np.asarray(ndimage.distance_transform_edt(free))[1:-1, 1:-1] * grid.resolution_m
    blocked = clearance <= inflation_m
    with np.errstate(over="ignore"):
        extra = wall_weight * np.exp(-(np.minimum(clearance, 1e9) - inflation_m) / wall_decay_m)
    cost = np.where(blocked, np.inf, 1.0 + extra)
    for arr in (clearance, blocked, cost):
        arr.setflags(write=False)
    return Costmap(grid, clearance, blocked, cost, float(inflation_m))

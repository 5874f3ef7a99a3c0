"""The team's hot places on the navigation's costmap: every path keeps out of them.

The fires' spots are priced by :func:`._fight.fire_costmap` (``fire_cost`` per metre
within ``fire_keepout_m`` of a spot, ten times that within ``fire_block_m``). The hot
places (:mod:`._hot`: where a robot's air reached the retreat temperature, or its camera
saw flames within the guard distance) are where the heat was *measured*, often farther
out than any spot (the hot gas a fire pushes through its door), and they were on no
costmap: a path crossed them at the price of open floor. Here every live hot place
(:func:`._hot.live_hot`) adds ``hot_cost`` per metre within ``hot_keepout_m`` of it, so
A* goes round it wherever there is another way; where there is none (the robot's slot
or goal lies beyond it, or in it) the path still crosses it, at its cheapest, since the
price is a cost and not a wall.

The price stays on every plan the navigation makes from this costmap: the first plan,
the re-plans when a robot strays or stalls, and those round its teammates' discs
(:func:`firefleet.control.navigation._team._with_teammates` keeps a costmap's price
beyond its walls; on mission-office seed 2 a fighter stalled behind a teammate by the
fire room's door was re-planned round that teammate on a costmap that had lost the
fire's price within 2.35 m of the teammate, drove through the door's flames and was
damaged).
"""

from __future__ import annotations

import numpy as np

from firefleet._frozen import replace
from firefleet._typing import BoolArray, FloatArray
from firefleet.control.mission._discs import disc_cells
from firefleet.control.mission._hot import live_hot
from firefleet.control.mission._params import TacticsParams
from firefleet.control.mission._team import TacticsState
from firefleet.control.navigation import Costmap
from firefleet.world import OccupancyGrid

__all__ = ["heat_costmap", "near_points"]


def near_points(grid: OccupancyGrid, xy_m: FloatArray, radius_m: float) -> BoolArray:
    """Map cells (H, W) whose centres lie within ``radius_m`` of any point (K, 2) [m]
    (:func:`._discs.disc_cells`, the fires' discs; none for a radius of 0).

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.world import OccupancyGrid
    >>> g = OccupancyGrid(np.zeros((10, 10), bool), np.ones((10, 10), bool), 0.1)
    >>> int(near_points(g, np.array([[0.55, 0.55]]), 0.2).sum())  # a centre, 4 + 4 + 4 more
    13
    """
    pts = np.asarray(xy_m, dtype=float).reshape(-1, 2)
    if len(pts) == 0 or radius_m <= 0.0:
        return np.zeros(grid.shape, dtype=bool)
    return disc_cells(grid, pts, radius_m)


def heat_costmap(state: TacticsState, params: TacticsParams) -> TacticsState:
    """The navigation's costmap with ``hot_cost`` per metre more within
    ``hot_keepout_m`` of every live hot place (module notes); unchanged without one.

    Call it after :func:`._fight.fire_costmap`, which builds the costmap anew from the
    map's (so the price is never added twice).

    Parameters
    ----------
    state : TacticsState
    params : TacticsParams

    Returns
    -------
    TacticsState
    """
    live = live_hot(state.hot_xy_m, state.hot_s, state.t_s, params.hot_forget_s)
    if len(live) == 0 or params.hot_cost <= 0.0 or params.hot_keepout_m <= 0.0:
        return state
    now = state.nav.costmap
    near = near_points(now.grid, live, params.hot_keepout_m) & ~now.blocked
    if not near.any():
        return state
    cost = np.array(now.cost)
    cost[near] += params.hot_cost
    cost.setflags(write=False)
    costmap = Costmap(now.grid, now.clearance_m, now.blocked, cost, now.inflation_m)
    return replace(state, nav=replace(state.nav, costmap=costmap))

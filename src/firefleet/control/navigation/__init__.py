"""Navigation around obstacles: global A* on an inflated map, smoothing, the dynamic window.

Public surface::

    build_costmap(grid, inflation_m) -> Costmap       inflate the map, price the walls
    astar(costmap, start_xy_m, goal_xy_m) -> AStarResult
    astar_cells(cost, start, goal, resolution_m)      the bare compiled search
    smooth_path(costmap, xy_m) -> PlanarPath          shortcut + rounded corners
"""

from firefleet.control.navigation._astar import AStarResult, astar, astar_cells
from firefleet.control.navigation._costmap import Costmap, build_costmap
from firefleet.control.navigation._smooth import clearance_along, smooth_path

__all__ = [
    "AStarResult",
    "Costmap",
    "astar",
    "astar_cells",
    "build_costmap",
    "clearance_along",
    "smooth_path",
]

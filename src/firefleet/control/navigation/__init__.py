"""Navigation around obstacles: global A* on an inflated map, smoothing, the dynamic window.

Public surface::

    build_costmap(grid, inflation_m) -> Costmap       inflate the map, price the walls
    astar(costmap, start_xy_m, goal_xy_m) -> AStarResult
    astar_cells(cost, start, goal, resolution_m)      the bare compiled search
    smooth_path(costmap, xy_m) -> PlanarPath          shortcut + rounded corners
    dwa_command(pose, last, reference, obstacles, radii, params, dt_s[, stuck])  the dynamic window

The team controller the ``navigate`` task kind calls each tick::

    params = NavigationParams()                       # frozen; Table 2 motors at 12 V
    state = navigation_init(grid, poses, goals_m, params)
    state, v_m_s, omega_rad_s = navigation_step(state, inputs, params, dt_s)
    state = navigation_retarget(state, goals_m, which)   # new goals for some robots

with ``inputs = NavigationInputs(pose (N, 3), ranges {name: (ranges (N, B), bearings (B,)
or (N, B))}, teammates_xy_m (N, 2), t_s)``; ``state.status`` per robot is one of
``moving, waiting, arrived, unreachable, start_blocked, goal_blocked``. How the stages
combine (A* -> smoothing -> fuzzy follower -> give way -> DWA, re-planning when stuck)
is written in :mod:`firefleet.control.navigation._team`.
"""

from firefleet.control.navigation._astar import AStarResult, astar, astar_cells
from firefleet.control.navigation._costmap import Costmap, build_costmap
from firefleet.control.navigation._dwa import DwaParams, dwa_command, dwa_limits_from_motor
from firefleet.control.navigation._smooth import clearance_along, smooth_path
from firefleet.control.navigation._step import navigation_step
from firefleet.control.navigation._team import (
    STATUSES,
    NavigationInputs,
    NavigationParams,
    NavigationState,
    navigation_init,
    navigation_retarget,
)

__all__ = [
    "STATUSES",
    "AStarResult",
    "Costmap",
    "DwaParams",
    "NavigationInputs",
    "NavigationParams",
    "NavigationState",
    "astar",
    "astar_cells",
    "build_costmap",
    "clearance_along",
    "dwa_command",
    "dwa_limits_from_motor",
    "navigation_init",
    "navigation_retarget",
    "navigation_step",
    "smooth_path",
]

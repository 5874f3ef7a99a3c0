"""The world the robots move in: building maps (ROS ``map_server`` format).

The grid convention (row 0 at the map's top, ``origin`` at the lower-left corner) lives
in :class:`OccupancyGrid` alone.
"""

from firefleet.world._grid import OccupancyGrid

__all__ = ["OccupancyGrid"]

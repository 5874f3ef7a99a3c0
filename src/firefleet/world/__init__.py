"""The world the robots move in: building maps (ROS ``map_server`` format).

The grid convention (row 0 at the map's top, ``origin`` at the lower-left corner) lives
in :class:`OccupancyGrid` alone. :func:`load_map` reads a built-in map (``office``,
``warehouse``, ``maze``) or any ``map_server`` YAML with its PGM or PNG image.
"""

from firefleet.world._grid import OccupancyGrid
from firefleet.world._load import BUILTIN_MAPS, load_map, parse_map

__all__ = ["BUILTIN_MAPS", "OccupancyGrid", "load_map", "parse_map"]

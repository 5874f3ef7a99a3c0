"""The world the robots move in: building maps (ROS ``map_server`` format), and the
fire, heat and smoke on them, and the people in them.

The grid convention (row 0 at the map's top, ``origin`` at the lower-left corner) lives
in :class:`OccupancyGrid` alone. :func:`load_map` reads a built-in map (``office``,
``warehouse``, ``maze``) or any ``map_server`` YAML with its PGM or PNG image.
"""

from firefleet.world._fields import HEAT, SMOKE, FieldParams, diffuse_step, stable_substeps
from firefleet.world._fire import (
    BURNING,
    BURNT,
    UNBURNT,
    FireParams,
    FireState,
    corridor_front_speed,
    fire_init,
    fire_step,
)
from firefleet.world._grid import OccupancyGrid, coarsen
from firefleet.world._load import BUILTIN_MAPS, load_map, parse_map
from firefleet.world._spray import SprayParams, spray_step
from firefleet.world._victims import (
    BODY_C,
    VictimParams,
    VictimState,
    victim_dose_rate,
    victim_step,
)

__all__ = [
    "BODY_C",
    "BUILTIN_MAPS",
    "BURNING",
    "BURNT",
    "HEAT",
    "SMOKE",
    "UNBURNT",
    "FieldParams",
    "FireParams",
    "FireState",
    "OccupancyGrid",
    "SprayParams",
    "VictimParams",
    "VictimState",
    "coarsen",
    "corridor_front_speed",
    "diffuse_step",
    "fire_init",
    "fire_step",
    "load_map",
    "parse_map",
    "spray_step",
    "stable_substeps",
    "victim_dose_rate",
    "victim_step",
]

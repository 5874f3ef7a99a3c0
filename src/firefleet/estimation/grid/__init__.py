"""Mapping and localisation on an occupancy grid (issue 14, point 4).

- occupancy mapping with known poses (log odds, Thrun et al. 2005 ch. 9), per robot
  and merged for the team;
- Monte Carlo localisation on a known map (likelihood field, augmented MCL, global
  localisation from a uniform prior);
- grid SLAM: a Rao-Blackwellised particle filter with a scan-matched proposal and
  per-particle maps (GMapping, Grisetti et al. 2007);
- the world loop's stages for all three.
"""

from firefleet.estimation.grid._mapping import (
    LogOddsParams,
    Scanner,
    map_agreement_pct,
    mapping_step,
    merge_log_odds,
    occupancy_probability,
    scan_endpoints,
)

__all__ = [
    "LogOddsParams",
    "Scanner",
    "map_agreement_pct",
    "mapping_step",
    "merge_log_odds",
    "occupancy_probability",
    "scan_endpoints",
]

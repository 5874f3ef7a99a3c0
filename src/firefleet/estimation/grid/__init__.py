"""Mapping and localisation on an occupancy grid (issue 14, point 4).

- occupancy mapping with known poses (log odds, Thrun et al. 2005 ch. 9), per robot
  and merged for the team;
- Monte Carlo localisation on a known map (likelihood field, augmented MCL, global
  localisation from a uniform prior);
- grid SLAM: a Rao-Blackwellised particle filter with a scan-matched proposal and
  per-particle maps (GMapping, Grisetti et al. 2007);
- the world loop's stages for all three.
"""

from firefleet.estimation.grid._likelihood import (
    LikelihoodField,
    field_log_likelihood,
    likelihood_field,
)
from firefleet.estimation.grid._mapping import (
    LogOddsParams,
    Scanner,
    map_agreement_pct,
    mapping_step,
    merge_log_odds,
    occupancy_probability,
    scan_endpoints,
)
from firefleet.estimation.grid._mcl import (
    GridMclParams,
    MclState,
    free_cell_poses,
    mcl_estimate,
    mcl_global,
    mcl_step,
    mcl_tracking,
)
from firefleet.estimation.grid._slam import (
    GridSlamParams,
    GridSlamState,
    slam_estimate,
    slam_init,
    slam_map,
    slam_step,
)
from firefleet.estimation.grid._stages import (
    GridSlamEstimation,
    MappingEstimation,
    MclEstimation,
    ScanFilterState,
)

__all__ = [
    "GridMclParams",
    "GridSlamEstimation",
    "GridSlamParams",
    "GridSlamState",
    "LikelihoodField",
    "LogOddsParams",
    "MappingEstimation",
    "MclEstimation",
    "MclState",
    "ScanFilterState",
    "Scanner",
    "field_log_likelihood",
    "free_cell_poses",
    "likelihood_field",
    "map_agreement_pct",
    "mapping_step",
    "mcl_estimate",
    "mcl_global",
    "mcl_step",
    "mcl_tracking",
    "merge_log_odds",
    "occupancy_probability",
    "scan_endpoints",
    "slam_estimate",
    "slam_init",
    "slam_map",
    "slam_step",
]

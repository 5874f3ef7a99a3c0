"""The world loop's estimation stages on a grid: known-pose mapping, MCL, grid SLAM.

Each follows :class:`firefleet.sim.loop.Estimation` (``init(pose, drive)``,
``step(state, drive, stack, readings)``, ``pose(state)``) for the whole team (N robots,
one filter each). The odometry increments come from the wheel encoders exactly as the
loop's :class:`~firefleet.sim.loop.Odometry` takes them (:func:`~firefleet.sim.drive.
dead_reckoning` of the count differences, nominal geometry). A filter updates every
``period_s`` (the scan rate) with the odometry increment accumulated since its last
update and the scan the sensors stage gave this tick under the name ``reading`` (a
(N, B) array of ranges [m], ``inf`` for no return); between updates the pose estimate
is the last update's estimate moved by the odometry since.

For the kind to record: ``occupancy(state)`` (the team's map, occupancy probability
(H, W)), ``robot_occupancy(state)`` (N, H, W) and ``particles(state)`` (N, P, 3), the
clouds padded with NaN to the largest count.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray
from firefleet.errors import InputError
from firefleet.estimation.grid._likelihood import LikelihoodField, likelihood_field
from firefleet.estimation.grid._mapping import (
    LogOddsParams,
    Scanner,
    mapping_step,
    merge_log_odds,
    occupancy_probability,
)
from firefleet.estimation.grid._mcl import (
    GridMclParams,
    MclState,
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
from firefleet.estimation.particle_filter import compose
from firefleet.sim.drive import DriveStack, DriveState, dead_reckoning
from firefleet.sim.loop import Messages
from firefleet.world import OccupancyGrid

__all__ = ["GridSlamEstimation", "MappingEstimation", "MclEstimation", "ScanFilterState"]


@dataclass(frozen=True, eq=False)
class ScanFilterState:
    """A scan-rate estimator's state in the loop.

    Attributes
    ----------
    estimate : ndarray, shape (N, 3)
        The poses at the last update.
    counts : ndarray, shape (N, 2)
        The encoder counts at the last update.
    odometry : ndarray, shape (N, 3)
        The odometry increment since the last update (dx, dy in the pose's frame [m],
        dtheta [rad]).
    elapsed_s : float
        Time since the last update [s].
    filters : tuple
        One filter state per robot (:class:`MclState`, :class:`GridSlamState`), or the
        maps (N, H, W) of known-pose mapping.
    rng : numpy.random.Generator
    """

    estimate: FloatArray
    counts: FloatArray
    odometry: FloatArray
    elapsed_s: float
    filters: tuple[object, ...]
    rng: np.random.Generator


def _scan(readings: Messages, name: str, n: int, stage: str) -> FloatArray:
    if name not in readings:
        raise InputError(
            f"{stage} needs the sensor reading {name!r}; the sensors gave {sorted(readings)}"
        )
    return np.asarray(readings[name], dtype=np.float64).reshape(n, -1)


def _advance(
    state: ScanFilterState, drive: DriveState, stack: DriveStack, period_s: float
) -> tuple[FloatArray, FloatArray, float, bool]:
    """The odometry since the last update, the counts now, the time, and whether the
    filters update this tick."""
    counts = drive.encoder.history[-1]
    n = counts.shape[0]
    delta = dead_reckoning(np.zeros((n, 3)), state.counts, counts, stack)
    total = compose(state.odometry, delta)  # the increments chain in the robot's frame
    elapsed = state.elapsed_s + stack.dt_s
    return total, counts, elapsed, elapsed >= period_s - 1e-9


def _start(
    pose: FloatArray,
    drive: DriveState,
    filters: tuple[object, ...],
    rng: np.random.Generator,
    estimate: FloatArray | None = None,
) -> ScanFilterState:
    n = pose.shape[0]
    return ScanFilterState(
        estimate=(pose if estimate is None else estimate).copy(),
        counts=drive.encoder.history[-1].copy(),
        odometry=np.zeros((n, 3)),
        elapsed_s=0.0,
        filters=filters,
        rng=rng,
    )


def _moved(
    state: ScanFilterState, total: FloatArray, counts: FloatArray, elapsed: float
) -> ScanFilterState:
    return ScanFilterState(state.estimate, counts, total, elapsed, state.filters, state.rng)


def _maps(state: ScanFilterState) -> NDArray[np.float32]:
    maps = state.filters[0]
    assert isinstance(maps, np.ndarray)
    return np.asarray(maps, dtype=np.float32)


def _pad(clouds: list[FloatArray]) -> FloatArray:
    m = max(c.shape[0] for c in clouds)
    out = np.full((len(clouds), m, 3), np.nan)
    for i, c in enumerate(clouds):
        out[i, : c.shape[0]] = c
    return out


@dataclass(frozen=True, eq=False)
class MappingEstimation:
    """Occupancy mapping with known poses: odometry's pose estimate, and each robot's
    map from its scans at its true pose (the loop's ground truth), merged for the team.

    Attributes
    ----------
    grid : OccupancyGrid
        The maps' cells (contents unused).
    scanner : Scanner
    reading : str
        The sensors stage's reading holding the scans (N, B).
    period_s : float
        Time between map updates [s].
    params : LogOddsParams
    """

    grid: OccupancyGrid
    scanner: Scanner
    reading: str = "lidar_range_m"
    period_s: float = 0.1
    params: LogOddsParams = field(default_factory=LogOddsParams)

    def init(self, pose: FloatArray, drive: DriveState) -> ScanFilterState:
        """Empty maps; the estimate at the true start poses."""
        maps = np.zeros((pose.shape[0], *self.grid.shape), np.float32)
        return _start(pose, drive, (maps,), np.random.default_rng(0))

    def step(
        self, state: ScanFilterState, drive: DriveState, stack: DriveStack, readings: Messages
    ) -> ScanFilterState:
        """Odometry every tick; the maps every ``period_s``."""
        total, counts, elapsed, update = _advance(state, drive, stack, self.period_s)
        if not update:
            return _moved(state, total, counts, elapsed)
        n = counts.shape[0]
        z = _scan(readings, self.reading, n, "mapping")
        maps = mapping_step(
            _maps(state),
            drive.pose,
            z,
            self.grid,
            self.scanner,
            self.params,
        )
        est = compose(state.estimate, total)
        return ScanFilterState(est, counts, np.zeros((n, 3)), 0.0, (maps,), state.rng)

    def pose(self, state: ScanFilterState) -> FloatArray:
        """The odometry poses (N, 3)."""
        return compose(state.estimate, state.odometry)

    def robot_occupancy(self, state: ScanFilterState) -> FloatArray:
        """Each robot's map, occupancy probability (N, H, W)."""
        return occupancy_probability(_maps(state))

    def occupancy(self, state: ScanFilterState) -> FloatArray:
        """The team's map (summed log odds), occupancy probability (H, W)."""
        return occupancy_probability(merge_log_odds(_maps(state), self.params.clamp))


@dataclass(frozen=True, eq=False)
class MclEstimation:
    """Monte Carlo localisation of each robot on a known map.

    Attributes
    ----------
    grid : OccupancyGrid
        The known map.
    scanner : Scanner
    reading : str
        The sensors stage's reading holding the scans (N, B): ``"lidar_range_m"`` or
        ``"ultrasonic_range_m"``.
    period_s : float
        Time between filter updates [s].
    params : GridMclParams
    start : {"global", "pose"}
        A uniform prior over the free cells (global localisation), or particles around
        the true start pose (tracking).
    seed : int
        Seeds the filters' random generator.
    likelihood : LikelihoodField, optional
        The map's likelihood field, when already computed (else from ``grid``).
    """

    grid: OccupancyGrid
    scanner: Scanner
    reading: str = "lidar_range_m"
    period_s: float = 0.1
    params: GridMclParams = field(default_factory=GridMclParams)
    start: Literal["global", "pose"] = "global"
    seed: int = 0
    likelihood: LikelihoodField | None = None

    def _field(self) -> LikelihoodField:
        return self.likelihood if self.likelihood is not None else likelihood_field(self.grid)

    def init(self, pose: FloatArray, drive: DriveState) -> ScanFilterState:
        """One filter per robot; the estimate of a global start is the cloud's."""
        if self.start not in ("global", "pose"):
            raise InputError(f"localisation start must be 'global' or 'pose', got {self.start!r}")
        rng = np.random.default_rng(self.seed)
        fld = self._field()
        if self.start == "global":
            filters = tuple(mcl_global(fld, self.params, rng) for _ in range(pose.shape[0]))
        else:
            filters = tuple(mcl_tracking(p, self.params, rng) for p in pose)
        est = np.array([mcl_estimate(f, self.params) for f in filters])
        return _start(pose, drive, (fld, *filters), rng, est)

    def step(
        self, state: ScanFilterState, drive: DriveState, stack: DriveStack, readings: Messages
    ) -> ScanFilterState:
        """Odometry every tick; each robot's filter every ``period_s``."""
        total, counts, elapsed, update = _advance(state, drive, stack, self.period_s)
        if not update:
            return _moved(state, total, counts, elapsed)
        n = counts.shape[0]
        z = _scan(readings, self.reading, n, "mcl")
        fld = state.filters[0]
        assert isinstance(fld, LikelihoodField)
        new = []
        for i in range(n):
            f = state.filters[1 + i]
            assert isinstance(f, MclState)
            new.append(mcl_step(f, total[i], z[i], fld, self.scanner, self.params, state.rng))
        est = np.array([mcl_estimate(f, self.params) for f in new])
        return ScanFilterState(est, counts, np.zeros((n, 3)), 0.0, (fld, *new), state.rng)

    def pose(self, state: ScanFilterState) -> FloatArray:
        """The estimated poses (N, 3)."""
        return compose(state.estimate, state.odometry)

    def particles(self, state: ScanFilterState) -> FloatArray:
        """The particle clouds (N, P, 3), NaN-padded to the largest cloud."""
        return _pad([f.particles for f in state.filters[1:]])  # type: ignore[attr-defined]


@dataclass(frozen=True, eq=False)
class GridSlamEstimation:
    """Grid SLAM for each robot (its own map, anchored at its true start pose).

    Attributes
    ----------
    frame : OccupancyGrid
        The maps' cells (contents unused: the extent and resolution).
    scanner : Scanner
    reading : str
        The sensors stage's reading holding the scans (N, B).
    period_s : float
        Time between filter updates [s] (GMapping's scans arrive at 10 Hz or less).
    params : GridSlamParams
    seed : int
        Seeds the filters' random generator.
    """

    frame: OccupancyGrid
    scanner: Scanner
    reading: str = "lidar_range_m"
    period_s: float = 0.1
    params: GridSlamParams = field(default_factory=GridSlamParams)
    seed: int = 0

    def init(self, pose: FloatArray, drive: DriveState) -> ScanFilterState:
        """One filter per robot at its true start pose, empty maps."""
        filters = tuple(slam_init(self.frame, p, self.params) for p in pose)
        return _start(pose, drive, filters, np.random.default_rng(self.seed))

    def step(
        self, state: ScanFilterState, drive: DriveState, stack: DriveStack, readings: Messages
    ) -> ScanFilterState:
        """Odometry every tick; each robot's filter every ``period_s``."""
        total, counts, elapsed, update = _advance(state, drive, stack, self.period_s)
        if not update:
            return _moved(state, total, counts, elapsed)
        n = counts.shape[0]
        z = _scan(readings, self.reading, n, "slam")
        new = []
        for i in range(n):
            f = state.filters[i]
            assert isinstance(f, GridSlamState)
            new.append(
                slam_step(f, total[i], z[i], self.frame, self.scanner, self.params, state.rng)
            )
        est = np.array([slam_estimate(f) for f in new])
        return ScanFilterState(est, counts, np.zeros((n, 3)), 0.0, tuple(new), state.rng)

    def pose(self, state: ScanFilterState) -> FloatArray:
        """The estimated poses (N, 3)."""
        return compose(state.estimate, state.odometry)

    def robot_occupancy(self, state: ScanFilterState) -> FloatArray:
        """Each robot's map (its heaviest particle's), occupancy probability (N, H, W)."""
        return occupancy_probability(np.stack([slam_map(f) for f in state.filters]))  # type: ignore[arg-type]

    def occupancy(self, state: ScanFilterState) -> FloatArray:
        """The team's map (the robots' maps' summed log odds), occupancy probability (H, W)."""
        maps = np.stack([slam_map(f) for f in state.filters])  # type: ignore[arg-type]
        return occupancy_probability(merge_log_odds(maps, self.params.mapping.clamp))

    def particles(self, state: ScanFilterState) -> FloatArray:
        """The particles' poses (N, P, 3)."""
        return _pad([f.poses for f in state.filters])  # type: ignore[attr-defined]

"""The grid estimators as world-loop stages: encoder odometry, a ray-cast lidar, and
the loop's own drive stack (with wheel slip)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest

from firefleet.control.pid import PidParams
from firefleet.errors import InputError
from firefleet.estimation.grid import (
    GridMclParams,
    GridSlamEstimation,
    MappingEstimation,
    MclEstimation,
    Scanner,
    map_agreement_pct,
)
from firefleet.models import EncoderParams, MotorParams, RobotGeometry
from firefleet.sim.drive import discretise_drive, drive_init, drive_step, speed_control
from firefleet.sim.loop import Stages, StaticWorld, WheelCommand, WorldState, run_staged
from firefleet.world import OccupancyGrid
from tests.estimation.grid_world import cast, office

SCANNER = Scanner.ring(90, 360.0, 10.0)
START = np.array([[1.0, 4.0, 0.0]])  # the corridor's west end, facing east


@dataclass(frozen=True, eq=False)
class Lidar:
    """A sensors stage: the exact lidar of the test office, 1 cm noise."""

    grid: OccupancyGrid
    rng: np.random.Generator

    def read(self, world: WorldState, drive: Any) -> dict[str, np.ndarray]:
        z = cast(self.grid, drive.pose, SCANNER.bearings_rad, 10.0, 0.01, self.rng)
        return {"lidar_range_m": z}


def wheels(t_s: float) -> np.ndarray:
    """East along the corridor, a turn to the north, on into the north-west room."""
    if t_s < 3.3:
        return np.array([[10.0, 10.0]])
    if t_s < 4.17:
        return np.array([[4.0, -4.0]])  # a left turn on the spot (right wheel first)
    return np.array([[8.0, 8.0]])


def run(stage: Any, duration_s: float = 7.0) -> tuple[Any, np.ndarray, np.ndarray]:
    """The stage on the loop's drive stack (the loop's order); final state, true and
    estimated poses at each tick."""
    grid = office(0.05)
    stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    rng = np.random.default_rng(7)
    drive = drive_init(START, np.zeros((1, 2)), stack)
    sensors = Lidar(grid, rng)
    state = stage.init(drive.pose, drive)
    truth, est = [], []
    for k in range(round(duration_s / stack.dt_s) + 1):
        readings = sensors.read(WorldState(np.zeros((1, 2))), drive)
        if k > 0:
            state = stage.step(state, drive, stack, readings)
        truth.append(drive.pose[0].copy())
        est.append(stage.pose(state)[0].copy())
        drive, voltage = speed_control(drive, wheels(k * stack.dt_s), stack)
        drive = drive_step(drive, voltage, stack, rng=rng)
    return state, np.array(truth), np.array(est)


def test_mapping_stage_builds_the_map_at_the_true_poses() -> None:
    grid = office(0.05)
    stage = MappingEstimation(grid, SCANNER)
    state, truth, est = run(stage)
    assert truth[-1, 1] > 4.8  # the robot did go north into the room
    assert map_agreement_pct(stage.occupancy(state), grid) > 96.0  # 97.0 % measured
    assert stage.robot_occupancy(state).shape == (1, *grid.shape)
    np.testing.assert_allclose(est[0], START[0])  # odometry's pose from the start


def test_mcl_stage_localises_globally() -> None:
    grid = office(0.05)
    stage = MclEstimation(
        grid, SCANNER, params=GridMclParams(n_particles=8000, min_particles=300), seed=3
    )
    state, truth, est = run(stage)
    err = np.hypot(*(est[:, :2] - truth[:, :2]).T)
    assert err[0] > 0.3  # it did start from the uniform prior
    assert np.all(err[-200:] < 0.2)  # the last 2 s
    clouds = stage.particles(state)
    assert clouds.ndim == 3
    assert clouds.shape[2] == 3


def test_slam_stage_tracks_and_maps() -> None:
    grid = office(0.05)
    stage = GridSlamEstimation(grid, SCANNER, seed=1)
    state, truth, est = run(stage)
    err = np.hypot(*(est[:, :2] - truth[:, :2]).T)
    assert err.max() < 0.15
    assert map_agreement_pct(stage.occupancy(state), grid) > 93.0  # 94.9 % measured
    assert stage.particles(state).shape == (1, 30, 3)


def test_stages_plug_into_the_loop_and_need_their_reading() -> None:
    """run_staged hands the sensors' readings to the estimator (and its estimate to the
    kind); a missing reading names itself."""
    grid = office(0.1)
    stack = discretise_drive(RobotGeometry(), MotorParams(), PidParams(), EncoderParams(), 0.01)
    drive = drive_init(START, np.zeros((1, 2)), stack)

    def decide(state: Any, inputs: Any, params: Any, dt_s: float) -> tuple[Any, WheelCommand]:
        return state, WheelCommand(np.full((1, 2), 5.0), series={"est": inputs.pose_estimate})

    lidar = Lidar(grid, np.random.default_rng(0))
    stages = Stages(world=StaticWorld(), sensors=lidar, estimation=MappingEstimation(grid, SCANNER))
    rec = run_staged(drive, stack, stages, decide, None, None, np.array([0, 50]), 50)
    np.testing.assert_allclose(rec.series["est"][-1], rec.pose[-1], atol=0.01)
    assert stages.estimation.occupancy(rec.estimation_state).shape == grid.shape  # type: ignore[attr-defined]
    stages = Stages(world=StaticWorld(), estimation=MappingEstimation(grid, SCANNER))
    with pytest.raises(InputError, match="lidar_range_m"):
        run_staged(drive, stack, stages, decide, None, None, np.array([0, 50]), 50)

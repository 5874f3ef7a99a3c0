"""The mission kind: the issue's YAML as printed, bad input, the baseline, the world's
physics at the robots, and detections that come from the detector."""

from __future__ import annotations

import dataclasses
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import firefleet
from firefleet.sim.kinds._mission_world import LOWER_LAYER, lower_layer
from firefleet.sim.kinds.mission import baseline_burned_area_m2, mission_metrics, mission_world
from firefleet.world import BURNING, UNBURNT

ISSUE_YAML = """\
name: office-fire
title: three robots, one fire, one victim
duration_s: 600.0
poses: [[1.0, 1.0, 0.0], [1.0, 2.0, 0.0], [1.0, 3.0, 0.0]]
world:
  map: office
  fires: [{x_m: 15.0, y_m: 8.0, start_s: 0.0}]
  victims: [{x_m: 12.0, y_m: 3.0}]
  fuel: {default: 1.0}              # relative fuel load; optional per-region overrides
sensors: {thermal: {}, ultrasonic: {count: 8}}
command:
  kind: mission
  robots: true                      # false runs the same world without the team: the baseline
"""


def _write(tmp_path: Path, text: str, name: str = "mission.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_the_issue_yaml_validates_as_printed(tmp_path: Path) -> None:
    scenario = firefleet.load_scenario(_write(tmp_path, ISSUE_YAML))
    assert scenario.command.kind == "mission"
    assert scenario.world is not None
    assert scenario.world.fires[0].x_m == 15.0
    assert scenario.world.victims[0].y_m == 3.0


@pytest.mark.parametrize(
    ("old", "new", "says"),
    [
        (
            "fires: [{x_m: 15.0, y_m: 8.0",
            "fires: [{x_m: 4.0, y_m: 2.0",
            "world.fires[0]: (4, 2) is inside a wall",
        ),
        (
            "victims: [{x_m: 12.0, y_m: 3.0}]",
            "victims: [{x_m: 30.0, y_m: 3.0}]",
            "world.victims[0]: (30, 3) is off the map",
        ),
        (
            "victims: [{x_m: 12.0, y_m: 3.0}]",
            "victims: [{x_m: 4.0, y_m: 2.0}]",
            "world.victims[0]: (4, 2) is inside a wall",
        ),
        (
            "fuel: {default: 1.0}",
            "fuel: {default: 1.0, regions: [{x_m: [30, 40], y_m: [0, 1], load: 2}]}",
            "world.fuel.regions[0]",
        ),
        (
            "sensors: {thermal: {}, ultrasonic: {count: 8}}",
            "sensors: {ultrasonic: {count: 8}}",
            "sensors.thermal",
        ),
        (
            "robots: true",
            "robots: true\n  refill_m: [4.0, 2.0]",
            "command.refill_m: (4, 2) is inside a wall of map 'office'",
        ),
        (
            "robots: true",
            "robots: true\n  refill_m: [[1.0, 1.0], [4.0, 2.0]]",
            "command.refill_m[1]: (4, 2) is inside a wall of map 'office'",
        ),
        (
            "robots: true",
            "robots: true\n  refill_m: []",
            "command.refill_m: give a point [x_m, y_m] or a list of them, got []",
        ),
        (
            "robots: true",
            "robots: true\n  refill_m: [[1.0, 1.0, 0.0]]",
            "command.refill_m[0]: Tuple should have at most 2 items",
        ),
        (
            "sensors: {thermal: {}, ultrasonic: {count: 8}}",
            "sensors: {thermal: {}, ultrasonic: {count: 8}, pt100: {time_constant_s: 0}}",
            "sensors.pt100.time_constant_s: expected > 0, got 0.0",
        ),
        (
            "poses: [[1.0, 1.0, 0.0], [1.0, 2.0, 0.0], [1.0, 3.0, 0.0]]",
            "poses: []",
            "poses must list at least one robot",
        ),
    ],
)
def test_bad_mission_input_is_one_line_exit_2(
    tmp_path: Path, old: str, new: str, says: str
) -> None:
    assert old in ISSUE_YAML
    path = _write(tmp_path, ISSUE_YAML.replace(old, new))
    done = subprocess.run(
        [sys.executable, "-m", "firefleet.cli", "validate", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 2
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert says in lines[0]
    assert lines[0].count(says.split(":")[0]) == 1, "the key is named once"


OFFICE = "mission-office"  # built in


def _short(name: str | Path, duration_s: float, **command: object) -> firefleet.Scenario:
    scenario = firefleet.load_scenario(name)
    replace: Any = dataclasses.replace
    cmd = replace(scenario.command, **command)
    return dataclasses.replace(scenario, duration_s=duration_s, command=cmd)


def test_a_run_without_the_team_burns_the_baseline() -> None:
    """``robots: false`` is the baseline world: the same seed burns the same cells."""
    scenario = _short(OFFICE, 40.0, robots=False)
    result = firefleet.simulate(scenario, record_every=100)
    metrics = mission_metrics(result)
    assert metrics["burned_area_m2"] == baseline_burned_area_m2(scenario) > 0.0
    assert metrics["burned_vs_baseline"] == 1.0
    assert metrics["fires_detected"] == 0.0
    assert not np.any(np.abs(result.pose - result.pose[0]) > 1e-9)  # nobody moved


def test_the_baseline_says_when_its_fire_went_out() -> None:
    """``baseline_all_out_s`` is the ``all_out_s`` of the world without the team: a fire
    on a 1 m x 1 m patch of fuel 0.05 (15 s a cell, ``burn_s_per_fuel`` 300 s) is out
    within the run; the office's fire at fuel 1 still burns at 40 s (None)."""
    from firefleet.scenarios._mission import FuelRegion, FuelSpec

    scenario = _short(OFFICE, 60.0, robots=False)
    x, y = scenario.world.fires[0].x_m, scenario.world.fires[0].y_m  # type: ignore[union-attr]
    fuel = FuelSpec(
        default=0.0, regions=(FuelRegion((x - 0.5, x + 0.5), (y - 0.5, y + 0.5), 0.05),)
    )
    world = dataclasses.replace(scenario.world, fuel=fuel)  # type: ignore[type-var]
    patch = dataclasses.replace(scenario, world=world)
    metrics = mission_metrics(firefleet.simulate(patch, record_every=100))
    out_s = metrics["all_out_s"]
    assert isinstance(out_s, float)
    assert 15.0 <= out_s < 60.0  # at least one cell's burning time
    assert metrics["baseline_all_out_s"] == pytest.approx(metrics["all_out_s"], abs=0.1)  # one step
    burning = mission_metrics(
        firefleet.simulate(_short(OFFICE, 40.0, robots=False), record_every=100)
    )
    assert np.isnan(burning["baseline_all_out_s"])
    assert np.isnan(burning["all_out_s"])


def test_air_near_the_floor_damages_a_robot_in_the_fire() -> None:
    scenario = _short(OFFICE, 10.0)
    world = mission_world(scenario)
    state = world.init(2)
    fire_cell = tuple(int(v) for v in world.fire_cells[0])
    xy = world.field.center_of(np.array(fire_cell))
    state = world.act(
        state,
        {"spray": np.zeros(2, bool), "refill": np.zeros(2, bool)},
        np.array([[xy[0], xy[1], 0.0], [1.0, 1.5, 0.0]]),
    )
    state = world.step(state, 0.0)  # the fire starts at 0 s: the cell burns at 800 C
    assert state.fire.state[fire_cell] == BURNING
    air = lower_layer(state.temperature_c[fire_cell], 20.0)
    assert air == pytest.approx(20.0 + LOWER_LAYER * 780.0)
    assert air > scenario.command.rating_c  # type: ignore[union-attr]
    state = world.step(state, world.world_step_s)
    assert state.damaged.tolist() == [True, False]
    assert state.voltage_scale is not None
    assert state.voltage_scale.tolist() == [0.0, 1.0]


def test_the_pt100_lags_the_air_by_its_time_constant() -> None:
    """A robot parked in hot air: its PT100 follows the lower layer's air at its cell
    through the sheath's first-order lag (the exact response to the air each world step
    holds) and reads it through the converter."""
    scenario = _short(OFFICE, 10.0)
    world = mission_world(scenario)
    tau, dt = world.pt100.time_constant_s, world.world_step_s
    state = world.init(1)
    state = world.act(
        state,
        {"spray": np.zeros(1, bool), "refill": np.zeros(1, bool)},
        np.array([[1.0, 1.5, 0.0]]),
    )
    cell = tuple(int(v) for v in world.field.cell_of(np.array([1.0, 1.5])))
    hot = np.full(world.field.shape, 220.0)
    probe, t_s = 20.0, 0.0
    for _ in range(100):  # 10 s, the air re-heated to 220 C before every world step
        state = world.step(dataclasses.replace(state, temperature_c=hot), t_s)
        air = float(lower_layer(state.temperature_c[cell], 20.0))
        probe = air + (probe - air) * math.exp(-dt / tau)
        t_s += dt
    assert 20.0 + LOWER_LAYER * 199.0 < air < 20.0 + LOWER_LAYER * 200.0
    assert state.probe_c[0] == pytest.approx(probe, rel=1e-12)
    assert probe == pytest.approx(air + (20.0 - air) * math.exp(-10.0 / tau), abs=0.2)
    # the reading: within one converter step (0.034 C) below the probe
    assert 0.0 <= probe - state.pt100_c[0] < 0.04


def test_detections_are_the_detectors_and_lie_where_the_heat_is() -> None:
    """60 s of mission-office: each fire detection, placed on the map by the robot's
    odometry, lies within 3 m of a cell hotter than 100 C at that time (the detector
    reads rendered frames: hot gas at a door is a fire to it, as to a person reading
    the frame); no person is reported where there is none."""
    scenario = _short(OFFICE, 60.0)
    result = firefleet.simulate(scenario, record_every=100)
    world = mission_world(scenario)
    det: Any = result.extra["detections"]
    fires = det[det["kind"] == "fire"]
    assert len(fires) > 0
    times = result.extra["field_t_s"]
    temps = result.extra["temperature_c"]
    for row in fires:
        j = int(np.argmin(np.abs(times - row["t_s"])))
        hot = world.field.center_of(np.argwhere(temps[j] > 100.0))
        d = np.hypot(hot[:, 0] - row["x_m"], hot[:, 1] - row["y_m"])
        assert d.min() <= 3.0, row
    people = det[det["kind"] == "person"]
    for row in people:
        d = np.hypot(*(world.victim_xy_m - [row["x_m"], row["y_m"]]).T)
        assert d.min() <= 2.5, row
    assert (result.extra["fire_state"][-1] != UNBURNT).any()


def test_the_water_on_the_floor_is_the_water_sprayed() -> None:
    """``wet_l_m2`` in result.npz: a robot spraying 10 s at the office floor puts on the
    cells, summed over their area, the litres its tank lost (every litre lands in the
    cone), and the recorded water only grows."""
    scenario = _short(OFFICE, 10.0)
    world = mission_world(scenario)
    state = world.init(1)
    on = {"spray": np.ones(1, bool), "refill": np.zeros(1, bool)}
    t_s = 0.0
    while t_s < 10.0:
        state = world.act(state, on, np.array([[1.0, 1.5, 0.0]]))
        state = world.step(state, t_s)
        t_s += world.world_step_s
    log = world.final(state)
    wet = np.asarray(log["wet_l_m2"], dtype=float)
    assert wet.shape == (len(log["field_t_s"]), *world.field.shape)
    area = world.field.resolution_m**2
    used = float(log["water_used_l"].sum())
    assert used > 5.0
    assert 20.0 - float(state.tank_l[0]) == pytest.approx(used)
    # recorded to 0.01 L/m^2 per cell, in float16 (11 significant bits)
    cells = int(np.count_nonzero(wet[-1]))
    tol = cells * (0.005 + float(wet[-1].max()) * 2.0**-11) * area
    assert float(wet[-1].sum()) * area == pytest.approx(used, abs=tol)
    assert np.all(np.diff(wet.sum(axis=(1, 2))) >= 0.0)  # it only accumulates
    assert float(wet[0].sum()) < float(wet[-1].sum())


def test_a_tank_fills_only_at_a_refill_point() -> None:
    """The team says two robots are refilling; the world fills the one whose true
    position lies within ``refill_reach_m`` of the refill point (the start poses'
    centroid) at ``refill_l_s`` and leaves the one 3 m off empty: the team's word is
    checked against the truth."""
    scenario = _short(OFFICE, 10.0)
    world = mission_world(scenario)
    c = np.asarray(scenario.poses, dtype=float)[:, :2].mean(axis=0)
    assert world.refill_xy_m is not None
    np.testing.assert_allclose(world.refill_xy_m, [c])
    state = dataclasses.replace(world.init(2), tank_l=np.zeros(2))
    order = {"spray": np.zeros(2, bool), "refill": np.ones(2, bool)}
    # 1.2 m off the point (inside the reach), and 3 m off it
    pose = np.array([[c[0] + 1.2, c[1], 0.0], [c[0], c[1] + 3.0, 0.0]])
    t_s = 0.0
    for _ in range(10):  # 1 s
        state = world.step(world.act(state, order, pose), t_s)
        t_s += world.world_step_s
    assert state.tank_l[0] == pytest.approx(world.refill_l_s * 1.0)
    assert state.tank_l[1] == 0.0
    reach = world.refill_reach_m
    edge = np.array([[c[0] + reach, c[1], 0.0], [c[0] + reach + 1e-6, c[1], 0.0]])
    assert world.at_refill(edge).tolist() == [True, False]
    assert world.at_refill(np.full((1, 3), np.nan)).tolist() == [False]


def test_the_world_fills_at_every_refill_point_given() -> None:
    """``command.refill_m`` with two points: the world fills at either, not between."""
    world = mission_world(_short(OFFICE, 10.0, refill_m=((1.0, 1.0), (10.0, 5.0))))
    pose = np.array([[1.0, 1.5, 0.0], [10.5, 5.0, 0.0], [5.5, 3.0, 0.0]])
    assert world.at_refill(pose).tolist() == [True, True, False]


@pytest.mark.parametrize(
    "name", ["examples/missions/mission-maze.yaml", "mission-office"], ids=["maze", "office"]
)
def test_the_worlds_cells_are_the_teams_cells(name: str) -> None:
    """The world's field and the team's coarse plan (both 0.25 m) are the same cells on
    the maze, whose 168 rows are not a whole number of 5-row blocks (the field was
    blocked from the bottom row and the plan from the top, 0.15 m apart), as on the
    office (200 rows): each field cell's centre falls in the plan cell of the same
    index, and both grids' cell centres coincide."""
    from firefleet.control.mission import TacticsParams, tactics_init

    root = Path(__file__).resolve().parents[2]
    scenario = firefleet.load_scenario(root / name if name.endswith(".yaml") else name)
    world = mission_world(scenario)
    assert scenario.world is not None
    state = tactics_init(scenario.world.grid(), scenario.poses, TacticsParams())
    cm = state.coarse
    assert cm.cell_m == world.field.resolution_m == 0.25
    rc = np.argwhere(np.ones(world.field.shape, dtype=bool))
    centres = world.field.center_of(rc)
    np.testing.assert_array_equal(cm.cell_of(centres), rc)
    # the plan's cell centres (its map cells' block centres) are the field's
    h, _w = scenario.world.grid().shape
    f = cm.factor
    top = scenario.world.grid().center_of(np.array([0, 0]))  # map cell (0, 0)
    res = scenario.world.grid().resolution_m
    plan_centre = top + np.array([(f - 1) / 2 * res, -(f - 1) / 2 * res])
    np.testing.assert_allclose(world.field.center_of(np.array([0, 0])), plan_centre, atol=1e-12)
    assert h % f == (3 if "maze" in name else 0)

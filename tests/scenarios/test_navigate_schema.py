"""The world, sensors and navigate keys of a scenario: accepted shapes and every error."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from firefleet.errors import InputError
from firefleet.scenarios import parse_scenario, read_scenario_file

BASE: dict[str, Any] = {
    "name": "cross-the-office",
    "title": "two robots cross the office",
    "duration_s": 120.0,
    "poses": [[1.0, 1.0, 0.0], [1.0, 3.0, 0.0]],
    "world": {"map": "office"},
    "sensors": {
        "ultrasonic": {"count": 8, "fov_deg": 15.0, "max_range_m": 4.0, "noise_m": 0.01},
        "lidar": {"beams": 90, "fov_deg": 360.0, "max_range_m": 10.0, "noise_m": 0.01},
    },
    "command": {
        "kind": "navigate",
        "goals_m": [[18.0, 7.0], [18.0, 2.0]],
        "goal_tolerance_m": 0.2,
        "localisation": "odometry",
    },
    "claims": [
        {"metric": "goal_reached", "op": ">=", "value": 1},
        {"metric": "collisions", "op": "<=", "value": 0},
    ],
}


def test_the_issues_example_parses() -> None:
    s = parse_scenario(copy.deepcopy(BASE))
    assert s.world is not None
    assert s.world.map == "office"
    assert s.sensors is not None
    assert s.sensors.lidar is not None
    assert s.sensors.lidar.beams == 90
    assert s.sensors.ultrasonic is not None
    assert s.command.kind == "navigate"
    assert s.command.goals_m == ((18.0, 7.0), (18.0, 2.0))


def _error(change: Any) -> str:
    data = copy.deepcopy(BASE)
    change(data)
    with pytest.raises(InputError) as info:
        parse_scenario(data, origin="s.yaml")
    return str(info.value)


@pytest.mark.parametrize(
    ("change", "expected"),
    [
        (
            lambda d: d["world"].update(map="ofice"),
            "world.map: unknown map 'ofice'; did you mean 'office'",
        ),
        (
            lambda d: d.update(poses=[[4.0, 2.0, 0.0], [1.0, 3.0, 0.0]]),
            "poses[0]: (4, 2) is inside a wall",
        ),
        (
            lambda d: d.update(poses=[[1.0, 1.0, 0.0], [-3.0, 3.0, 0.0]]),
            "poses[1]: (-3, 3) is off the map",
        ),
        (
            lambda d: d["command"].update(goals_m=[[18.0, 7.0], [9.0, 2.0]]),
            "command.goals_m[1]: (9, 2) is inside a wall",
        ),
        (
            lambda d: d["command"].update(goals_m=[[18.0, 70.0], [18.0, 2.0]]),
            "command.goals_m[0]: (18, 70) is off the map",
        ),
        (
            lambda d: d["command"].update(goals_m=[[18.0, 7.0]]),
            "command.goals_m: one goal per robot, got 1 goals for 2 poses",
        ),
        (
            lambda d: (d.pop("sensors"), d["command"].update(localisation="mcl")),
            "localisation 'mcl' needs a range sensor",
        ),
        (
            lambda d: (d.pop("sensors"), d["command"].update(localisation="slam")),
            "localisation 'slam' needs a range sensor",
        ),
        (lambda d: d["command"].update(localisation="gps"), "command.localisation"),
        (lambda d: d.pop("world"), "world.map: a navigate command needs a map"),
        (lambda d: d["sensors"]["lidar"].update(beams=0), "sensors.lidar.beams must be >= 1"),
        (lambda d: d["sensors"]["ultrasonic"].update(max_range_m=-1.0), "sensors.ultrasonic"),
        (lambda d: d["sensors"].update(lidr={}), "sensors.lidr: unknown key; did you mean 'lidar'"),
        (lambda d: d["world"].update(mapp="office"), "world.mapp: unknown key; did you mean 'map'"),
        (lambda d: d["command"].update(goal_tolerance_m=0.0), "goal_tolerance_m"),
        (lambda d: d["world"].update(map="no/such/map.yaml"), "no such map file"),
    ],
)
def test_errors_name_the_key(change: Any, expected: str) -> None:
    assert expected in _error(change)


def test_a_plane_scenario_is_unchanged_and_poses_off_a_map_only_matter_with_a_map() -> None:
    data = copy.deepcopy(BASE)
    data["command"] = {"kind": "voltage-step", "voltage_v": 1.0}
    data.pop("world")
    data["claims"] = []
    data["poses"] = [[-300.0, 5.0, 0.0]]
    assert parse_scenario(data).world is None
    data["world"] = {"map": "office"}
    with pytest.raises(InputError, match="off the map"):
        parse_scenario(data)


def test_a_map_path_relative_to_the_scenario_file(tmp_path: Path) -> None:
    maps = Path(__file__).parents[1] / "data" / "maps"
    (tmp_path / "m").mkdir()
    for name in ("tiny.yaml", "tiny.pgm"):
        (tmp_path / "m" / name).write_bytes((maps / name).read_bytes())
    text = (
        "name: tiny\ntitle: t\nduration_s: 1.0\nposes: [[-0.25, 2.25, 0.0]]\n"
        "world: {map: m/tiny.yaml}\n"
        "command: {kind: navigate, goals_m: [[0.75, 2.25]]}\n"
    )
    (tmp_path / "s.yaml").write_text(text, encoding="utf-8")
    scenario = read_scenario_file(tmp_path / "s.yaml")
    assert scenario.world is not None
    assert scenario.world.grid().shape == (3, 4)

"""The navigate kind: metrics against hand-computed runs, and maps it was not tuned for."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from firefleet import compute_metrics, simulate
from firefleet.cli import main
from firefleet.scenarios import parse_scenario, read_scenario_file
from firefleet.scenarios.schema import Scenario
from firefleet.sim.kinds._navigate_metrics import clearance_m, navigate_metrics
from firefleet.sim.result import SimResult
from firefleet.world import OccupancyGrid, load_map
from firefleet.world._plans import encode_pgm, map_yaml


def _write_map(folder: Path, occupied: np.ndarray, name: str = "m") -> Path:
    """A map_server map of ``occupied`` at 0.05 m (the built-ins' encoding)."""
    (folder / f"{name}.pgm").write_bytes(encode_pgm(occupied))
    (folder / f"{name}.yaml").write_text(map_yaml(f"{name}.pgm"), encoding="utf-8")
    return folder / f"{name}.yaml"


def test_clearance_equals_brute_force_over_every_cell() -> None:
    rng = np.random.default_rng(3)
    occ = rng.random((30, 40)) < 0.05
    grid = OccupancyGrid(occ, ~occ, resolution_m=0.1, origin_m=(-1.0, 0.5))
    pts = rng.uniform([-1.0, 0.5], [3.0, 3.5], size=(200, 2))
    # brute force: every occupied square and every square of the ring just off the map
    h, w = occ.shape
    pad = np.ones((h + 2, w + 2), dtype=bool)
    pad[1:-1, 1:-1] = occ
    rows, cols = np.nonzero(pad)
    centres = grid.center_of(np.stack([rows - 1, cols - 1], axis=-1))
    dx = np.maximum(np.abs(pts[:, None, 0] - centres[None, :, 0]) - 0.05, 0.0)
    dy = np.maximum(np.abs(pts[:, None, 1] - centres[None, :, 1]) - 0.05, 0.0)
    np.testing.assert_allclose(clearance_m(grid, pts), np.hypot(dx, dy).min(axis=1), atol=1e-12)


def _hall(tmp_path: Path) -> Path:
    """10 m x 5 m at 0.05 m, walls 0.1 m thick all round and a pillar at x 5-6, y 2-3."""
    occ = np.zeros((100, 200), dtype=bool)
    occ[:2, :] = occ[-2:, :] = occ[:, :2] = occ[:, -2:] = True
    occ[40:60, 100:120] = True
    return _write_map(tmp_path, occ, "hall")


def _scenario(
    map_path: Path, poses: list[list[float]], goals: list[list[float]], **kw: float
) -> Scenario:
    return parse_scenario(
        {
            "name": "t",
            "title": "t",
            "duration_s": kw.get("duration_s", 1.0),
            "poses": poses,
            "world": {"map": str(map_path)},
            "command": {"kind": "navigate", "goals_m": goals, "goal_tolerance_m": 0.2},
        }
    )


def _result(scenario: Scenario, t: np.ndarray, pose: np.ndarray) -> SimResult:
    z = np.zeros((*pose.shape[:2], 2))
    return SimResult(scenario, t, pose, z, z, z, z, z, z, extra={"estimated_pose": pose + 0.1})


def test_metrics_of_a_crafted_run(tmp_path: Path) -> None:
    """Robot 1 drives along y = 2.5 m (the pillar's centre line) to x = 4.95 m: its disc
    (0.15 m) overlaps the pillar's face at x = 5 m from x > 4.85 m; robot 2 stands still
    at (4.5, 2.75), and robot 1's disc overlaps it when it passes x = 4.5 m."""
    scenario = _scenario(
        _hall(tmp_path), [[1.0, 1.0, 0.0], [4.5, 4.0, 0.0]], [[4.0, 2.5], [4.5, 2.75]]
    )
    x = np.array([1.0, 2.0, 3.0, 3.9, 4.5, 4.7, 4.9, 4.95])  # 8 samples, 1 s apart
    t = np.arange(x.size, dtype=float)
    pose = np.zeros((x.size, 2, 3))
    pose[:, 0, 0], pose[:, 0, 1] = x, 2.5  # along the pillar's centre line y = 2.5
    pose[:, 1, :2] = (4.5, 2.5 + 0.25)  # robot 2 just above the line, still
    m: dict[str, Any] = navigate_metrics(_result(scenario, t, pose))
    # robot 1 to robot 2: |dx|, dy = 0.25; discs overlap when the distance < 0.3
    d12 = np.hypot(x - 4.5, 0.25)
    wall1 = 5.0 - x - 0.15  # pillar face at x = 5 m (the cells 100-119 start at 5.0)
    clear1 = np.minimum(wall1, d12 - 0.3)
    wall2 = 5.0 - 4.5 - 0.15  # robot 2: 0.35 m from the pillar's face
    assert m["collisions"] == [float(np.sum(clear1 < 0)), float(np.sum(d12 - 0.3 < 0))]
    assert m["collisions"] == [3.0, 1.0]  # x = 4.5 (robot), 4.9 and 4.95 (wall)
    np.testing.assert_allclose(m["min_clearance_m"][0], clear1.min(), atol=1e-12)
    assert m["min_clearance_m"][1] == pytest.approx(min(wall2, 0.25 - 0.3), abs=1e-12)
    assert m["goal_reached"] == [1.0, 1.0]
    assert m["time_to_goal_s"] == [3.0, 0.0]  # x = 3.9 is within 0.2 m of x = 4
    assert m["path_length_m"] == pytest.approx([3.95, 0.0])
    assert m["position_rms_m"] == pytest.approx([0.1 * math.sqrt(2)] * 2)
    assert math.isnan(m["map_agreement_pct"])


def test_goal_never_reached_is_zero_and_null(tmp_path: Path) -> None:
    scenario = _scenario(_hall(tmp_path), [[1.0, 1.0, 0.0]], [[9.0, 4.0]])
    pose = np.zeros((3, 1, 3))
    pose[:, 0, :2] = [[1.0, 1.0], [2.0, 1.0], [3.0, 1.0]]
    m: dict[str, Any] = navigate_metrics(_result(scenario, np.arange(3.0), pose))
    assert m["goal_reached"] == [0.0]
    assert math.isnan(m["time_to_goal_s"][0])
    assert m["collisions"] == [0.0]


def _random_rooms(seed: int) -> np.ndarray:
    """A floor of 3 x 2 rooms, 4 m x 3.5 m, with 0.15 m walls; each wall between two rooms
    has one 1 m door at a random place, except that room (2, 1) (top right) has none."""
    rng = np.random.default_rng(seed)
    res = 0.05
    w_cells, h_cells = round(12.0 / res), round(7.0 / res)
    occ = np.zeros((h_cells, w_cells), dtype=bool)
    t = 3
    occ[:t], occ[-t:], occ[:, :t], occ[:, -t:] = True, True, True, True
    for i in (1, 2):  # vertical walls at x = 4, 8 m
        c = round(4.0 * i / res)
        occ[:, c - 1 : c + 2] = True
        for j in (0, 1):  # a door in each room's stretch, random height
            if i == 2 and j == 1:
                continue  # top-right room: closed on its west side
            y0 = rng.uniform(0.5, 2.0) + 3.5 * j
            r0, r1 = h_cells - round((y0 + 1.0) / res), h_cells - round(y0 / res)
            occ[r0:r1, c - 1 : c + 2] = False
    r = h_cells - round(3.5 / res)  # horizontal wall at y = 3.5 m
    occ[r - 1 : r + 2, :] = True
    for i in (0, 1):  # doors north from rooms 0, 1 (room 2's north is closed)
        x0 = rng.uniform(0.8, 2.2) + 4.0 * i
        occ[r - 1 : r + 2, round(x0 / res) : round((x0 + 1.0) / res)] = False
    return occ


def test_a_map_not_tuned_for_reachable_and_unreachable_goals(tmp_path: Path) -> None:
    path = _write_map(tmp_path, _random_rooms(11), "rooms")
    grid = load_map(path)
    assert grid.shape == (140, 240)
    # reachable: bottom-left room to the top-middle room, through two doors
    ok = _scenario(path, [[1.5, 1.5, 0.0]], [[6.0, 5.5]], duration_s=90.0)
    result = simulate(ok)
    m: dict[str, Any] = dict(compute_metrics(result))
    assert m["goal_reached"] == [1.0]
    assert m["collisions"] == [0.0]
    assert result.t[-1] < 90.0  # ended when the robot arrived
    # unreachable: the closed top-right room; reported at once, not waited for
    shut = _scenario(path, [[1.5, 1.5, 0.0]], [[10.0, 5.5]], duration_s=90.0)
    result = simulate(shut)
    m = dict(compute_metrics(result))
    assert m["goal_reached"] == [0.0]
    assert math.isnan(m["time_to_goal_s"][0])
    assert result.t[-1] < 5.0


def test_the_command_line_exits_1_on_an_unreachable_goal(tmp_path: Path) -> None:
    _write_map(tmp_path, _random_rooms(11), "rooms")
    text = (
        "name: shut\ntitle: an unreachable room\nduration_s: 60.0\n"
        "poses: [[1.5, 1.5, 0.0]]\nworld: {map: rooms.yaml}\n"
        "command: {kind: navigate, goals_m: [[10.0, 5.5]]}\n"
        "claims:\n  - {metric: goal_reached, op: '>=', value: 1}\n"
    )
    (tmp_path / "shut.yaml").write_text(text, encoding="utf-8")
    assert read_scenario_file(tmp_path / "shut.yaml").world is not None
    out = tmp_path / "out"
    assert main(["run", str(tmp_path / "shut.yaml"), "--out", str(out), "--no-plots"]) == 1
    assert main(["validate", str(tmp_path / "shut.yaml")]) == 0
    bad = text.replace("[[10.0, 5.5]]", "[[8.0, 5.5]]")  # inside the wall at x = 8 m
    (tmp_path / "bad.yaml").write_text(bad, encoding="utf-8")
    assert main(["validate", str(tmp_path / "bad.yaml")]) == 2


def test_a_bad_map_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = _write_map(tmp_path, _random_rooms(11), "rooms")
    path.write_text(path.read_text().replace("resolution: 0.05\n", ""), encoding="utf-8")
    text = (
        "name: bad\ntitle: t\nduration_s: 1.0\nposes: [[1.5, 1.5, 0.0]]\n"
        "world: {map: rooms.yaml}\ncommand: {kind: navigate, goals_m: [[2.0, 2.0]]}\n"
    )
    (tmp_path / "bad.yaml").write_text(text, encoding="utf-8")
    capsys.readouterr()
    assert main(["run", str(tmp_path / "bad.yaml"), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "rooms.yaml: key 'resolution' missing" in err

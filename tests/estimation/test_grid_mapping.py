"""Occupancy mapping with known poses: exact cells, the compiled frame, the team merge,
and map agreement on a drive through a building."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.estimation.grid import (
    LogOddsParams,
    Scanner,
    map_agreement_pct,
    mapping_step,
    merge_log_odds,
    occupancy_probability,
)
from firefleet.estimation.grid._rays import cell_rc, grid_frame, scan_update
from firefleet.world import OccupancyGrid
from tests.estimation.grid_world import cast, drive, office


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(14)


def wall_grid() -> OccupancyGrid:
    occ = np.zeros((10, 10), bool)
    occ[:, 7] = True  # a wall whose west face is at x = 0.7 m
    return OccupancyGrid(occ, ~occ, 0.1)


def test_scan_of_a_known_wall_marks_exactly_the_expected_cells() -> None:
    grid = wall_grid()
    prm = LogOddsParams()
    scanner = Scanner(np.array([0.0, np.pi / 2]), max_range_m=0.6)
    pose = np.array([[0.15, 0.45, 0.0]])  # cell (5, 1), facing east
    ranges = cast(grid, pose, scanner.bearings_rad, 10.0)  # 0.55 m to the wall
    assert ranges[0, 0] == pytest.approx(0.55)
    ranges[0, 1] = 0.7  # north: no return within 0.6 m
    maps = mapping_step(np.zeros((1, 10, 10), np.float32), pose, ranges, grid, scanner, prm)[0]
    expected = np.zeros((10, 10))
    expected[5, 1:7] = prm.l_free  # crossed by the east beam (its own cell once, not twice)
    expected[5, 7] = prm.l_occ  # the hit; nothing beyond it (columns 8, 9)
    expected[0:5, 1] = prm.l_free  # the north beam without return: free to the map's edge
    np.testing.assert_allclose(maps, expected, rtol=1e-6)
    ignore = LogOddsParams(no_return="ignore")
    maps = mapping_step(np.zeros((1, 10, 10), np.float32), pose, ranges, grid, scanner, ignore)[0]
    expected[0:5, 1] = 0.0
    np.testing.assert_allclose(maps, expected, rtol=1e-6)


def test_log_odds_accumulate_and_clamp() -> None:
    grid = wall_grid()
    scanner = Scanner(np.zeros(1), max_range_m=5.0)
    pose = np.array([[0.15, 0.45, 0.0]])
    prm = LogOddsParams(clamp=2.0)
    maps = np.zeros((1, 10, 10), np.float32)
    for _ in range(5):
        maps = mapping_step(maps, pose, [[0.55]], grid, scanner, prm)
    assert maps[0, 5, 7] == pytest.approx(min(5 * prm.l_occ, 2.0))
    assert maps[0, 5, 3] == pytest.approx(max(5 * prm.l_free, -2.0))
    p = occupancy_probability(maps[0])
    assert p[5, 7] == pytest.approx(1 / (1 + np.exp(-2.0)))
    assert p[0, 0] == 0.5


def test_compiled_cell_of_matches_the_grid(rng: np.random.Generator) -> None:
    grid = OccupancyGrid(np.zeros((37, 23), bool), np.ones((37, 23), bool), 0.07, (-1.3, 2.1))
    ox, oy, res, h, _ = grid_frame(grid)
    pts = rng.uniform([-2.0, 1.0], [1.0, 5.0], (500, 2))
    ref = grid.cell_of(pts)
    got = np.array([cell_rc(x, y, ox, oy, res, h) for x, y in pts])
    np.testing.assert_array_equal(got, ref)


def test_bresenham_cells_hug_the_segment(rng: np.random.Generator) -> None:
    """Every ray visits max(|dr|, |dc|) + 1 cells, 8-connected, within sqrt(2)/2 of the
    segment between the cell centres (an independent property of Bresenham's line)."""
    for _ in range(200):
        r0, c0, r1, c1 = (int(v) for v in rng.integers(0, 40, 4))
        values = np.zeros((40, 40), np.float32)
        marks = np.zeros((40, 40), np.int8)
        scan_update(
            values,
            marks,
            r0,
            c0,
            np.array([r1]),
            np.array([c1]),
            np.array([False]),
            -1.0,
            1.0,
            -10.0,
            10.0,
        )
        cells = np.argwhere(values != 0)
        assert len(cells) == max(abs(r1 - r0), abs(c1 - c0)) + 1
        assert not marks.any()
        a, d = np.array([r0, c0], float), np.array([r1 - r0, c1 - c0], float)
        t = np.clip(((cells - a) @ d) / max(d @ d, 1e-12), 0, 1)
        dist = np.linalg.norm(cells - (a + t[:, None] * d), axis=1)
        assert dist.max() <= np.sqrt(2) / 2 + 1e-9


def test_team_merge_is_the_sum_of_log_odds() -> None:
    grid = wall_grid()
    scanner = Scanner(np.array([0.0]), max_range_m=5.0)
    poses = np.array([[0.15, 0.45, 0.0], [0.15, 0.25, 0.0]])
    maps = mapping_step(np.zeros((2, 10, 10), np.float32), poses, [[0.55], [0.55]], grid, scanner)
    merged = merge_log_odds(maps)
    np.testing.assert_allclose(merged, maps[0] + maps[1])
    assert merged[5, 7] > 0
    assert merged[7, 7] > 0
    assert merged[6, 7] == 0


def test_map_agreement_on_a_drive_through_the_office(rng: np.random.Generator) -> None:
    grid = office(0.05)
    poses = drive(40.0, rate_hz=5.0)
    scanner = Scanner.ring(90, 360.0, 8.0)
    ranges = cast(grid, poses, scanner.bearings_rad, 8.0, noise_m=0.01, rng=rng)
    maps = np.zeros((1, *grid.shape), np.float32)
    for k in range(len(poses)):
        maps = mapping_step(maps, poses[k : k + 1], ranges[k : k + 1], grid, scanner)
    p = occupancy_probability(maps[0])
    observed = np.count_nonzero(p != 0.5) / p.size
    agreement = map_agreement_pct(p, grid)
    occupied = p[(p != 0.5) & grid.occupied] > 0.5
    all_free = 100.0 * np.mean(~grid.occupied[p != 0.5])  # a map that knows no wall
    assert observed > 0.3  # the drive sees a good part of the floor
    # true poses, 1 cm noise on 5 cm cells: only the walls' faces disagree (97.9 % measured)
    assert agreement > 97.0
    assert agreement > all_free + 2.0
    assert occupied.mean() > 0.85  # the walls seen are in the map (89 % measured)


def test_errors_name_what_was_typed() -> None:
    grid = wall_grid()
    scanner = Scanner(np.zeros(1), 5.0)
    with pytest.raises(InputError, match="ranges_m"):
        mapping_step(np.zeros((1, 10, 10), np.float32), [[0, 0, 0]], [[1.0, 2.0]], grid, scanner)
    with pytest.raises(InputError, match="ranges_m"):
        mapping_step(np.zeros((1, 10, 10), np.float32), [[0, 0, 0]], [[-1.0]], grid, scanner)
    with pytest.raises(InputError, match="log_odds"):
        mapping_step(np.zeros((1, 9, 10), np.float32), [[0, 0, 0]], [[1.0]], grid, scanner)
    with pytest.raises(InputError, match="p_occupied"):
        LogOddsParams(p_occupied=0.4)
    with pytest.raises(InputError, match="no_return"):
        LogOddsParams(no_return="maybe")  # type: ignore[arg-type]
    with pytest.raises(InputError, match="max_range_m"):
        Scanner(np.zeros(2), 0.0)
    with pytest.raises(InputError, match="shape"):
        map_agreement_pct(np.zeros((3, 3)), grid)

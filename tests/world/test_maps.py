"""Maps: map_server YAML + PGM/PNG against cells known by hand, and every error path."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from firefleet.errors import InputError
from firefleet.world import BUILTIN_MAPS, load_map, parse_map
from firefleet.world._plans import PLANS, encode_pgm, map_yaml

DATA = Path(__file__).parents[1] / "data" / "maps"

TINY_YAML = (DATA / "tiny.yaml").read_text(encoding="utf-8")


def test_tiny_map_cells_as_written_by_hand() -> None:
    grid = load_map(DATA / "tiny.yaml")
    # grey 0 -> occupied; 254 -> free; 205 (p = 0.196, not < 0.196) and 100 (p = 0.608)
    # -> unknown
    assert grid.occupied.astype(int).tolist() == [[1, 0, 0, 1], [0, 0, 0, 0], [1, 0, 0, 0]]
    assert grid.free.astype(int).tolist() == [[0, 1, 1, 0], [1, 0, 0, 1], [0, 1, 1, 1]]
    assert grid.resolution_m == 0.5
    assert grid.origin_m == (-1.0, 2.0)
    assert grid.extent_m == (-1.0, 1.0, 2.0, 3.5)
    # the top-left cell (row 0) is the map's top edge: x in [-1, -0.5), y in [3, 3.5)
    assert grid.occupied_at([[-0.9, 3.4], [-0.9, 2.1], [-0.4, 3.4]]).tolist() == [
        True,
        True,
        False,
    ]


def test_thresholds_move_the_middle_grey() -> None:
    text = TINY_YAML.replace("occupied_thresh: 0.65", "occupied_thresh: 0.5")
    pgm = (DATA / "tiny.pgm").read_bytes()
    grid = parse_map(text, {"tiny.pgm": pgm})
    assert bool(grid.occupied[1, 2])  # p = 155/255 = 0.608 > 0.5
    text = TINY_YAML.replace("free_thresh: 0.196", "free_thresh: 0.2")
    grid = parse_map(text, {"tiny.pgm": pgm})
    assert bool(grid.free[1, 1])  # p = 50/255 = 0.196 < 0.2


def test_negate_swaps_black_and_white() -> None:
    pgm = (DATA / "tiny.pgm").read_bytes()
    grid = parse_map(TINY_YAML.replace("negate: 0", "negate: 1"), {"tiny.pgm": pgm})
    # p = v / 255: 254 -> occupied, 0 -> free, 205 (0.80) occupied, 100 (0.39) unknown
    assert grid.occupied.astype(int).tolist() == [[0, 1, 1, 0], [1, 1, 0, 1], [0, 1, 1, 1]]
    assert grid.free.astype(int).tolist() == [[1, 0, 0, 1], [0, 0, 0, 0], [1, 0, 0, 0]]


def test_png_floor_plan_with_alpha_and_colour(tmp_path: Path) -> None:
    """A HouseExpo-style PNG: black walls on white, RGB(A); transparent is unknown."""
    rgba = np.zeros((2, 3, 4), dtype=np.uint8)
    rgba[..., 3] = 255
    rgba[0, 1, :3] = 255  # white: free
    rgba[0, 2, :3] = (255, 255, 0)  # yellow: mean 170, p = 0.33 -> unknown
    rgba[1, :, :3] = 255
    rgba[1, 2, 3] = 0  # transparent: unknown
    Image.fromarray(rgba, "RGBA").save(tmp_path / "plan.png")
    (tmp_path / "plan.yaml").write_text(TINY_YAML.replace("tiny.pgm", "plan.png"), encoding="utf-8")
    grid = load_map(tmp_path / "plan.yaml")
    assert grid.occupied.astype(int).tolist() == [[1, 0, 0], [0, 0, 0]]
    assert grid.free.astype(int).tolist() == [[0, 1, 0], [1, 1, 0]]


def test_relative_image_resolves_against_the_yaml_folder(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    sub = tmp_path / "maps"
    sub.mkdir()
    (sub / "tiny.pgm").write_bytes((DATA / "tiny.pgm").read_bytes())
    (sub / "tiny.yaml").write_text(TINY_YAML, encoding="utf-8")
    monkeypatch.chdir(tmp_path)
    assert load_map("maps/tiny.yaml").shape == (3, 4)


@pytest.mark.parametrize(
    "key", ["image", "resolution", "origin", "negate", "occupied_thresh", "free_thresh"]
)
def test_a_missing_key_names_the_file_and_the_key(tmp_path: Path, key: str) -> None:
    text = "".join(line for line in TINY_YAML.splitlines(True) if not line.startswith(key))
    (tmp_path / "m.yaml").write_text(text, encoding="utf-8")
    (tmp_path / "tiny.pgm").write_bytes((DATA / "tiny.pgm").read_bytes())
    with pytest.raises(InputError, match=rf"m\.yaml: key '{key}' missing"):
        load_map(tmp_path / "m.yaml")


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("resolution: 0.5", "resolution: -1", "key 'resolution' must be > 0"),
        ("resolution: 0.5", "resolution: fine", "key 'resolution' must be a number"),
        ("negate: 0", "negate: 2", "key 'negate' must be 0 or 1"),
        ("origin: [-1.0, 2.0, 0.0]", "origin: [0, 0, 0.5]", "rotated map"),
        ("origin: [-1.0, 2.0, 0.0]", "origin: zero", "key 'origin' must be"),
        ("free_thresh: 0.196", "free_thresh: 0.9", "free_thresh < occupied_thresh"),
        ("negate: 0", "negate: 0\nmode: scale", "key 'mode' must be 'trinary'"),
    ],
)
def test_bad_values_name_the_key(old: str, new: str, message: str) -> None:
    pgm = (DATA / "tiny.pgm").read_bytes()
    with pytest.raises(InputError, match=message):
        parse_map(TINY_YAML.replace(old, new), {"tiny.pgm": pgm}, name="bad.yaml")


def test_not_an_image_and_no_free_cell() -> None:
    with pytest.raises(InputError, match=r"bad\.yaml: image 'tiny\.pgm' is not a valid PGM"):
        parse_map(TINY_YAML, {"tiny.pgm": b"not an image at all"}, name="bad.yaml")
    walls = b"P5\n2 2\n255\n" + bytes([0, 0, 205, 0])
    with pytest.raises(InputError, match="has no free cell"):
        parse_map(TINY_YAML, {"tiny.pgm": walls}, name="bad.yaml")


def test_missing_files_and_unknown_names(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such map file"):
        load_map(tmp_path / "none.yaml")
    (tmp_path / "m.yaml").write_text(TINY_YAML, encoding="utf-8")
    with pytest.raises(InputError, match=r"image: no such file .*tiny\.pgm"):
        load_map(tmp_path / "m.yaml")
    with pytest.raises(InputError, match="did you mean 'office'"):
        load_map("ofice")
    (tmp_path / "list.yaml").write_text("- 1\n- 2\n", encoding="utf-8")
    with pytest.raises(InputError, match="must be a mapping"):
        load_map(tmp_path / "list.yaml")


@pytest.mark.parametrize("name", BUILTIN_MAPS)
def test_shipped_maps_are_what_the_plans_draw(name: str) -> None:
    folder = resources.files("firefleet.world") / "maps"
    assert (folder / f"{name}.pgm").read_bytes() == encode_pgm(PLANS[name]())
    assert (folder / f"{name}.yaml").read_text(encoding="utf-8") == map_yaml(f"{name}.pgm")
    grid = load_map(name)
    assert np.array_equal(grid.occupied, PLANS[name]())
    assert np.array_equal(grid.free, ~PLANS[name]())


def test_office_doors_are_0_9_m_and_sizes_as_documented() -> None:
    office, warehouse, maze = load_map("office"), load_map("warehouse"), load_map("maze")
    assert (office.width_m, office.height_m) == (20.0, 10.0)
    assert (warehouse.width_m, warehouse.height_m) == (30.0, 20.0)
    assert maze.width_m == pytest.approx(12.0)
    assert maze.height_m == pytest.approx(8.4)
    # along the corridor's south wall (y = 4.1 m) the gaps are the four doors
    xs = np.arange(0.025, 20.0, 0.05)
    wall = office.occupied_at(np.stack([xs, np.full(xs.size, 4.125)], axis=-1))
    edges = np.flatnonzero(np.diff(wall.astype(int)))
    gaps = (edges[1::2] - edges[::2]) * 0.05
    assert gaps.tolist() == pytest.approx([0.9] * 4)

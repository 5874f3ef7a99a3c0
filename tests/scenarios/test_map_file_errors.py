"""A scenario whose ``world.map`` file is missing or broken: the one-line error names
``world.map`` (it named only ``world:`` before, for a file; an unknown built-in name
already named ``world.map``)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest

from firefleet.errors import InputError
from firefleet.scenarios import parse_scenario

BASE: dict[str, Any] = {
    "name": "one-fire",
    "title": "a mission on a user's map",
    "duration_s": 10.0,
    "poses": [[1.0, 1.0, 0.0]],
    "world": {"map": "office", "fires": [{"x_m": 16.5, "y_m": 8.0}]},
    "sensors": {"thermal": {}},
    "command": {"kind": "mission", "robots": True},
}

MAP_KEYS = "resolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\noccupied_thresh: 0.65\n"


def _error(map_path: str) -> str:
    data = copy.deepcopy(BASE)
    data["world"]["map"] = map_path
    with pytest.raises(InputError) as info:
        parse_scenario(data, origin="s.yaml")
    return str(info.value)


def test_a_missing_map_file_names_world_map(tmp_path: Path) -> None:
    where = tmp_path / "maps.yaml"
    assert _error(str(where)) == f"s.yaml: world.map: {where}: no such map file"


def test_a_broken_map_file_names_world_map_and_the_maps_key(tmp_path: Path) -> None:
    (tmp_path / "m.pgm").write_bytes(b"P5\n2 1\n255\n\x00\xfe")
    (tmp_path / "no_free.yaml").write_text(f"image: m.pgm\n{MAP_KEYS}", encoding="utf-8")
    msg = _error(str(tmp_path / "no_free.yaml"))
    assert msg.startswith("s.yaml: world.map: ")
    assert "key 'free_thresh' missing" in msg
    (tmp_path / "no_image.yaml").write_text(
        f"image: nothing.pgm\n{MAP_KEYS}free_thresh: 0.196\n", encoding="utf-8"
    )
    msg = _error(str(tmp_path / "no_image.yaml"))
    assert msg.startswith("s.yaml: world.map: ")
    assert "image: no such file" in msg


def test_an_unknown_map_name_names_world_map_once() -> None:
    msg = _error("ofice")
    assert msg.startswith("s.yaml: world.map: unknown map 'ofice'; did you mean 'office'")
    assert msg.count("world.map") == 1

"""The buildings nobody tuned for (``examples/missions/small-house``, ``apartment``,
``school``): the copied map is byte for byte the one its PROVENANCE names, the drawn ones
are what their scripts draw, and the missions load on them (``test_examples`` loads every
``mission-*.yaml`` too)."""

from __future__ import annotations

import hashlib
import re
import runpy
from pathlib import Path

import numpy as np

from firefleet import load_scenario
from firefleet.world import load_map

MISSIONS = Path(__file__).resolve().parents[1] / "examples" / "missions"


def _git_blob(data: bytes) -> str:
    """The git object id of a file's bytes (``git hash-object``)."""
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def test_the_small_house_map_is_the_file_its_provenance_names() -> None:
    here = MISSIONS / "small-house"
    readme = (here / "README.md").read_text(encoding="utf-8")
    assert "PROVENANCE: github.com/aws-robotics/aws-robomaker-small-house-world" in readme
    for name in ("map.pgm", "map.yaml"):
        blob = re.search(
            rf"turtlebot3_waffle_pi/{re.escape(name)}` \(git blob ([0-9a-f]+)\)", readme
        )
        assert blob is not None, name
        assert _git_blob((here / name).read_bytes()).startswith(blob.group(1))
    grid = load_map(here / "map.yaml")
    assert grid.shape == (500, 500)
    assert grid.origin_m == (-12.5, -12.5)
    # the map_saver's three values: 3,442 occupied, 63,021 free, the rest unknown
    assert int(grid.occupied.sum()) == 3442
    assert int(grid.free.sum()) == 63021


def test_the_apartment_map_is_what_its_script_draws() -> None:
    draw = runpy.run_path(str(MISSIONS / "apartment" / "draw_apartment.py"))
    shipped = load_map(MISSIONS / "apartment" / "apartment.yaml")
    assert shipped.occupied.shape == (280, 360)
    assert (shipped.occupied == draw["apartment"]()).all()


def test_the_school_map_is_what_its_script_draws() -> None:
    draw = runpy.run_path(str(MISSIONS / "school" / "draw_school.py"))
    shipped = load_map(MISSIONS / "school" / "school.yaml")
    assert shipped.occupied.shape == (280, 480)
    assert (shipped.occupied == draw["school"]()).all()
    # 39 classroom desks of 1.2 m x 0.6 m (288 cells each) stand free of every wall
    import scipy.ndimage as ndi

    label, _ = ndi.label(shipped.occupied)
    assert int((np.bincount(label.ravel())[1:] == 288).sum()) == 3 * 9 + 2 * 6


def test_the_untuned_missions_put_fire_people_and_robots_in_one_reachable_floor() -> None:
    """Every robot, fire and person of the missions on the free floor connected to the
    robots' start (4-connected free cells: no one placed in a sealed pocket)."""
    import scipy.ndimage as ndi

    for path in (
        MISSIONS / "small-house" / "mission-small-house.yaml",
        MISSIONS / "apartment" / "mission-apartment.yaml",
        MISSIONS / "school" / "mission-school.yaml",
    ):
        scn = load_scenario(path)
        assert scn.world is not None
        grid = load_map(scn.world.map)
        label, _ = ndi.label(grid.free)
        starts = grid.cell_of(np.array([p[:2] for p in scn.poses]))
        home = {int(label[r, c]) for r, c in starts}
        assert len(home) == 1
        assert 0 not in home
        points = [(f.x_m, f.y_m) for f in scn.world.fires] + [
            (v.x_m, v.y_m) for v in scn.world.victims
        ]
        for r, c in grid.cell_of(np.array(points)):
            assert int(label[r, c]) in home, (path.name, r, c)

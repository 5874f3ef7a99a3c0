"""Person detections checked against the floor plan (``_people``), against frames the
mission's renderer draws and the real detector reads."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.mission import CoarseMap, TacticsParams, tactics_init
from firefleet.control.mission._knowledge import empty_knowledge, update_knowledge
from firefleet.control.mission._people import behind_wall, person_plausible, wall_distance
from firefleet.errors import InputError

P = TacticsParams()


def _office_cm() -> CoarseMap:
    from firefleet.world import load_map

    return tactics_init(load_map("office"), [[1.0, 1.5, 0.0]], P).coarse


def _people_seen(
    pose: list[float], temp_c: np.ndarray, people: np.ndarray, seed: int
) -> list[tuple[float, float, float]]:
    """Person detections (x [m], y [m], peak [C]) of one frame rendered as the mission
    renders it (office field grid, the mission's scene, 3 % depth noise) and read by
    the real detector, placed on the map as the mission kind places them."""
    from firefleet.perception.thermal import detect
    from firefleet.sim.kinds._mission_world import SCENE
    from firefleet.sim.sensors import ThermalCameraParams, render_thermal_grid_depth
    from firefleet.world import coarsen, load_map

    field = coarsen(load_map("office"), 5)
    rng = np.random.default_rng(seed)
    frames, depth = render_thermal_grid_depth(
        np.array(pose)[None],
        field,
        temp_c,
        np.zeros(field.shape, bool),
        people.reshape(-1, 2),
        ThermalCameraParams(supersample=2, netd_k=0.05),
        rng=rng,
        scene=SCENE,
    )
    depth = depth * (1.0 + 0.03 * rng.standard_normal(depth.shape))
    out = []
    for d in detect(frames[0], depth_m=depth[0]).detections:
        if d.kind == "person" and d.range_m is not None:
            a = pose[2] + d.bearing_rad
            out.append(
                (pose[0] + d.range_m * math.cos(a), pose[1] + d.range_m * math.sin(a), d.peak_c)
            )
    return out


def _field_xy() -> tuple[np.ndarray, np.ndarray]:
    from firefleet.world import coarsen, load_map

    field = coarsen(load_map("office"), 5)
    h, w = field.shape
    ys = field.origin_m[1] + (h - 1 - np.arange(h) + 0.5) * field.resolution_m
    xs = field.origin_m[0] + (np.arange(w) + 0.5) * field.resolution_m
    return np.meshgrid(xs, ys)


POSES = [[17.9, 4.58, math.radians(-157)], [18.5, 4.9, math.radians(-160)], [14.5, 4.9, -0.35]]


def test_a_hot_wall_the_detector_names_a_person_is_dropped_and_a_person_by_it_kept() -> None:
    """The corridor's south wall heated to 50 C over 1.5 m (the hot gas from a fire
    room's door: mission-office seed 1 saw 33-63 C there) is named a person by the real
    detector from three poses; every such detection is dropped by the plan's test
    alone (no peak given), while people standing 0.35 m from the same wall (where
    mission-smoke puts one) and in the rooms are named and kept."""
    cm = _office_cm()
    x, y = _field_xy()
    hot = np.full(x.shape, 20.0)
    hot[(y > 4.25) & (y < 4.5) & (x > 15.5) & (x < 17.0)] = 50.0
    seen = [(pose, _people_seen(pose, hot, np.zeros(0), s)) for s, pose in enumerate(POSES)]
    wall = [d for _, ds in seen for d in ds]
    wall_robot = [pose for pose, ds in seen for _ in ds]
    assert len(wall) >= 3  # the detector is fooled from every pose
    wxy = np.array([d[:2] for d in wall])
    wpeak = np.array([d[2] for d in wall])
    assert not person_plausible(cm, np.array(wall_robot)[:, :2], wxy, None, 40.0, 0.1).any()
    assert (wpeak > 40.0).all()  # and too hot for skin besides
    cool = np.full(x.shape, 20.0)
    people = [
        ([15.3, 4.9, 0.1], [17.6, 4.6]),
        ([19.4, 4.9, math.pi], [17.6, 4.6]),
        ([13.5, 5.1, 0.0], [16.0, 5.4]),
        ([12.5, 4.7, math.atan2(-2.7, -0.5)], [12.0, 2.0]),  # through the room's door
    ]
    for s, (pose, xy) in enumerate(people):
        named = _people_seen(pose, cool, np.array(xy), 10 + s)
        assert len(named) == 1, (pose, xy)
        pxy = np.array([named[0][:2]])
        assert np.hypot(*(pxy[0] - xy)) < 0.2
        keep = person_plausible(cm, np.array([pose[:2]]), pxy, np.array([named[0][2]]), 40.0, 0.1)
        assert keep.tolist() == [True], (pose, xy, pxy)


def test_wall_distance_is_the_brute_force_distance_to_the_wall_squares() -> None:
    """Against every opaque cell's square, searched over the whole map."""
    cm = _office_cm()
    rng = np.random.default_rng(3)
    pts = np.c_[rng.uniform(0.0, 20.0, 300), rng.uniform(0.0, 10.0, 300)]  # the office
    got = wall_distance(cm, pts, 0.6)
    hc, wc = cm.shape
    r, c = np.mgrid[-1 : hc + 1, -1 : wc + 1]
    inside = (r >= 0) & (r < hc) & (c >= 0) & (c < wc)
    opaque = ~inside
    opaque[inside] = cm.opaque[r[inside], c[inside]]
    ctr = cm.centre_xy(np.stack([r[opaque], c[opaque]], axis=-1))
    gx = np.maximum(np.abs(pts[:, None, 0] - ctr[None, :, 0]) - cm.cell_m / 2, 0.0)
    gy = np.maximum(np.abs(pts[:, None, 1] - ctr[None, :, 1]) - cm.cell_m / 2, 0.0)
    ref = np.hypot(gx, gy).min(axis=1)
    ref = np.where(ref <= 0.6, ref, np.inf)
    assert np.array_equal(np.isinf(got), np.isinf(ref))
    fin = np.isfinite(ref)
    np.testing.assert_allclose(got[fin], ref[fin], atol=1e-12)
    assert (got[fin] == 0).sum() > 10
    assert (got[fin] > 0).sum() > 10
    assert wall_distance(cm, np.array([[-0.1, 5.0], [10.0, 10.2]]), 0.6).tolist() == [0.0, 0.0]


def test_behind_a_wall_and_the_peak() -> None:
    cm = _office_cm()
    # from the corridor: the south-middle room's person is behind the wall, not at the door
    a = np.array([[12.5, 4.9], [10.0, 4.9]])
    b = np.array([[12.0, 2.0], [12.0, 2.0]])
    assert behind_wall(cm, a, b).tolist() == [False, True]
    robot = np.array([[12.5, 4.9]] * 3)
    people = np.array([[12.0, 2.0]] * 3)
    peaks = np.array([37.0, 40.0, 40.5])
    assert person_plausible(cm, robot, people, peaks, 40.0, 0.1).tolist() == [True, True, False]
    assert person_plausible(cm, robot, people, np.full(3, np.nan), 40.0, 0.1).all()
    with pytest.raises(InputError, match="peak_c"):
        person_plausible(cm, robot, people, peaks[:2], 40.0, 0.1)
    with pytest.raises(InputError, match="person_peak_max_c"):
        TacticsParams(person_peak_max_c=float("nan"))
    with pytest.raises(InputError, match="person_wall_m"):
        TacticsParams(person_wall_m=-0.1)


def test_the_knowledge_takes_no_victim_from_a_wall() -> None:
    """A wall's "person" makes no victim; a person in the room does."""
    from firefleet.world import load_map

    state = tactics_init(load_map("office"), [[17.9, 4.58, -2.7]], P)
    pose = np.array([[17.9, 4.58, -2.7], [12.5, 4.7, -1.75]])
    k, changed = update_knowledge(
        empty_knowledge(),
        state.coarse,
        pose,
        np.zeros((0, 2)),
        np.zeros(0, dtype=np.int64),
        np.array([[16.4, 4.28], [12.0, 2.05]]),
        np.array([0, 1]),
        np.zeros(2, bool),
        5.0,
        P,
        None,
        np.array([36.0, 37.1]),
    )
    assert changed
    np.testing.assert_allclose(k.victim_xy_m, [[12.0, 2.05]])

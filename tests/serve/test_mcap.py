"""run.mcap: written by ``firefleet run --mcap``, read back with the ``mcap`` reader."""

from __future__ import annotations

import io
import json
import shutil
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from firefleet.cli._main import main
from firefleet.mcap_log import mcap_bytes, read_mcap
from firefleet.serve.app import run_document
from firefleet.serve.replay import layers
from firefleet.serve.runs import find_runs


@pytest.fixture(scope="module")
def coop(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("mcap") / "coop"
    argv = ["run", "coop-different-paths", "--mcap", "--no-plots", "--out", str(out)]
    assert main(argv) == 0
    return out


def wrap(angle: np.ndarray) -> np.ndarray:
    return np.angle(np.exp(1j * angle))


def test_coop_mcap_has_the_channels_schemas_counts_and_times(coop: Path) -> None:
    manifest = json.loads((coop / ".firefleet-run.json").read_text())
    assert manifest["files"] == ["metrics.json", "result.npz", "run.mcap"]
    with np.load(coop / "result.npz") as z:
        t, pose, odometry = z["t"], z["pose"], z["odometry_pose"]
    metrics = json.loads((coop / "metrics.json").read_text())
    reader = make_reader(io.BytesIO((coop / "run.mcap").read_bytes()))
    summary = reader.get_summary()
    assert summary is not None
    assert summary.statistics is not None
    schema_of = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    n_samples = t.size
    expected = {"/tf": ("foxglove.FrameTransforms", n_samples)}
    for i in (1, 2, 3):
        expected[f"/robot_{i}/pose"] = ("foxglove.PoseInFrame", n_samples)
        expected[f"/robot_{i}/odometry_pose"] = ("foxglove.PoseInFrame", n_samples)
    expected["/points/desired_xy_m"] = ("foxglove.PosesInFrame", n_samples)
    expected["/scene"] = ("foxglove.SceneUpdate", 1)
    expected["/events"] = ("foxglove.Log", 1 + len(metrics["claims"]))
    expected["/signals"] = ("firefleet.Signals", n_samples)  # JSON, for Foxglove's plots
    assert {topic: name for topic, (name, _) in expected.items()} == schema_of
    counts = {
        summary.channels[cid].topic: count
        for cid, count in summary.statistics.channel_message_counts.items()
    }
    assert counts == {topic: count for topic, (_, count) in expected.items()}
    assert summary.statistics.message_start_time == 0
    assert summary.statistics.message_end_time == round(t[-1] * 1e9) == 80 * 10**9
    times: dict[str, list[int]] = {}
    logs = []
    for _, channel, message in reader.iter_messages(topics=["/robot_2/pose", "/events"]):
        times.setdefault(channel.topic, []).append(message.log_time)
        if channel.topic == "/events":
            logs.append(message.data)
    assert times["/robot_2/pose"] == [round(s * 1e9) for s in t]
    assert sum(b"passed" in m for m in logs) == sum(c["passed"] for c in metrics["claims"])
    back = read_mcap((coop / "run.mcap").read_bytes())
    np.testing.assert_allclose(back["t"], t, atol=1e-9)
    np.testing.assert_allclose(back["pose"][..., :2], pose[..., :2], atol=1e-12)
    np.testing.assert_allclose(wrap(back["pose"][..., 2] - pose[..., 2]), 0.0, atol=1e-12)
    np.testing.assert_allclose(back["odometry_pose"][..., :2], odometry[..., :2], atol=1e-12)


def test_serve_replays_a_run_from_its_mcap_alone(coop: Path, tmp_path: Path) -> None:
    only = tmp_path / "coop-mcap-only"
    only.mkdir()
    for name in ("metrics.json", "run.mcap"):
        shutil.copy(coop / name, only / name)
    (run,) = find_runs([only])
    from_mcap = run_document(run)
    assert from_mcap["summary"]["replay"] == "run.mcap"
    (full,) = find_runs([coop])
    from_npz = run_document(full)["layers"]
    drawn = from_mcap["layers"]
    assert drawn["t"] == from_npz["t"]
    np.testing.assert_allclose(drawn["pose"][-1], from_npz["pose"][-1], atol=1e-4)
    np.testing.assert_allclose(drawn["series"]["y_err_m"], from_npz["series"]["y_err_m"], atol=1e-4)
    assert set(drawn["points"]) == set(from_npz["points"]) == {"desired_xy_m"}


def synthetic_run() -> dict[str, np.ndarray]:
    """Two robots for 5 samples with a map, a lidar, a sonar and thermal frames: the
    arrays a kind with sensors would record, in result.npz's names."""
    rng = np.random.default_rng(1)
    t = np.linspace(0.0, 2.0, 5)
    pose = np.zeros((5, 2, 3))
    pose[:, :, 0] = t[:, None] + np.array([0.0, 1.0])
    occupancy = np.zeros((40, 60))
    occupancy[0, :] = 1.0  # a wall along the map's top row
    return {
        "t": t,
        "pose": pose,
        "estimated_pose": pose + 0.01,
        "occupancy": occupancy,
        "map_resolution_m": np.array(0.1),
        "map_origin_m": np.array([-1.0, -2.0]),
        "lidar_range_m": rng.uniform(0.5, 3.0, (5, 2, 8)),
        "ultrasonic_range_m": rng.uniform(0.2, 2.0, (5, 2)),
        "thermal_c": rng.uniform(20.0, 300.0, (5, 2, 6, 8)),
        "landmarks_xy": np.array([[1.0, 1.0], [2.0, -1.0]]),
        "particles_xy": rng.normal(size=(5, 30, 2)),
    }


def test_sensor_arrays_become_grid_scans_images_and_layers() -> None:
    arrays = synthetic_run()
    summary = make_reader(io.BytesIO(mcap_bytes(arrays))).get_summary()
    assert summary is not None
    assert summary.statistics is not None
    schema_of = {c.topic: summary.schemas[c.schema_id].name for c in summary.channels.values()}
    counts = Counter(
        {summary.channels[c].topic: k for c, k in summary.statistics.channel_message_counts.items()}
    )
    assert schema_of["/map"] == "foxglove.Grid"
    assert counts["/map"] == 1
    for i in (1, 2):
        assert schema_of[f"/robot_{i}/lidar_range_m"] == "foxglove.LaserScan"
        assert schema_of[f"/robot_{i}/ultrasonic_range_m"] == "foxglove.LaserScan"
        assert schema_of[f"/robot_{i}/thermal"] == "foxglove.RawImage"
        assert schema_of[f"/robot_{i}/estimated_pose"] == "foxglove.PoseInFrame"
        assert counts[f"/robot_{i}/thermal"] == counts[f"/robot_{i}/lidar_range_m"] == 5
    doc = layers(arrays)
    assert doc["map"]["resolution_m"] == 0.1
    assert doc["map"]["origin_m"] == [-1.0, -2.0]
    assert doc["map"]["cells"][0][:3] == [1.0, 1.0, 1.0]
    assert [r["name"] for r in doc["ranges"]] == ["lidar_range_m", "ultrasonic_range_m"]
    assert len(doc["ranges"][0]["angle_rad"]) == 8
    assert doc["ranges"][1]["angle_rad"] == [0.0]
    np.testing.assert_allclose(doc["ranges"][0]["range_m"], arrays["lidar_range_m"], atol=1e-3)
    assert np.shape(doc["thermal"]["frames"]) == (5, 2, 6, 8)
    assert doc["landmarks"]["landmarks_xy"] == [[1.0, 1.0], [2.0, -1.0]]
    assert np.shape(doc["particles"]["particles_xy"]["xy"]) == (5, 30, 2)
    assert set(doc["estimates"]) == {"estimated_pose"}

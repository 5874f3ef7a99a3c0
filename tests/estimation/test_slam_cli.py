"""``firefleet slam``: outputs, exit statuses, line-numbered errors, nothing half-written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from firefleet.cli import main
from firefleet.estimation.alignment import absolute_trajectory_error
from firefleet.estimation.logs import read_log

VP = Path(__file__).resolve().parents[1] / "data" / "victoria_park_first1500.txt"


def test_slam_on_victoria_park_subset_with_default_options(tmp_path: Path) -> None:
    out = tmp_path / "o"
    assert main(["slam", str(VP), "--out", str(out)]) == 0
    lines = (out / "trajectory.csv").read_text().splitlines()
    assert lines[0] == "pose_id,x,y,theta"
    assert len(lines) == 1 + 929
    assert lines[1] == "0,0.000000,0.000000,0.000000"  # the first pose at the origin
    lm = (out / "landmarks.csv").read_text().splitlines()
    assert lm[0] == "id,x,y"
    assert len(lm) == 1 + 52
    doc = json.loads((out / "summary.json").read_text())
    assert doc["scenario"] == str(VP)
    assert doc["particles"] == 300  # the default with given association
    assert doc["poses"] == 929
    assert doc["claims"] == []  # no ground truth: GTSAM is the reference
    assert (out / "slam.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (out / "slam.gif").read_bytes()[:6] == b"GIF89a"
    gtsam = pytest.importorskip("gtsam")  # test extra; see pyproject
    graph, initial = gtsam.load2D(str(VP))
    graph.add(
        gtsam.PriorFactorPose2(
            0, gtsam.Pose2(), gtsam.noiseModel.Diagonal.Sigmas([1e-3, 1e-3, 1e-4])
        )
    )
    best = gtsam.LevenbergMarquardtOptimizer(
        graph, initial, gtsam.LevenbergMarquardtParams()
    ).optimize()
    ids = [int(line.split(",")[0]) for line in lines[1:]]
    ref = np.array([[best.atPose2(i).x(), best.atPose2(i).y()] for i in ids])
    path = np.array([[float(v) for v in line.split(",")[1:3]] for line in lines[1:]])
    ate = absolute_trajectory_error(path, ref)
    ate_odo = absolute_trajectory_error(read_log(VP).dead_reckoning()[:, :2], ref)
    assert ate_odo > 10.0
    # the defaults (calibration on, sigmas x 2, 300 particles), seeds 0-3: 0.60-0.86 m;
    # the defaults before (no calibration, sigmas x 1, 100 particles): 9.5-10.6 m
    assert ate <= 2.5


def test_sim_loop_claims_in_the_scenario_format(tmp_path: Path) -> None:
    out = tmp_path / "o"
    args = ["slam", "sim-loop", "--out", str(out), "--no-plots", "--fastslam", "1"]
    assert main([*args, "--particles", "60"]) == 0
    doc = json.loads((out / "summary.json").read_text())
    assert doc["version"] == 1
    assert [c["name"] for c in doc["claims"]] == ["position_rms_m", "landmark_rms_m"]
    for claim in doc["claims"]:  # the same keys as firefleet run's metrics.json
        assert set(claim) == {"name", "expected", "measured", "passed", "source"}
        assert claim["measured"] == doc[claim["name"]]
        assert claim["expected"].startswith("<= ")
        assert claim["passed"]


def test_malformed_log_exits_2_with_line_number(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    bad = tmp_path / "bad.txt"
    text = VP.read_text().splitlines()[:20]
    text[11] = "LANDMARK 11 5 10.7274"
    bad.write_text("\n".join(text) + "\n")
    out = tmp_path / "o"
    assert main(["slam", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:12: LANDMARK needs 7 fields, got 3" in err
    assert "Traceback" not in err
    assert not out.exists()


def test_missing_log_and_bad_seed(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["slam", str(tmp_path / "none.txt"), "--out", str(tmp_path / "o")]) == 2
    assert "no such file" in capsys.readouterr().err
    assert main(["slam", str(VP), "--seed", "-1", "--out", str(tmp_path / "o")]) == 2
    assert not (tmp_path / "o").exists()
    bad_sigma = ["slam", str(VP), "--turn-scale-sigma", "-0.1", "--out", str(tmp_path / "o")]
    assert main(bad_sigma) == 2
    assert "--turn-scale-sigma must be >= 0, got -0.1" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()
    # error messages name the flag a person typed, not the library's field
    assert main(["slam", str(VP), "--particles", "0", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--particles must be >= 1, got 0" in err
    assert "n_particles" not in err
    assert not (tmp_path / "o").exists()


def test_too_many_particles_refused_before_allocating(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: tried to allocate 22.5 GiB and died with a MemoryError traceback
    out = tmp_path / "o"
    assert main(["slam", str(VP), "--particles", "10000000", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--particles 10000000 needs about" in err
    assert "GiB" in err
    assert "Traceback" not in err
    assert not out.exists()


def test_log_without_landmark_lines_exits_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: IndexError in fastslam (exit 1, a traceback)
    odometry_only = tmp_path / "odo.txt"
    lines = [x for x in VP.read_text().splitlines() if x.startswith("ODOMETRY")][:50]
    odometry_only.write_text("\n".join(lines) + "\n")
    out = tmp_path / "o"
    assert main(["slam", str(odometry_only), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "no LANDMARK or BR lines" in err
    assert "Traceback" not in err
    assert not out.exists()


def test_negative_variance_exits_2_naming_line_and_field(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # before: accepted, and the filter ran with a negative variance
    text = VP.read_text().splitlines()[:40]
    n = next(i for i, x in enumerate(text) if x.startswith("LANDMARK"))
    words = text[n].split()
    words[5] = "-" + words[5]
    text[n] = " ".join(words)
    bad = tmp_path / "bad.txt"
    bad.write_text("\n".join(text) + "\n")
    assert main(["slam", str(bad), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert f"{bad}:{n + 1}: LANDMARK variance c11 (field 5) must be > 0" in err
    assert not (tmp_path / "o").exists()


def test_fastslam_flag_replaces_version(capsys: pytest.CaptureFixture[str]) -> None:
    # slam --version clashed with the program's --version
    with pytest.raises(SystemExit):
        main(["slam", "--help"])
    text = capsys.readouterr().out
    assert "--fastslam" in text
    assert "--version" not in text


def test_slam_estimates_the_odometry_calibration(tmp_path: Path) -> None:
    out = tmp_path / "o"
    args = ["slam", str(VP), "--out", str(out), "--particles", "50", "--no-plots"]
    assert main(args) == 0  # calibration on by default
    doc = json.loads((out / "summary.json").read_text())
    # Victoria Park's odometry under-reports its heading: GTSAM's optimum turns
    # 0.0026 rad/m more than the odometry over these 929 poses (522 m): a positive drift
    assert 0.0 < doc["heading_drift_rad_per_m"] < 0.006
    assert abs(doc["turn_scale_error"]) < 0.2

"""The report's section 2.7 runs: claims checked against known answers."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from firefleet.report.sensing import stereo_runs, thermal_run

DATA = Path(__file__).resolve().parents[1] / "data" / "thermal"


def _frames() -> dict[str, np.ndarray]:
    return {p.stem: np.load(p)["celsius"] for p in sorted(DATA.glob("*.npz"))}


def test_thermal_run_on_the_known_frames_and_the_simulated_lepton() -> None:
    run = thermal_run(_frames())
    doc = run.document
    # Known answers (tests/data/PROVENANCE.md): one warm object near (128, 172), no fire.
    assert doc["t420_warm_objects"] == 1.0
    assert doc["t420_warm_object_offset_px"] <= 10.0
    assert doc["fire_alarm_frames"] == 0.0
    # The simulated scene: a fire at atan2(1.2, 5) and a person at atan2(-1, 3.5).
    assert doc["simulated_fire_found"] == 1.0
    assert doc["simulated_person_found"] == 1.0
    pixel_deg = 51.0 / 80.0
    assert doc["simulated_fire_bearing_error_deg"] <= pixel_deg
    assert doc["simulated_person_bearing_error_deg"] <= pixel_deg
    assert all(c["passed"] for c in doc["claims"])
    assert set(run.figures) <= set(run.files)
    assert all(run.files[f].startswith(b"\x89PNG") for f in run.figures)


def test_thermal_run_without_real_frames_claims_only_the_simulation() -> None:
    doc = thermal_run({}).document
    names = {c["name"] for c in doc["claims"]}
    assert names == {
        "simulated_fire_found",
        "simulated_fire_bearing_error_deg",
        "simulated_person_found",
        "simulated_person_bearing_error_deg",
    }


def test_stereo_runs_against_the_motorcycle_ground_truth() -> None:
    pytest.importorskip("skimage")
    calibrated, uncalibrated = stereo_runs()
    doc = calibrated.document
    # Depth against the truth: well inside the 3 % bound (0.27 % measured).
    assert doc["depth_median_rel_error_pct"] <= 3.0
    assert doc["bad_2px_pct"] <= 15.0
    # The scene lies between 2.1 and 5.0 m (f b / (d + doffs) of the true disparities).
    assert 2.0 < doc["depth_min_m"] < doc["depth_max_m"] < 5.1
    un = uncalibrated.document
    # Known warps put corresponding points rows apart; rectification brings them back.
    assert un["row_offset_before_median_px"] > 2.0
    assert un["row_offset_after_median_px"] <= 0.5
    assert un["matches"] > 100
    assert all(c["passed"] for c in doc["claims"] + un["claims"])
    assert not math.isnan(un["scene_in_frame_pct"])


def test_slam_runs_on_the_loop_and_the_victoria_park_subset() -> None:
    pytest.importorskip("gtsam")
    from firefleet.report.slam import slam_report_runs

    log = Path(__file__).resolve().parents[1] / "data" / "victoria_park_first1500.txt"
    loop, park = slam_report_runs(log, seed=1)
    assert all(c["passed"] for c in loop.document["claims"])
    assert loop.document["duplicate_landmarks"] == 0
    # Victoria Park's first 929 poses: the default run is within 2.5 m of GTSAM's optimum
    # (as tests/estimation's default-options test measures: 0.6-0.9 m), and far better
    # than dead reckoning.
    doc = park.document
    assert doc["ate_vs_gtsam_m"] <= 2.5
    assert doc["ate_vs_gtsam_m"] < 0.5 * doc["odometry_ate_vs_gtsam_m"]
    assert park.files["slam.png"].startswith(b"\x89PNG")

"""SLAM log reading: Victoria Park's format, firefleet's own, malformed lines."""

from __future__ import annotations

import gzip
import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.errors import InputError
from firefleet.estimation.fastslam import FastSlamParams, run_fastslam
from firefleet.estimation.logs import format_log, parse_log, read_log
from firefleet.sim.world import DriveResult

VP = Path(__file__).resolve().parents[1] / "data" / "victoria_park_first1500.txt"


def test_victoria_park_subset() -> None:
    log = read_log(VP)
    assert log.n_poses == 929  # counted with grep: 928 ODOMETRY lines in the first 1500
    assert log.n_observations == 572  # 1500 - 928 LANDMARK lines
    assert log.pose_ids[:4].tolist() == [0, 1, 2, 3]
    # the data README's worked example: LANDMARK 4 5 11.5387 -3.2007 -> bearing -0.2706 rad,
    # range 11.974 m; GTSAM's noise reading: sigmas sqrt(0.4) m and sqrt(0.04) rad
    assert log.obs_landmark[0] == 5
    assert log.pose_ids[log.obs_step[0]] == 4
    np.testing.assert_allclose(log.obs_z[0], [11.974, -0.2706], atol=5e-4)
    np.testing.assert_allclose(np.diag(log.obs_cov[0]), [0.4, 0.04], rtol=1e-12)
    # ODOMETRY covariance upper triangle 0.0001 0 0 4e-06 0 4e-06
    np.testing.assert_allclose(log.odometry_cov[0], np.diag([1e-4, 4e-6, 4e-6]))
    assert log.truth_pose is None


def test_round_trip_of_a_simulated_log(tmp_path: Path, drive: DriveResult) -> None:
    path = tmp_path / "log.txt.gz"
    path.write_bytes(gzip.compress(format_log(drive.log).encode()))
    back = read_log(path)
    a, b = drive.log, back
    np.testing.assert_array_equal(a.pose_ids, b.pose_ids)
    np.testing.assert_array_equal(a.odometry, b.odometry)  # 17 digits: exact
    np.testing.assert_array_equal(a.odometry_cov, b.odometry_cov)
    np.testing.assert_array_equal(a.obs_step, b.obs_step)
    np.testing.assert_array_equal(a.obs_landmark, b.obs_landmark)
    np.testing.assert_allclose(a.obs_z, b.obs_z, rtol=1e-15)
    np.testing.assert_allclose(a.obs_cov, b.obs_cov, rtol=1e-14)
    assert b.truth_pose is not None
    assert a.truth_pose is not None
    np.testing.assert_array_equal(a.truth_pose, b.truth_pose)
    assert b.sensor_fov_rad == pytest.approx(math.radians(51.0))


GOOD = ["ODOMETRY 0 1 1 0 0 0.01 0 0 0.01 0 0.01", "BR 1 7 0.5 3.0 0.01 0.1"]


@pytest.mark.parametrize(
    ("bad", "message"),
    [
        ("ODOMETRY 1 2 1 0 0 0.01 0 0", "ODOMETRY needs 11 fields, got 8"),
        ("ODOMETRY 1 2 1 x 0 0.01 0 0 0.01 0 0.01", "not a number"),
        ("ODOMETRY 1 2 1 nan 0 0.01 0 0 0.01 0 0.01", "non-finite"),
        ("ODOMETRY 5 6 1 0 0 0.01 0 0 0.01 0 0.01", "chain is at pose 1"),
        ("LANDMARK 1.5 3 1 1 0.4 0 0.4", "ids must be integers"),
        ("BR 1 3 0.1 -2 0.01 0.1", "must be > 0"),
        ("VERTEX 1 0 0 0", "unknown record 'VERTEX'"),
        ("ODOMETRY 1 2 1 0 0 -1 0 0 0.01 0 0.01", "variance c11 (field 6) must be >= 0, got -1"),
        ("ODOMETRY 1 2 1 0 0 0.01 0 0 0.01 0 -1e-4", "variance c33 (field 11) must be >= 0"),
        ("ODOMETRY 1 2 1 0 0 0.01 0.5 0 0.01 0 0.01", "not positive semi-definite"),
        # a negative or zero variance of an observation was accepted before
        ("LANDMARK 1 3 1 1 -0.4 0 0.4", "LANDMARK variance c11 (field 5) must be > 0, got -0.4"),
        ("LANDMARK 1 3 1 1 0.4 0 0", "LANDMARK variance c22 (field 7) must be > 0, got 0"),
        ("LANDMARK 1 3 1 1 0.4 0.5 0.4", "not positive definite: c12 = 0.5"),
        # found by the mutation test below: the filter's path was NaN, exit 0
        ("ODOMETRY 1 2 1 0 0 1e308 0 0 0.01 0 0.01", "field 6 is 1e308: beyond 1e+12"),
    ],
)
def test_malformed_line_is_named_with_its_number(bad: str, message: str) -> None:
    with pytest.raises(InputError, match=r"^x\.log:3: ") as info:
        parse_log([*GOOD, bad], name="x.log")
    assert message in str(info.value)


def test_empty_missing_and_binary_files(tmp_path: Path) -> None:
    (tmp_path / "empty.txt").write_text("")
    with pytest.raises(InputError, match="no ODOMETRY lines"):
        read_log(tmp_path / "empty.txt")
    with pytest.raises(InputError, match="no such file"):
        read_log(tmp_path / "nope.txt")
    (tmp_path / "bin").write_bytes(b"\xff\xfe\x00garbage")
    with pytest.raises(InputError, match="not a text file"):
        read_log(tmp_path / "bin")
    with pytest.raises(InputError, match="observation from pose 9, not in the chain"):
        parse_log([GOOD[0], "BR 9 7 0.5 3.0 0.01 0.1"])


_SAMPLE = VP.read_text().splitlines()[:60]


@settings(max_examples=150, deadline=None)
@given(
    edits=st.lists(
        st.tuples(
            st.integers(0, len(_SAMPLE) - 1),
            st.integers(0, 11),
            st.sampled_from(["-1", "0", "nan", "1e308", "-0.5", "x", "", "3.5", "7", "-7"]),
        ),
        min_size=1,
        max_size=4,
    )
)
def test_mutated_logs_parse_or_raise_input_error(edits: list[tuple[int, int, str]]) -> None:
    # a valid log with fields replaced or dropped: read and filtered, or one InputError
    # naming the line (never another exception from the reader or the filter)
    lines = list(_SAMPLE)
    for row, col, value in edits:
        words = lines[row].split()
        if col < len(words):
            words[col] = value
        lines[row] = " ".join(w for w in words if w)
    message = ""
    try:
        log = parse_log(lines, name="m.log")
        res = run_fastslam(log, np.random.default_rng(0), params=FastSlamParams(n_particles=5))
    except InputError as exc:
        message = str(exc)
    if message:
        assert message.startswith("m.log")
    else:
        assert np.all(np.isfinite(res.trajectory))


@settings(max_examples=100, deadline=None)
@given(text=st.text(max_size=300))
def test_random_text_parses_or_raises_input_error(text: str) -> None:
    message = "r.log"
    try:
        parse_log(text.splitlines(), name="r.log")
    except InputError as exc:
        message = str(exc)
    assert message.startswith("r.log")

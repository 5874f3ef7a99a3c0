"""The command line: outputs, exit statuses, one-line errors, nothing half-written."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from firefleet.cli import main

GOOD = """\
name: mine
title: my test
duration_s: 1.0
command: {kind: wheel-speed-step, speed_rad_s: 2.0}
claims:
  - {metric: rise_time_s, op: "<", value: 0.2}
"""


def test_run_writes_metrics_arrays_and_plots(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "d"
    assert main(["run", "motor-pid", "--out", str(out)]) == 0
    doc = json.loads((out / "metrics.json").read_text())
    assert doc["scenario"] == "motor-pid"
    names = {c["name"] for c in doc["claims"]}
    assert {"rise_time_s", "settling_time_s", "overshoot_pct", "disturbance_recovery_s"} <= names
    assert all(c["passed"] for c in doc["claims"])
    for key in (
        "rise_time_s",
        "settling_time_s",
        "overshoot_pct",
        "steady_state_error_rad_s",
        "disturbance_recovery_s",
    ):
        assert isinstance(doc[key], float)
    with np.load(out / "result.npz") as npz:
        assert npz["t"].shape == (1001,)
        assert npz["pose"].shape == (1001, 1, 3)
        assert npz["current_a"].shape == (1001, 1, 2)
    assert (out / "response.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "rise_time_s" in capsys.readouterr().out
    assert not list(tmp_path.glob(".d.staging-*"))


def test_run_yaml_path_with_seed_and_no_plots(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD)
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out), "--seed", "3", "--no-plots"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["metrics.json", "result.npz"]


def test_failed_claim_exits_1(tmp_path: Path) -> None:
    path = tmp_path / "strict.yaml"
    path.write_text(GOOD.replace("value: 0.2", "value: 0.001"))
    assert main(["run", str(path), "--out", str(tmp_path / "o"), "--no-plots"]) == 1
    doc = json.loads((tmp_path / "o" / "metrics.json").read_text())
    assert doc["claims"][0]["passed"] is False


def test_validate_misspelt_key_exits_2_and_suggests(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "typo.yaml"
    path.write_text(GOOD.replace("duration_s", "duraton_s"))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert "duraton_s: unknown key; did you mean 'duration_s'?" in err
    assert "Traceback" not in err


def test_validate_ok(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "fine.yaml"
    path.write_text(GOOD)
    assert main(["validate", str(path)]) == 0
    assert "ok (mine, 1 robot(s), 100 steps)" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (None, "no such file"),
        (GOOD + "dt_s: -0.01\n", "dt_s must be > 0, got -0.01"),
        (GOOD + "poses: [[0.0, 0.0]]\n", "poses[0][2]: required, missing"),
        (
            GOOD.replace("speed_rad_s: 2.0", "speed_rad_s: fast"),
            "speed_rad_s: Input should be a valid number",
        ),
    ],
)
def test_bad_input_is_one_line_exit_2_and_writes_nothing(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], content: str | None, fragment: str
) -> None:
    path = tmp_path / "bad.yaml"
    if content is not None:
        path.write_text(content)
    out = tmp_path / "never"
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert fragment in err
    assert len(err.strip().splitlines()) == 1
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == (["bad.yaml"] if content else [])


def test_out_that_is_a_file_is_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    target = tmp_path / "file"
    target.write_text("keep me")
    assert main(["run", "motor-pid", "--out", str(target)]) == 2
    assert "exists and is not a folder" in capsys.readouterr().err
    assert target.read_text() == "keep me"


def test_unknown_scenario_name(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["run", "motor-pdi"]) == 2
    assert "did you mean motor-pid" in capsys.readouterr().err


def test_list_names_every_builtin(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["list"]) == 0
    out = capsys.readouterr().out
    assert "motor-open-loop" in out
    assert "motor-pid" in out
    assert "Figure 25" in out


def test_reproduce_writes_report(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "report"
    assert main(["reproduce", "--out", str(out)]) == 0
    index = (out / "index.html").read_text()
    for figure, name in (("Figure 24", "motor-open-loop"), ("Figure 25", "motor-pid")):
        assert figure in index
        assert f'src="{name}/response.png"' in index
        assert (out / name / "response.png").is_file()
        assert (out / name / "metrics.json").is_file()
    total = index.count("<td class=pass>") + index.count("<td class=fail>")
    assert total >= 6  # the motor scenarios' 6, and those of every other built-in
    assert f"{total} of {total} claims passed" in index
    assert "FAILED" not in index
    assert str((out / "index.html").resolve()) in capsys.readouterr().out

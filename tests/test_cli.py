"""The command line: outputs, exit statuses, one-line errors, nothing half-written."""

from __future__ import annotations

import argparse
import io
import json
import re
import shlex
import subprocess
import warnings
from pathlib import Path

import numpy as np
import pytest
from rich.console import Console

import firefleet
from firefleet import builtin_names, load_scenario
from firefleet.cli import main
from firefleet.cli._console import claims_table, progress_bar
from firefleet.cli._main import _parser
from firefleet.cli._run import _jobs, report_footer
from firefleet.errors import InputError
from firefleet.outputs import MANIFEST
from firefleet.report.html import render_index
from firefleet.sim.registry import task_kind
from tests._reproduce import Reproduced

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
    # a short run writes its MCAP log by default (under MCAP_AUTO_BYTES)
    assert sorted(p.name for p in out.iterdir()) == [
        MANIFEST, "metrics.json", "result.npz", "run.mcap"
    ]  # fmt: skip


def test_mcap_only_when_small_unless_asked(tmp_path: Path) -> None:
    # coop-different-paths: 3 robots x 8,001 samples, about 7 MB of MCAP: not by default
    out = tmp_path / "big"
    assert main(["run", "coop-different-paths", "--out", str(out), "--no-plots"]) == 0
    assert not (out / "run.mcap").exists()
    assert main(["run", "coop-different-paths", "--out", str(out), "--no-plots", "--mcap"]) == 0
    assert (out / "run.mcap").stat().st_size > 1_000_000
    small = tmp_path / "small"
    assert main(["run", "motor-pid", "--out", str(small), "--no-plots", "--no-mcap"]) == 0
    assert not (small / "run.mcap").exists()


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


def test_reproduce_writes_report(reproduced: Reproduced) -> None:
    # one run a session (tests/conftest.py), section 2.7 without Victoria Park: said, not
    # failed; tests/sim/test_engine.py reads the built-ins' claims from the same run
    out, no_data = reproduced.out, reproduced.no_data
    assert reproduced.status == 0
    index = (out / "index.html").read_text()
    for figure, name in (("Figure 24", "motor-open-loop"), ("Figure 25", "motor-pid")):
        assert figure in index
        assert f'src="{name}/response.png"' in index
        assert (out / name / "response.png").is_file()
        assert (out / name / "metrics.json").is_file()
    # the deliverable's sections in its order, then what goes beyond it
    heads = [index.index(f"<h2 class=part>{h}") for h in ("2.3 ", "2.6.4.1 ", "2.6.5 ", "2.7 ")]
    assert heads == sorted(heads) < [index.index("<h2 class=part>Beyond the deliverable")]
    for run in ("thermal", "stereo-motorcycle", "stereo-uncalibrated", "slam-sim-loop"):
        assert f'id="{run}"' in index
        assert (out / run / "metrics.json").is_file()
    assert 'id="slam-victoria-park"' not in index
    assert "Victoria Park (slam/victoria_park.txt)" in index  # what was left out, said
    scenario_claims = sum(
        len(load_scenario(n).claims) for n in builtin_names() if load_scenario(n).reproduces
    )
    documents = [json.loads(p.read_text()) for p in out.glob("*/metrics.json")]
    missions = [n for n in builtin_names() if load_scenario(n).command.kind == "mission"]
    assert {"mission-smoke", "mission-warehouse"} <= set(missions)
    for name in missions:  # their claims are checked here only (tests/sim/test_engine.py)
        doc = json.loads((out / name / "metrics.json").read_text())
        assert set(load_scenario(name).metric_names) <= set(doc)
        assert doc["claims"]
        assert all(c["passed"] for c in doc["claims"]), doc["claims"]
    # the missions side by side beyond the deliverable, each with its animation
    beyond = index.split("<h2 class=part>Beyond the deliverable")[1]
    shown = re.findall(r'<section id="([^"]+)">', beyond)
    first = shown.index(missions[0])
    assert shown[first : first + len(missions)] == missions  # next to each other
    for name in missions:
        section = beyond[beyond.index(f'<section id="{name}">') :].split("</section>")[0]
        assert "beyond the deliverable: the mission" in section
        assert f'src="{name}/mission.gif"' in section
        assert (out / name / "mission.gif").read_bytes()[:6] == b"GIF89a"
        assert (out / name / "mission.png").is_file()
    total = sum(len(d["claims"]) for d in documents)
    assert total > scenario_claims >= 25
    assert f"{total} of {total} claims passed" in index
    assert index.count('src="path-straight/controller.png"') == 1  # shown once
    assert "controller.png" not in index.split('id="path-curved-on"')[1].split("<img")[0]
    assert "issue" not in index.lower()
    made_by = f"firefleet reproduce --out {out} --data {no_data} --workers {reproduced.workers}"
    assert f"Made by: {made_by}." in index
    assert "Seeds: " in index
    assert "FAILED" not in index
    assert str((out / "index.html").resolve()) in reproduced.stdout


def _job(err: Console, k: int) -> int:
    """A report job for ``_jobs``: k squared; job 2 warns, job 3 fails."""
    if k == 2:
        warnings.warn("job 2 warns", UserWarning, stacklevel=1)
    if k == 3:
        raise InputError("job 3 fails")
    return k * k


@pytest.mark.parametrize("workers", [1, 2])
def test_report_jobs_give_their_values_warnings_and_errors_here(workers: int) -> None:
    # the session's report runs in worker processes (tests/conftest.py): a warning there
    # is warned here, under pytest's filters (an error), as in one process
    with _jobs(workers, Console(stderr=True)) as jobs:
        values = [jobs(_job, k) for k in range(4)]
        assert values[1]() == 1
        assert values[0]() == 0
        with pytest.warns(UserWarning, match="job 2 warns"):
            assert values[2]() == 4
        with pytest.raises(InputError, match="job 3 fails"):
            values[3]()


def test_reproduce_with_no_workers_is_bad_input(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "r"
    assert main(["reproduce", "--workers", "0", "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.strip().splitlines() == ["firefleet: error: --workers must be at least 1, got 0"]
    assert not out.exists()


def test_run_path_following_writes_per_robot_metrics(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "coop"
    assert main(["run", "coop-same-path", "--out", str(out)]) == 0
    doc = json.loads((out / "metrics.json").read_text())
    assert len(doc["wait_time_s"]) == 3
    names = [c["name"] for c in doc["claims"]]
    assert "wait_time_s[robot 2]" in names
    robot2 = next(c for c in doc["claims"] if c["name"] == "wait_time_s[robot 2]")
    assert robot2["measured"] == doc["wait_time_s"][1]
    with np.load(out / "result.npz") as npz:
        assert npz["pose"].shape[1:] == (3, 3)
        assert npz["y_err_m"].shape == (*npz["t"].shape, 3)
        assert npz["odometry_pose"].shape == npz["pose"].shape
    for png in ("trajectory.png", "velocities.png", "controller.png"):
        assert (out / png).stat().st_size > 10_000
    assert "[robot 1]" in capsys.readouterr().out


def test_run_into_a_previous_run_leaves_only_the_new_run(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD)
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out)]) == 0
    assert (out / "response.png").is_file()
    assert main(["run", str(path), "--out", str(out), "--no-plots", "--no-mcap"]) == 0
    assert sorted(p.name for p in out.iterdir()) == [MANIFEST, "metrics.json", "result.npz"]
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["files"] == ["metrics.json", "result.npz"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.yaml", "o"]  # no staging left


@pytest.mark.parametrize("foreign", ["notes.txt", "sub/data.csv"])
def test_run_refuses_a_folder_with_files_it_did_not_write(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], foreign: str
) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD)
    out = tmp_path / "o"
    assert main(["run", str(path), "--out", str(out), "--no-plots"]) == 0
    (out / foreign).parent.mkdir(exist_ok=True)
    (out / foreign).write_text("mine, not firefleet's")
    before = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    capsys.readouterr()
    assert main(["run", str(path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert f"--out {out}: holds files firefleet did not write ({foreign})" in err
    assert sorted(str(p.relative_to(out)) for p in out.rglob("*")) == before
    assert (out / foreign).read_text() == "mine, not firefleet's"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.yaml", "o"]


def test_run_into_an_empty_folder_is_fine(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD)
    out = tmp_path / "empty"
    out.mkdir()
    assert main(["run", str(path), "--out", str(out), "--no-plots"]) == 0
    assert (out / "metrics.json").is_file()


def test_metrics_name_version_commit_seed_and_command(tmp_path: Path) -> None:
    path = tmp_path / "mine.yaml"
    path.write_text(GOOD)
    out = tmp_path / "o"
    argv = ["run", str(path), "--out", str(out), "--seed", "7", "--no-plots"]
    assert main(argv) == 0
    provenance = json.loads((out / "metrics.json").read_text())["provenance"]
    assert provenance["firefleet_version"] == firefleet.__version__
    assert provenance["seed"] == 7
    assert shlex.split(provenance["command"]) == ["firefleet", *argv]
    root = Path(firefleet.__file__).resolve().parents[2]
    head = subprocess.run(
        ["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True
    )
    if head.returncode == 0:  # run from a checkout
        assert provenance["git_commit"].removesuffix("-dirty") == head.stdout.strip()
    manifest = json.loads((out / MANIFEST).read_text())
    assert manifest["seed"] == 7
    assert manifest["git_commit"] == provenance["git_commit"]


def test_report_footer_names_version_commit_command_and_seeds() -> None:
    record = {"git_commit": "0123abc", "command": "firefleet reproduce --out r"}
    page = render_index([], version="9.8.7", footer=report_footer(record, {"motor-pid": 4}))
    footer = page[page.rindex("<p class=small>firefleet") :]
    for fragment in ("firefleet 9.8.7", "0123abc", "firefleet reproduce --out r", "motor-pid 4"):
        assert fragment in footer


@pytest.mark.parametrize(
    ("written", "seconds"), [("1e3", 1000.0), ("2.5E1", 25.0), ("+1e+1", 10.0), ("1_0", 10)]
)
def test_yaml_numbers_as_a_person_writes_them(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], written: str, seconds: float
) -> None:
    path = tmp_path / "n.yaml"
    path.write_text(GOOD.replace("duration_s: 1.0", f"duration_s: {written}"))
    assert main(["validate", str(path)]) == 0
    steps = round(seconds / 0.01)
    assert f"ok (mine, 1 robot(s), {steps} steps)" in capsys.readouterr().out


@pytest.mark.parametrize("written", [".nan", ".inf", "-.inf"])
def test_yaml_non_finite_number_names_the_key(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], written: str
) -> None:
    path = tmp_path / "n.yaml"
    path.write_text(GOOD.replace("duration_s: 1.0", f"duration_s: {written}"))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.strip() == f"{path}: duration_s must be a finite number"
    path.write_text(GOOD.replace("speed_rad_s: 2.0", f"speed_rad_s: {written}"))
    assert main(["validate", str(path)]) == 2
    assert "command.speed_rad_s must be a finite number" in capsys.readouterr().err


def test_claim_on_a_robot_the_team_lacks_is_a_validation_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "r.yaml"
    path.write_text(GOOD.replace("value: 0.2}", "value: 0.2, robot: 5}"))
    assert main(["validate", str(path)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1
    assert "robot 5" in err
    assert "1 robot(s)" in err
    path.write_text(GOOD.replace("value: 0.2}", "value: 0.2, robot: 1}"))
    assert main(["validate", str(path)]) == 0


def test_bare_firefleet_prints_the_help(capsys: pytest.CaptureFixture[str]) -> None:
    assert main([]) == 0
    out = capsys.readouterr().out
    assert out.startswith("usage: firefleet")
    for command in ("list", "run", "validate", "reproduce", "fis", "thermal", "stereo", "slam"):
        assert command in out


def _options() -> list[tuple[str, argparse.Action]]:
    parser = _parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return [
        (name, action)
        for name, command in sub.choices.items()
        for action in command._actions
        if action.option_strings and not isinstance(action, argparse._HelpAction)
    ]


def test_every_option_help_says_its_default() -> None:
    options = _options()
    assert len(options) > 30
    for name, action in options:
        text = action.help or ""
        assert "default" in text or "required" in text, (name, action.option_strings, text)
        default = action.default
        if isinstance(default, int | float) and not isinstance(default, bool):
            # the number the help names is the number used
            said = {f"default {default}", f"default {default:g}"}
            assert any(s in text for s in said), (name, action.option_strings, text)


def test_list_prints_one_line_per_scenario_within_80_columns(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    assert main(["list"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == list(builtin_names())
    assert max(len(line) for line in lines) <= 80
    assert any("Figure 25" in line for line in lines)


def test_run_table_fits_80_columns_and_names_every_metric_whole(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("COLUMNS", "80")
    out = tmp_path / "coop"
    assert main(["run", "coop-different-paths", "--out", str(out), "--no-plots"]) == 0
    printed = capsys.readouterr().out
    assert max(len(line) for line in printed.splitlines()) <= 80
    doc = json.loads((out / "metrics.json").read_text())
    for key in doc:
        if key not in ("scenario", "provenance", "claims"):
            assert f" {key} " in printed, key  # whole, not cut to "cross_track_rms_…"
    assert printed.count("passed") == len(doc["claims"])


def test_table_of_a_large_team_shows_min_mean_max_and_claimed_robots(
    capsys: pytest.CaptureFixture[str],
) -> None:
    values = [("gap_m", [float(k) for k in range(1, 201)])]
    claims = [{"name": "gap_m[robot 150]", "expected": "<= 200", "passed": True}]
    Console(width=80).print(claims_table("t", values, claims))
    printed = capsys.readouterr().out
    for fragment in ("min of 200", "mean of 200", "max of 200", "[robot 150]", "<= 200"):
        assert fragment in printed
    assert "100.5" in printed  # the mean of 1..200
    assert len(printed.splitlines()) < 20


def test_table_names_a_list_of_victims_by_victim_not_robot(
    capsys: pytest.CaptureFixture[str],
) -> None:
    values = [("victims_found_s", [90.5, None]), ("water_used_l", [1.0, 2.0, 3.0])]
    items = dict(task_kind("mission").list_items)
    Console(width=80).print(claims_table("t", values, [], items=items))
    printed = capsys.readouterr().out
    for fragment in ("[victim 1]", "[victim 2]", "[robot 1]", "[robot 3]", "90.5", "n/a"):
        assert fragment in printed  # water is per robot
    assert "[victim 3]" not in printed
    assert "[robot 1]" not in printed.split("water_used_l")[0]


def test_progress_on_a_pipe_is_a_few_plain_lines_on_long_runs() -> None:
    text = io.StringIO()
    console = Console(file=text, width=80)  # not a terminal
    now = [0.0]
    with progress_bar(console, "sim", clock=lambda: now[0]) as progress:
        for done in range(1, 1001):
            now[0] = done * 0.01  # a 10 s run
            progress(done, 1000)
    lines = text.getvalue().splitlines()
    assert lines == ["sim: 25 % (2 s)", "sim: 50 % (5 s)", "sim: 75 % (8 s)", "sim: 100 % (10 s)"]
    quick = io.StringIO()
    with progress_bar(Console(file=quick), "sim", clock=lambda: 0.5) as progress:
        for done in range(1, 11):
            progress(done, 10)
    assert quick.getvalue() == ""  # a short run prints nothing


@pytest.mark.parametrize(
    ("argv", "fragment"),
    [
        (["run", "motor-pid", "--seed", "abc"], "argument --seed: invalid int value: 'abc'"),
        (["run"], "the following arguments are required: SCENARIO"),
        (["nosuch"], "argument COMMAND: invalid choice: 'nosuch'"),
    ],
)
def test_bad_command_line_is_one_line_naming_the_flag(
    capsys: pytest.CaptureFixture[str], argv: list[str], fragment: str
) -> None:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert fragment in err
    assert "--help" in err


def test_slam_summary_names_version_commit_seed_and_command(tmp_path: Path) -> None:
    log = Path(__file__).resolve().parent / "data" / "victoria_park_first1500.txt"
    out = tmp_path / "s"
    argv = ["slam", str(log), "--particles", "5", "--seed", "4", "--no-plots", "--out", str(out)]
    assert main(argv) in (0, 1)
    provenance = json.loads((out / "summary.json").read_text())["provenance"]
    assert provenance["seed"] == 4
    assert provenance["firefleet_version"] == firefleet.__version__
    assert shlex.split(provenance["command"]) == ["firefleet", *argv]
    assert json.loads((out / MANIFEST).read_text())["files"] == [
        "landmarks.csv",
        "summary.json",
        "trajectory.csv",
    ]

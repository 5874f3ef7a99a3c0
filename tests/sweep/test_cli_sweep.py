"""``firefleet sweep`` on the command line: files, exit statuses, one-line errors."""

from __future__ import annotations

import json
import socket
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from firefleet import load_scenario
from firefleet.cli import main
from firefleet.sweep import parse_set, points_of, scenario_data


def test_a_sweep_writes_the_table_summary_and_plots_equal_to_firefleet_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "s"
    argv = ["sweep", "motor-pid", "--seeds", "0:3", "--set", "speed_pid.kp=2.5,4"]
    assert main([*argv, "--workers", "1", "--out", str(out)]) == 0
    names = sorted(p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file())
    assert names == [
        ".firefleet-run.json",
        "plots/metrics_vs_speed_pid.kp.png",
        "plots/pass_rates.png",
        "plots/pass_rates_vs_speed_pid.kp.png",
        "results.csv",
        "results.parquet",
        "summary.json",
    ]
    table = pq.read_table(out / "results.parquet")
    csv_lines = (out / "results.csv").read_text().splitlines()
    assert len(csv_lines) == 1 + 6
    assert csv_lines[0].startswith('"point","speed_pid.kp","seed"')
    # every run equals `firefleet run` of the point's scenario with that seed
    base = load_scenario("motor-pid")
    for row in table.to_pylist():
        (point,) = points_of(base, [parse_set(f"speed_pid.kp={row['speed_pid.kp']}")])
        path = tmp_path / f"p{row['point']}.yaml"
        path.write_text(yaml.safe_dump(scenario_data(point.scenario)))
        single = tmp_path / f"run{row['point']}-{row['seed']}"
        status = main(
            ["run", str(path), "--seed", str(row["seed"]), "--no-plots", "--out", str(single)]
        )
        doc = json.loads((single / "metrics.json").read_text())
        for claim in doc["claims"]:
            assert row[f"claim:{claim['name']} {claim['expected']}"] is claim["passed"]
        assert status == (0 if all(c["passed"] for c in doc["claims"]) else 1)
        for name in base.metric_names:
            assert row[name] == doc[name], (name, row["seed"])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["runs"] == 6
    assert summary["failed"] == 0
    assert summary["complete"]
    kp4 = summary["points"][1]
    settling = [r["settling_time_s"] for r in table.to_pylist() if r["speed_pid.kp"] == 4.0]
    assert kp4["values"] == {"speed_pid.kp": "4"}
    assert kp4["metrics"]["settling_time_s"]["mean"] == pytest.approx(sum(settling) / 3)
    passed = sum(
        r["claim:settling_time_s < 0.5"] for r in table.to_pylist() if r["speed_pid.kp"] == 4
    )
    assert kp4["claims"]["settling_time_s < 0.5"]["pass_rate"] == pytest.approx(passed / 3)
    # a rerun with more seeds resumes: the six runs are reused, three are new
    capsys.readouterr()
    assert main([*argv[:2], "--seeds", "0:4", *argv[4:], "--workers", "1", "--out", str(out)]) == 0
    assert "8 runs (6 reused" in capsys.readouterr().out
    again = pq.read_table(out / "results.parquet")
    assert again.num_rows == 8
    assert again.slice(0, 3).equals(table.slice(0, 3))  # the reused rows, run times and all


def test_failed_runs_are_recorded_and_counted_in_the_exit_status(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "f"
    argv = ["sweep", "path-straight", "--seeds", "0:2", "--no-plots", "--workers", "1"]
    status = main([*argv, "--set", "command.controller_fis=gone.fis,''", "--out", str(out)])
    assert status == 10 + 2
    err = capsys.readouterr().err
    assert "2 of 4 runs failed" in err
    errors = pq.read_table(out / "results.parquet").column("error").to_pylist()
    assert [e is not None and "gone.fis: no such file" in e for e in errors] == [
        True,
        True,
        False,
        False,
    ]


def _one_error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize(
    ("extra", "expected"),
    [
        (["--set", "command.sped_rad_s=1,2"], "did you mean 'speed_rad_s'?"),
        (["--set", "command.speed_rad_s=1,fast"], "--set command.speed_rad_s=fast: "),
        (["--seeds", "3:3"], "--seeds 3:3: an empty range of seeds"),
        (["--set", "seed=1,2"], "--set seed: not a sweep key"),
        (["--workers", "0"], "--workers must be >= 1, got 0"),
        (["--scheduler", "localhost"], "--scheduler localhost: expected an address"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    extra: list[str], expected: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / "o"
    assert main(["sweep", "motor-pid", *extra, "--out", str(out)]) == 2
    line = _one_error_line(capsys)
    assert line.startswith("firefleet: error: ")
    assert expected in line
    assert not out.exists()


def test_an_unreachable_scheduler_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    with socket.socket() as sock:  # a port nobody listens on
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    start = time.monotonic()
    out = tmp_path / "o"
    assert main(["sweep", "motor-pid", "--scheduler", address, "--out", str(out)]) == 2
    took_s = time.monotonic() - start
    line = _one_error_line(capsys)
    assert line.startswith(f"firefleet: error: --scheduler {address}: no scheduler reached")
    assert not out.exists()
    print(f"unreachable scheduler reported after {took_s:.1f} s")

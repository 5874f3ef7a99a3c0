"""The bench harness's pure logic on hand-made numbers (no timing is asserted)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

import _harness as h
from _topics import parse_bound, slug, topic_result


def rate(value: float, key: str = "t.case.rate") -> h.Row:
    return h.Row(key, value, "steps/s")


def seconds(value: float, key: str = "t.case.time_s") -> h.Row:
    return h.Row(key, value, "s", higher_is_better=False)


@pytest.mark.parametrize(
    ("op", "measured", "passed"),
    [
        (">=", 3000.0, True),
        (">=", 2999.9, False),
        (">", 3000.0, False),
        ("<=", 3000.0, True),
        ("<", 3000.0, False),
        ("<", 2999.9, True),
    ],
)
def test_floor_verdict_at_the_bound(op: h.Op, measured: float, passed: bool) -> None:
    assert h.Floor("f", measured, 3000.0, "steps/s", op).passed is passed


def test_floor_on_a_row_carries_its_key_unit_and_label() -> None:
    row = h.Row("motor.team.n10000.steps_per_s", 1151.0, "steps/s", label="N = 10,000")
    floor = h.Floor.on(row, ">=", 3000.0)
    assert (floor.name, floor.measured, floor.unit, floor.key) == (
        "N = 10,000",
        1151.0,
        "steps/s",
        "motor.team.n10000.steps_per_s",
    )
    assert not floor.passed
    assert floor.to_dict()["passed"] is False


def test_slowdown_of_rates_and_times() -> None:
    # A rate from 100 to 80 takes 1.25 times as long; a time from 2 s to 1 s halves.
    assert h.Comparison(rate(80.0), 100.0).slowdown == pytest.approx(1.25)
    assert h.Comparison(seconds(1.0), 2.0).slowdown == pytest.approx(0.5)
    assert math.isinf(h.Comparison(rate(0.0), 100.0).slowdown)


@pytest.mark.parametrize(
    ("row", "baseline", "flagged"),
    [
        (rate(90.0), 100.0, True),  # 11.1 % more time
        (rate(91.0), 100.0, False),  # 9.9 % more time
        (seconds(1.12), 1.0, True),
        (seconds(1.09), 1.0, False),
        (seconds(0.5), 1.0, False),  # faster
        (h.Row("t.case.peak_mb", 50.0, "MB", False, "memory"), 10.0, False),  # memory: info
    ],
)
def test_regression_flag_at_ten_percent(row: h.Row, baseline: float, flagged: bool) -> None:
    assert h.Comparison(row, baseline).regressed() is flagged


def test_compare_skips_rows_without_baseline_and_lists_regressions() -> None:
    base = {"a.b.rate": rate(100.0, "a.b.rate"), "a.c.time_s": seconds(1.0, "a.c.time_s")}
    now = [rate(50.0, "a.b.rate"), seconds(1.0, "a.c.time_s"), rate(1.0, "a.new.rate")]
    comps = h.compare(now, base)
    assert [c.row.key for c in comps] == ["a.b.rate", "a.c.time_s"]
    assert [c.row.key for c in h.regressions(comps)] == ["a.b.rate"]
    text = h.regression_summary(comps, [r.key for r in now], base)
    assert text.startswith("1 of 2 speed rows more than 10% slower (a.b.rate")
    assert "no baseline for a.new.rate" in text


def test_baseline_file_round_trip(tmp_path: Path) -> None:
    rows = [rate(1151.0, "motor.team.n10000.steps_per_s"), seconds(0.5, "x.y.time_s")]
    path = tmp_path / "baseline.json"
    h.write_results(path, h.baseline_document(rows, {"cpu": "test", "x": math.nan}, "abc1234"))
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["commit"] == "abc1234"
    assert doc["machine"]["x"] is None  # non-finite numbers become null
    assert h.load_baseline(path) == {r.key: r for r in rows}


def test_collect_floors_lists_required_first_and_each_floor_once() -> None:
    row = rate(5000.0, "motor.team.n10000.steps_per_s")
    same = h.Floor.on(row, ">=", 3000.0)
    other = h.Floor("own floor", 1.0, 2.0, "x")
    results = {"motor": h.TopicResult((row,), (same, other))}
    required: list[tuple[str, h.Op, float]] = [
        ("motor.team.n10000.steps_per_s", ">=", 3000.0),
        ("fuzzy.single.evals_per_s", ">=", 300_000.0),  # not measured: skipped
    ]
    floors = h.collect_floors(required, results, "issue 12")
    assert [(s, f.name) for s, f in floors] == [
        ("issue 12", "motor.team.n10000.steps_per_s"),
        ("motor", "own floor"),
    ]


def test_row_key_must_be_dotted_lower_case() -> None:
    with pytest.raises(ValueError, match="Motor team"):
        h.Row("Motor team", 1.0, "x")


def test_best_of_calls_warmup_then_repeats() -> None:
    calls: list[int] = []
    timing = h.best_of(lambda: calls.append(1), 4, warmup=2)
    assert len(calls) == 6
    assert len(timing.times_s) == 4
    assert timing.best_s == min(timing.times_s)
    both = h.best_of_interleaved({"a": lambda: calls.append(2), "b": lambda: None}, 3)
    assert calls.count(2) == 4
    assert [len(t.times_s) for t in both.values()] == [3, 3]


def test_traced_peak_sees_an_allocation() -> None:
    assert h.traced_peak_bytes(lambda: bytearray(5_000_000)) >= 5_000_000


def test_parse_bound_and_slug() -> None:
    assert parse_bound(">= 30 %") == (">=", 30.0, "%")
    assert parse_bound("< 60.0 s") == ("<", 60.0, "s")
    assert parse_bound("1,151 steps/s") == (None, 1151.0, "steps/s")
    assert parse_bound("1.06x") == (None, 1.06, "x")
    with pytest.raises(ValueError, match="PASS"):
        parse_bound("PASS")
    assert slug("Motorcycle 741 x 500") == "motorcycle_741x500"
    assert slug("calibrated, x2") == "calibrated_x2"


def test_a_topic_dict_is_read_into_rows_and_floors() -> None:
    returned = {
        "rows": [
            {"case": "3 robots", "x_real_time": 5361.2, "floor_x_real_time": 200.0},
            {"case": "1,000 robots", "x_real_time": 16.8, "floor_x_real_time": 50.0},
        ]
    }
    res = topic_result("path_following", returned)
    assert res.row("path_following.robots1000.x_real_time").value == 16.8
    assert [f.passed for f in res.floors] == [True, False]
    assert topic_result("anything", res) is res
    with pytest.raises(TypeError, match=r"bench/thermal\.py returned list"):
        topic_result("thermal", [])


def test_slam_without_victoria_park_has_scaling_rows_only() -> None:
    returned = {
        "victoria_park": {"skipped": True},
        "scaling": [
            {"particles": 100, "landmarks": 10, "steps_per_s": 8207.7, "step_peak_mb": 0.07}
        ],
        "floors": [{"name": "f", "required": "< 60.0 s", "measured": "6.28 s", "pass": True}],
    }
    res = topic_result("slam", returned)
    assert [r.key for r in res.rows] == [
        "slam.scaling.p100_l10.steps_per_s",
        "slam.scaling.p100_l10.step_peak_mb",
    ]
    assert [(f.op, f.bound, f.measured, f.unit, f.passed) for f in res.floors] == [
        ("<", 60.0, 6.28, "s", True)
    ]


def test_text_floors_in_other_words_keep_their_verdict() -> None:
    returned = {
        "victoria_park": {"skipped": True},
        "scaling": [],
        "floors": [
            {"name": "error", "required": "no worse", "measured": "0.264 vs 0.690 m", "pass": True},
            {"name": "odd", "required": "as good", "measured": "yes", "pass": False},
        ],
    }
    floors = topic_result("slam", returned).floors
    assert [(f.measured, f.op, f.bound, f.unit, f.passed) for f in floors] == [
        (0.264, "<=", 0.690, "m", True),
        (0.0, ">=", 1.0, "pass", False),
    ]
    assert floors[1].name == "odd (as good: yes)"


def test_mission_bench_scenarios_load() -> None:
    """The mission topic's scenario files exist and load (mission-office moved into
    scenarios/builtin while the bench still looked for mission-large beside it)."""
    import importlib.util

    from firefleet import load_scenario

    spec = importlib.util.spec_from_file_location(
        "_bench_mission", Path(__file__).resolve().parents[2] / "bench" / "mission.py"
    )
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    names = [load_scenario(p).name for p in (module.OFFICE, module.LARGE)]
    assert names == ["mission-office", "mission-large"]

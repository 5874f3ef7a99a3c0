"""``firefleet reproduce --seeds``: each claim's pass rate over seeds, in the report."""

from __future__ import annotations

import dataclasses
import io
from pathlib import Path

import pytest
from rich.console import Console

import firefleet
from firefleet import load_scenario
from firefleet.cli._main import _parser
from firefleet.cli._sweep import seed_pass_rates
from firefleet.report.html import ReportEntry, render_index
from firefleet.scenarios import Claim
from firefleet.sweep import claim_key


def test_pass_rates_over_seeds_match_the_runs_one_by_one(tmp_path: Path) -> None:
    base = load_scenario("motor-pid")
    result = [firefleet.compute_metrics(firefleet.simulate(base, seed=s)) for s in range(3)]
    # a bound that one seed meets and two miss (the seeds' settling times differ)
    times = sorted(float(m["settling_time_s"]) for m in result)  # type: ignore[arg-type]
    assert times[0] < times[1]
    borderline = Claim(metric="settling_time_s", op="<", value=(times[0] + times[1]) / 2)
    scenario = dataclasses.replace(base, claims=(*base.claims, borderline))
    (tmp_path / scenario.name).mkdir()
    entry = ReportEntry(
        name=scenario.name,
        title=scenario.title,
        reproduces=scenario.reproduces,
        deliverable_says="",
        folder=scenario.name,
        figures=(),
        document={"scenario": scenario.name, "claims": []},
    )
    quiet = Console(file=io.StringIO(), width=100)
    (updated,) = seed_pass_rates([entry], [scenario], (0, 1, 2), "0:3", tmp_path, quiet, quiet)
    for claim in scenario.claims:
        expected = sum(claim.holds(m.get(claim.metric)) for m in result)
        assert updated.pass_rates[claim_key(claim)] == (expected, 3)
    assert updated.pass_rates["settling_time_s < 0.5"] == (3, 3)  # the scenario's own bound
    assert sum(claim.holds(m["settling_time_s"]) for m in result) == 1
    assert updated.seeds == "0:3"
    assert "seeds.csv" in updated.links
    assert len((tmp_path / scenario.name / "seeds.csv").read_text().splitlines()) == 4
    document = {
        "scenario": scenario.name,
        "claims": [
            {"name": c.label, "expected": c.expected, "measured": 0.0, "passed": True}
            for c in scenario.claims
        ],
    }
    page = render_index([ReportEntry(**{**updated.__dict__, "document": document})], version="x")
    assert "holds over seeds 0:3" in page
    assert page.count("3/3 (100 %)") == sum(r == (3, 3) for r in updated.pass_rates.values())
    assert page.count("1/3 (33 %)") == 1


def test_reproduce_takes_seeds_and_refuses_an_empty_range(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from firefleet.cli import main

    args = _parser().parse_args(["reproduce", "--seeds", "0:20"])
    assert args.seeds == "0:20"
    assert main(["reproduce", "--seeds", "4:4", "--out", str(tmp_path / "r")]) == 2
    assert "--seeds 4:4: an empty range" in capsys.readouterr().err
    assert not (tmp_path / "r").exists()

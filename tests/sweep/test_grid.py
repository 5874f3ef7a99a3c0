"""--set and --seeds: parsed, put into the scenario and checked by its schema up front."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from firefleet import load_scenario
from firefleet.errors import InputError
from firefleet.scenarios import WheelSpeedStep
from firefleet.sweep import Point, parse_seeds, parse_set, points_of


def test_seeds_are_a_half_open_range_a_number_or_a_list() -> None:
    assert parse_seeds("0:100") == tuple(range(100))
    assert parse_seeds("4") == (4,)
    assert parse_seeds("9,2,2") == (2, 9)


@pytest.mark.parametrize("text", ["5:5", "7:3"])
def test_an_empty_seed_range_is_an_error_naming_the_flag(text: str) -> None:
    with pytest.raises(InputError, match=rf"--seeds {text}: an empty range"):
        parse_seeds(text)


@pytest.mark.parametrize("text", ["a:b", "1.5", "-2:3"])
def test_malformed_or_negative_seeds_are_errors(text: str) -> None:
    with pytest.raises(InputError, match="--seeds"):
        parse_seeds(text)


def test_values_split_at_top_level_commas_only() -> None:
    axis = parse_set("poses=[[0, 0, 0]], [[0, 0, 0], [1, 0, 90]]")
    assert axis.values == ([[0, 0, 0]], [[0, 0, 0], [1, 0, 90]])
    assert parse_set("command.speed_rad_s=1e1,2").values == (10.0, 2)


def _speed(point: Point) -> float:
    command = point.scenario.command
    assert isinstance(command, WheelSpeedStep)
    return command.speed_rad_s


def test_the_grid_is_the_product_and_zip_pairs() -> None:
    base = load_scenario("motor-pid")
    axes = [parse_set("command.speed_rad_s=1,2,3"), parse_set("speed_pid.kp=1,2,3")]
    grid = points_of(base, axes)
    assert [(_speed(p), p.scenario.speed_pid.kp) for p in grid] == [
        (a, b) for a in (1.0, 2.0, 3.0) for b in (1.0, 2.0, 3.0)
    ]
    zipped = points_of(base, axes, zipped=True)
    assert [(_speed(p), p.scenario.speed_pid.kp) for p in zipped] == [
        (1.0, 1.0),
        (2.0, 2.0),
        (3.0, 3.0),
    ]
    # everything not swept is the base scenario's
    assert grid[0].scenario.motor == base.motor
    assert grid[0].scenario.claims == base.claims
    assert len({p.digest for p in grid}) == 9


def test_a_misspelt_key_gets_the_schemas_did_you_mean() -> None:
    with pytest.raises(InputError) as info:
        points_of(load_scenario("motor-pid"), [parse_set("command.sped_rad_s=1,2")])
    message = str(info.value)
    assert message.startswith("--set command.sped_rad_s=1: command.sped_rad_s: unknown key")
    assert "did you mean 'speed_rad_s'?" in message
    assert "\n" not in message


def test_a_bad_value_names_the_key_and_the_value() -> None:
    with pytest.raises(InputError, match=r"--set encoder.counts_per_rev=lots: .*counts_per_rev"):
        points_of(load_scenario("motor-pid"), [parse_set("encoder.counts_per_rev=2048,lots")])


def test_zip_needs_as_many_values_on_every_key() -> None:
    axes = [parse_set("command.speed_rad_s=1,2"), parse_set("speed_pid.kp=1,2,3")]
    with pytest.raises(InputError, match=r"--zip: .*command.speed_rad_s \(2\), speed_pid.kp \(3\)"):
        points_of(load_scenario("motor-pid"), axes, zipped=True)


@pytest.mark.parametrize("text", ["command.speed_rad_s", "=1,2", "command.speed_rad_s=1,,2"])
def test_malformed_set_is_an_error(text: str) -> None:
    with pytest.raises(InputError, match="--set"):
        parse_set(text)


def test_a_value_read_from_a_file(tmp_path: Path) -> None:
    team = [[0.0, 0.0, 0.0], [1.0, 0.0, 90.0]]
    (tmp_path / "team2.yaml").write_text(yaml.safe_dump(team))
    axis = parse_set("poses=@team2.yaml", base=tmp_path)
    assert axis.labels == ("@team2.yaml",)
    (point,) = points_of(load_scenario("motor-pid"), [axis])
    assert point.scenario.n_robots == 2
    assert point.scenario.poses[1] == (1.0, 0.0, 90.0)
    with pytest.raises(InputError, match=r"@missing\.yaml: no such file"):
        parse_set("poses=@missing.yaml", base=tmp_path)


def test_a_key_inside_a_list_by_index() -> None:
    base = load_scenario("coop-different-paths")
    (point,) = points_of(base, [parse_set("command.paths[1].x_end_m=19.0")])
    assert point.scenario.command.paths[1].x_end_m == 19.0  # type: ignore[union-attr]
    assert point.scenario.command.paths[0] == base.command.paths[0]  # type: ignore[union-attr]
    with pytest.raises(InputError, match=r"no item \[7\]"):
        points_of(base, [parse_set("command.paths[7].x_end_m=19.0")])

"""The registry of task kinds: every command kind is one, looked up by its string."""

from __future__ import annotations

import pytest

from firefleet import builtin_names, load_scenario
from firefleet.errors import InputError
from firefleet.scenarios.schema import Command
from firefleet.sim import registry
from firefleet.sim.registry import TaskKind, kind_names, register, task_kind


def _no_metrics(result: object) -> dict[str, float | list[float]]:
    return {"x_m": 1.0}


def _no_figures(result: object, metrics: object) -> dict[str, bytes]:
    return {}


def test_every_command_kind_of_the_schema_is_a_registered_kind() -> None:
    import typing

    tags = {
        typing.get_args(typing.get_type_hints(member)["kind"])[0]
        for member in typing.get_args(typing.get_args(Command)[0])
    }
    assert set(kind_names()) == tags
    for name in tags:
        kind = task_kind(name)
        assert kind.name == name
        assert kind.metric_names
        assert len(set(kind.metric_names)) == len(kind.metric_names)


def test_scenario_metric_names_come_from_the_kind() -> None:
    for name in builtin_names():
        scn = load_scenario(name)
        assert scn.metric_names == task_kind(scn.command.kind).metric_names


def test_unknown_kind_names_the_known_ones() -> None:
    with pytest.raises(InputError, match=r"unknown kind 'swarm'.*path-following"):
        task_kind("swarm")


def test_register_adds_a_kind_and_refuses_a_taken_name(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registry, "_REGISTERED", {})
    new = TaskKind(
        name="survey",
        metric_names=("x_m",),
        metrics=_no_metrics,
        figures=_no_figures,
        runner=lambda scenario, rec_steps, progress: None,  # type: ignore[arg-type,return-value]
    )
    register(new)
    assert task_kind("survey") is new
    assert "survey" in kind_names()
    with pytest.raises(InputError, match="registered already"):
        register(new)
    with pytest.raises(InputError, match="registered already"):
        register(TaskKind("formation", ("x_m",), _no_metrics, _no_figures, runner=new.runner))


def test_a_kind_has_a_decider_or_a_runner() -> None:
    with pytest.raises(InputError, match="decider or a runner"):
        TaskKind("x", ("x_m",), _no_metrics, _no_figures)


def test_looking_kinds_up_does_not_import_matplotlib() -> None:
    # the figures functions import their report code only when called
    import subprocess
    import sys

    code = (
        "import sys, firefleet\n"
        "from firefleet.sim.registry import kind_names, task_kind\n"
        "[task_kind(k).figures for k in kind_names()]\n"
        "print('matplotlib' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"

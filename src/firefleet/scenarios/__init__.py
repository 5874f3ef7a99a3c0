"""Scenarios: typed, strict YAML descriptions of an experiment, and the built-in ones."""

from firefleet.scenarios.registry import builtin_names, load_scenario
from firefleet.scenarios.schema import (
    Claim,
    LoadStep,
    Scenario,
    VoltageStep,
    WheelSpeedStep,
    parse_scenario,
    read_scenario_file,
)

__all__ = [
    "Claim",
    "LoadStep",
    "Scenario",
    "VoltageStep",
    "WheelSpeedStep",
    "builtin_names",
    "load_scenario",
    "parse_scenario",
    "read_scenario_file",
]

"""The Raspberry Pi deployment: the systemd unit parses and runs ``firefleet robot`` as
the README says, and the README's wiring table, the configurations and the Pi's header
map (gpiozero's, an independent source) agree pin for pin."""

from __future__ import annotations

import configparser
import re
import shlex
from pathlib import Path
from typing import Any

import pytest
import yaml

from firefleet.robot import parse_robot_config

ROOT = Path(__file__).resolve().parents[2]
UNIT = ROOT / "deploy" / "firefleet-robot.service"
PI_CONFIG = ROOT / "deploy" / "robot.yaml"
EXAMPLE = ROOT / "examples" / "robot-fake.yaml"


def unit() -> configparser.ConfigParser:
    parser = configparser.ConfigParser(interpolation=None, strict=True)
    parser.optionxform = str  # type: ignore[assignment,method-assign]  # keys are case-sensitive
    parser.read_string(UNIT.read_text(encoding="utf-8"))
    return parser


def test_the_systemd_unit_runs_firefleet_robot() -> None:
    u = unit()
    assert set(u.sections()) == {"Unit", "Service", "Install"}
    service = u["Service"]
    argv = shlex.split(service["ExecStart"])
    assert Path(argv[0]).name == "firefleet"
    assert Path(argv[0]).is_absolute()  # systemd needs an absolute executable
    assert argv[1:3] == ["robot", "/etc/firefleet/robot.yaml"]
    assert "--fake" not in argv
    assert service["Restart"] == "on-failure"
    assert service["KillSignal"] == "SIGTERM"
    assert service["User"] == "firefleet"
    assert service["RestartPreventExitStatus"] == "2"  # the CLI's exit status on bad input
    assert int(service["TimeoutStopSec"]) >= 5
    assert u["Install"]["WantedBy"] == "multi-user.target"
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    # the README installs the unit and the configuration where ExecStart looks
    assert "deploy/robot.yaml /etc/firefleet/robot.yaml" in readme
    # ... and the checkout and its venv where ExecStart runs firefleet from
    assert argv[0] == "/opt/firefleet/.venv/bin/firefleet"
    assert "/opt/firefleet && cd /opt/firefleet" in readme
    assert "sudo python3 -m venv .venv" in readme


def _wiring_rows() -> list[list[str]]:
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    section = readme.split("### On a Raspberry Pi", 1)[1].split("\n## ", 1)[0]
    rows = [
        [c.strip() for c in line.strip().strip("|").split("|")]
        for line in section.splitlines()
        if line.startswith("| ") and not line.startswith("| Device")
    ]
    assert len(rows) == 8
    return rows


def _lookup(config: dict[str, Any], key: str) -> Any:
    value: Any = config["hardware"]
    for part in key.split("."):
        value = value[part]
    return value


@pytest.mark.parametrize("path", [PI_CONFIG, EXAMPLE], ids=["deploy", "example"])
def test_the_readme_wiring_is_the_configurations(path: Path) -> None:
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    parse_robot_config(data, origin=path.name)  # a valid configuration
    checked = 0
    for device, connection, pi, keys in _wiring_rows():
        pairs = dict(re.findall(r"`([a-z0-9_.]+): ([^`]+)`", keys))
        assert pairs, f"{device}: no configuration key"
        for key, text in pairs.items():
            try:
                value = _lookup(data, key)
            except KeyError:
                assert path == EXAMPLE, f"{path.name} has no hardware.{key}"
                continue  # the example config does not fit every device
            assert str(value) == text, f"{device}: README {key}: {text}, {path.name}: {value}"
            checked += 1
        # and the Pi column says the same as the configuration
        gpio = re.match(r"GPIO(\d+)", pi)
        for key, text in pairs.items():
            if key.endswith("_gpio"):
                assert gpio is not None
                assert gpio.group(1) == text
            if key.endswith("spi_device"):
                bus = pairs[key.replace("spi_device", "spi_bus")]
                assert f"SPI{bus} CE{text}" in connection
            if key.endswith("i2c_bus"):
                assert f"I2C{text}" in connection
            if key.endswith(("port", "left", "right")):
                assert pi == f"`{text}`"
    assert checked >= (10 if path == PI_CONFIG else 5)


@pytest.mark.parametrize("revision", ["c03111", "d04170"], ids=["pi4", "pi5"])
def test_the_readme_header_pins_are_the_pis(revision: str) -> None:
    from gpiozero import pi_info  # type: ignore[import-untyped]

    header = {p.number: p.name for p in pi_info(revision).headers["J8"].pins.values()}
    text = " ".join(" ".join(row[1:3]) for row in _wiring_rows())
    pins = re.findall(r"GPIO(\d+),? \(?pin (\d+)\)?", text)
    assert len(pins) >= 9
    for gpio, pin in pins:
        assert header[int(pin)] == f"GPIO{gpio}"

"""Every runtime dependency installs on a Raspberry Pi 4/5 (64-bit Raspberry Pi OS,
CPython 3.11) from a wheel: asked of the package index itself (PEP 691's JSON simple
API), not assumed, so that `pip install firefleet` does not compile for an hour."""

from __future__ import annotations

import json
import re
import time
import tomllib
import urllib.request
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
INDEX = "https://pypi.org/simple/{name}/"
# platforms a Pi 4/5 on 64-bit Raspberry Pi OS (Debian 12, glibc 2.36) takes
PLATFORM = re.compile(
    r"manylinux_2_(1[7-9]|2\d|3[0-6])_aarch64|manylinux2014_aarch64|linux_aarch64|any"
)


def _runtime_pins() -> list[tuple[str, str]]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    pins = list(project["dependencies"]) + list(project["optional-dependencies"].get("robot", []))
    out = []
    for pin in pins:
        name, _, version = pin.partition("==")
        out.append((re.sub(r"\[.*\]", "", name).strip(), version.strip()))
    return out


def _files(name: str) -> list[str]:
    request = urllib.request.Request(
        INDEX.format(name=name), headers={"Accept": "application/vnd.pypi.simple.v1+json"}
    )
    for attempt in range(3):
        try:
            with urllib.request.urlopen(request, timeout=20) as response:
                return [f["filename"] for f in json.load(response)["files"]]
        except OSError:
            if attempt == 2:
                raise
            time.sleep(2.0)
    raise AssertionError("unreachable")


def _wheel_ok(filename: str, name: str, version: str) -> bool:
    """Whether a file is a wheel of ``name==version`` that CPython 3.11 on a Pi installs."""
    if not filename.endswith(".whl"):
        return False
    parts = filename[:-4].split("-")
    dist, ver, py, abi, plat = parts[0], parts[1], parts[-3], parts[-2], parts[-1]
    if dist.lower().replace("_", "-") != name.lower().replace("_", "-") or ver != version:
        return False
    pythons = py.split(".")
    if abi == "none":  # pure Python, or one build for any CPython 3
        python_ok = any(p in ("py3", "cp311") for p in pythons)
    elif abi == "abi3":  # the stable ABI: built for CPython 3.X <= 3.11 runs on 3.11
        python_ok = any(re.fullmatch(r"cp3\d+", p) and int(p[3:]) <= 11 for p in pythons)
    else:
        python_ok = abi == "cp311" and "cp311" in pythons
    return python_ok and any(PLATFORM.fullmatch(p) for p in plat.split("."))


@pytest.mark.parametrize(("name", "version"), _runtime_pins())
def test_runtime_dependency_has_an_aarch64_wheel(name: str, version: str) -> None:
    files = _files(name)
    assert any(_wheel_ok(f, name, version) for f in files), (
        f"{name}=={version}: no wheel for CPython 3.11 on manylinux aarch64 on PyPI"
    )


@pytest.mark.parametrize(
    ("filename", "ok"),
    [
        ("numpy-2.4.6-cp311-cp311-manylinux_2_27_aarch64.manylinux_2_28_aarch64.whl", True),
        ("numpy-2.4.6-cp311-cp311-manylinux_2_27_x86_64.whl", False),
        ("numpy-2.4.6-cp312-cp312-manylinux_2_28_aarch64.whl", False),
        ("numpy-2.4.6-cp311-cp311-manylinux_2_39_aarch64.whl", False),  # glibc above Debian 12's
        ("numpy-2.4.6.tar.gz", False),
        ("rich-15.0.0-py3-none-any.whl", True),
        ("eclipse_zenoh-1.10.2-cp39-abi3-manylinux_2_17_aarch64.manylinux2014_aarch64.whl", True),
        ("foo-1.0-cp312-abi3-manylinux_2_28_aarch64.whl", False),
    ],
)
def test_the_wheel_tag_rules(filename: str, ok: bool) -> None:
    name, version = filename.split("-")[:2]
    assert _wheel_ok(filename, name.replace("_", "-"), version.removesuffix(".tar.gz")) is ok

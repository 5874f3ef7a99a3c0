"""Every Python example in the README runs as printed, in a fresh folder."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


def _blocks() -> list[tuple[int, str]]:
    """(line number, code) of every ```python block of the README."""
    text = README.read_text(encoding="utf-8")
    return [
        (text[: m.start()].count("\n") + 1, m.group(1))
        for m in re.finditer(r"^```python\n(.*?)^```", text, re.S | re.M)
    ]


SHIPPED = ("motor_pid.py", "slam_loop.py")
"""Examples the README prints whole: tests/test_examples.py runs each shipped file, checks
the numbers it prints, and checks that the README holds its code; a block that is one of
them is not run a second time here (the SLAM loop took 10 s)."""


def _shipped() -> set[str]:
    examples = README.parent / "examples"
    return {(examples / name).read_text().split('"""', 2)[2].strip() for name in SHIPPED}


def _params() -> list[object]:
    shipped = _shipped()
    return [
        pytest.param(code, id=f"README.md:{line}")
        for line, code in _blocks()
        if code.strip() not in shipped
    ]


def test_the_shipped_examples_are_readme_blocks() -> None:
    # what _params leaves out is run by tests/test_examples.py, block for block
    blocks = {code.strip() for _, code in _blocks()}
    assert _shipped() <= blocks


def test_the_readme_has_python_examples() -> None:
    assert len(_blocks()) >= 6


@pytest.mark.parametrize("code", _params())
def test_readme_example_runs_as_printed(code: str, tmp_path: Path) -> None:
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)}
    done = subprocess.run(
        [sys.executable, "-c", code],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        env=env,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr


def test_readme_scenario_yaml_validates(tmp_path: Path) -> None:
    from firefleet.cli import main

    text = README.read_text(encoding="utf-8")
    blocks = re.findall(r"^```yaml\n(.*?)^```", text, re.S | re.M)
    scenarios = [b for b in blocks if b.startswith("name:")]  # whole files, not fragments
    assert scenarios
    for k, block in enumerate(scenarios):
        path = tmp_path / f"s{k}.yaml"
        path.write_text(block, encoding="utf-8")
        assert main(["validate", str(path)]) == 0, block

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


def _params() -> list[object]:
    params: list[object] = []
    for line, code in _blocks():
        params.append(pytest.param(code, id=f"README.md:{line}"))
    return params


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

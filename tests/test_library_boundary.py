"""models, control, planning, perception, estimation and world are libraries: they import
neither the report nor the command line, write no file a command line decides on, and
keep each module small (a package of private modules past about 600 lines)."""

from __future__ import annotations

import ast
import importlib
import subprocess
import sys
from pathlib import Path

import pytest

LIBRARIES = (
    "firefleet.models",
    "firefleet.control",
    "firefleet.planning",
    "firefleet.perception",
    "firefleet.estimation",
    "firefleet.world",
)
FORBIDDEN = ("firefleet.report", "firefleet.cli", "firefleet.outputs", "matplotlib")
# Path.write_text / write_bytes, np.save, json.dump, mkdir: the command line's job
WRITES = {"write_text", "write_bytes", "save", "savez", "savez_compressed", "dump", "mkdir"}
MAX_LINES = 650


def _sources(package: str) -> list[Path]:
    module = importlib.import_module(package)
    assert module.__file__ is not None
    return sorted(Path(module.__file__).parent.rglob("*.py"))


@pytest.mark.parametrize("package", LIBRARIES)
def test_importing_the_library_loads_no_report_or_cli_module(package: str) -> None:
    root = Path(importlib.import_module("firefleet").__file__ or "").parents[1]
    names = [
        ".".join(p.relative_to(root).with_suffix("").parts).removesuffix(".__init__")
        for p in _sources(package)
    ]
    code = (
        "import importlib, sys\n"
        f"for name in {names!r}: importlib.import_module(name)\n"
        f"print(','.join(sorted(m for m in sys.modules if m.startswith({FORBIDDEN!r}))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == ""


@pytest.mark.parametrize("package", LIBRARIES)
def test_no_library_source_imports_report_or_cli_or_writes_files(package: str) -> None:
    sources = _sources(package)
    assert len(sources) >= 3
    for path in sources:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith(FORBIDDEN), path
            if isinstance(node, ast.Import):
                for alias in node.names:
                    assert not alias.name.startswith(FORBIDDEN), path
            if isinstance(node, ast.Attribute):
                assert node.attr not in WRITES, (path, node.lineno)
            if isinstance(node, ast.Name):
                assert node.id != "open", (path, node.lineno)


@pytest.mark.parametrize("package", LIBRARIES)
def test_no_library_module_much_over_600_lines(package: str) -> None:
    for path in _sources(package):
        assert len(path.read_text(encoding="utf-8").splitlines()) <= MAX_LINES, path

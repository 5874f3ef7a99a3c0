"""control.fuzzy is a library: it imports neither the report nor the command line, writes
no file, and keeps each module under about 600 lines (a library, not a command line)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import firefleet.control.fuzzy

PACKAGE = Path(firefleet.control.fuzzy.__file__).parent
SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_importing_fuzzy_loads_no_report_cli_or_output_module() -> None:
    code = (
        "import sys\n"
        "import firefleet.control.fuzzy, firefleet.control.fuzzy_kernel\n"
        "bad = sorted(m for m in sys.modules if m.startswith(('firefleet.report', "
        "'firefleet.cli', 'firefleet.outputs', 'matplotlib')))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == ""


def test_no_fuzzy_source_imports_report_or_cli_or_writes_files() -> None:
    assert len(SOURCES) == 6  # __init__ and five private modules
    for path in SOURCES:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith(("firefleet.report", "firefleet.cli")), path
                assert node.module != "firefleet.outputs", path
            if isinstance(node, ast.Attribute):
                bad = {"write_text", "write_bytes", "save", "savez", "dump", "mkdir"}
                assert node.attr not in bad, (path, node.lineno)
            if isinstance(node, ast.Name):
                assert node.id != "open", (path, node.lineno)


def test_no_module_much_over_600_lines() -> None:
    for path in SOURCES:
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 600, path

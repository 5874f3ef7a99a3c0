"""estimation is a library: it imports neither the report nor the command line, writes
no file, and keeps each module small (issue 12, point 4)."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import firefleet.estimation

PACKAGE = Path(firefleet.estimation.__file__).parent
SOURCES = sorted(PACKAGE.rglob("*.py"))


def test_importing_estimation_loads_no_report_or_cli_module() -> None:
    code = (
        "import sys\n"
        "import firefleet.estimation, firefleet.estimation.fastslam\n"
        "bad = sorted(m for m in sys.modules if m.startswith(('firefleet.report', "
        "'firefleet.cli', 'matplotlib')))\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == ""


def test_no_estimation_source_imports_report_or_cli_or_writes_files() -> None:
    assert len(SOURCES) >= 12  # the fastslam package, logs, particle_filter, alignment
    for path in SOURCES:
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith(("firefleet.report", "firefleet.cli")), path
            if isinstance(node, ast.Import):
                for alias in node.names:
                    assert not alias.name.startswith(("firefleet.report", "firefleet.cli")), path
            if isinstance(node, ast.Attribute):
                # Path.write_text / write_bytes, np.save, json.dump, mkdir: the CLI's job
                bad = {"write_text", "write_bytes", "save", "savez", "dump", "mkdir"}
                assert node.attr not in bad, (path, node.lineno)


def test_no_module_much_over_600_lines() -> None:
    for path in SOURCES:
        assert len(path.read_text(encoding="utf-8").splitlines()) <= 650, path

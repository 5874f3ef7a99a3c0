"""Fixtures shared across the test folders: the reproduction report, made once a session.

``firefleet reproduce`` runs every built-in scenario (each one's claims, figures and
``metrics.json``), the deliverable's section 2.7 and the link study: minutes of the
suite. The report's test (``tests/test_cli.py::test_reproduce_writes_report``) and the
built-ins' claim checks (``tests/sim/test_engine.py``) read the same run, so each
built-in is simulated once per session, not twice. The report runs its experiments in
``REPORT_WORKERS`` processes (``--workers``): nothing else of the suite runs while the
session fixture is made, so the real-time and browser tests do not share the cores.
"""

from __future__ import annotations

import contextlib
import io
import json
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from tests._reproduce import Reproduced

REPORT_TEST = ("test_cli.py", "test_reproduce_writes_report")
"""The test that runs the whole report (file name, function name)."""
REPORT_WORKERS = min(2, os.cpu_count() or 1)
"""Processes the session's report runs its experiments in: 2 (CI's machine has 2 cores),
1 on a machine with one."""


@pytest.fixture(scope="session")
def reproduced(tmp_path_factory: pytest.TempPathFactory) -> Reproduced:
    """The report, made once: section 2.7 without Victoria Park (an empty data folder),
    its experiments in ``REPORT_WORKERS`` processes."""
    from firefleet.cli import main

    root = tmp_path_factory.mktemp("reproduce")
    out = root / "report"
    no_data = root / "no-data"  # section 2.7 without Victoria Park: said, not failed
    no_data.mkdir()
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        status = main(
            [
                "reproduce",
                "--out",
                str(out),
                "--data",
                str(no_data),
                "--workers",
                str(REPORT_WORKERS),
            ]
        )
    return Reproduced(
        out=out,
        no_data=no_data,
        workers=REPORT_WORKERS,
        status=status,
        stdout=printed.getvalue(),
    )


def _runs_the_report(session: pytest.Session) -> bool:
    return any((item.path.name, item.name) == REPORT_TEST for item in session.items)


@pytest.fixture(scope="session")
def report_out(request: pytest.FixtureRequest) -> Path | None:
    """The session's report folder when the session runs the report's test (its runs'
    figures, drawn by the same functions), else None (a test then makes its own)."""
    if _runs_the_report(request.session):
        out: Path = request.getfixturevalue("reproduced").out
        return out
    return None


@pytest.fixture(scope="session")
def builtin_document(request: pytest.FixtureRequest) -> Callable[[str], dict[str, Any]]:
    """A built-in scenario's ``metrics.json`` document (its metrics and checked claims) at
    its own seed: read from the session's report when the session runs the report's
    test (the same run, by the same functions), else simulated here."""
    if _runs_the_report(request.session):
        out = request.getfixturevalue("reproduced").out

        def from_report(name: str) -> dict[str, Any]:
            document: dict[str, Any] = json.loads((out / name / "metrics.json").read_text())
            document.pop("provenance")
            return document

        return from_report

    from firefleet import compute_metrics, load_scenario, simulate
    from firefleet.sim.metrics import metrics_document

    def simulated(name: str) -> dict[str, Any]:
        scenario = load_scenario(name)
        metrics = compute_metrics(simulate(scenario))
        return metrics_document(scenario.name, scenario.claims, metrics)

    return simulated

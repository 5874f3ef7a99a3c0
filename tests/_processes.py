"""The multi-process tests' guard: no child process outlives a test."""

from __future__ import annotations

import time
from collections.abc import Iterator

import psutil  # type: ignore[import-untyped]  # no type information shipped
import pytest


@pytest.fixture(autouse=True)
def no_stray_processes() -> Iterator[None]:
    """Fail (and clean up) if a test leaves a child process running (a module uses it by
    importing it: an autouse fixture)."""
    me = psutil.Process()
    before = {p.pid for p in me.children(recursive=True)}
    stray: list[psutil.Process] = []
    try:
        yield
    finally:
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            stray = [p for p in me.children(recursive=True) if p.pid not in before]
            if not stray:
                break
            time.sleep(0.05)
        for proc in stray:
            proc.kill()
        psutil.wait_procs(stray, timeout=5.0)
    assert not stray, f"processes left running: {[p.pid for p in stray]}"

"""What the session's ``firefleet reproduce`` run left (the ``reproduced`` fixture of
tests/conftest.py)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class Reproduced:
    """One ``firefleet reproduce --out out --data no_data --workers workers`` run: its
    folders, its processes, its exit status and what it printed."""

    out: Path
    no_data: Path
    workers: int
    status: int
    stdout: str

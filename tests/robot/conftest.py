from __future__ import annotations

import ctypes
from pathlib import Path

import pytest

from tests.robot._firmware import build


@pytest.fixture(scope="session")
def firmware(tmp_path_factory: pytest.TempPathFactory) -> ctypes.CDLL:
    """The sketch's portable C, compiled for this machine."""
    return build(Path(tmp_path_factory.mktemp("firmware")))

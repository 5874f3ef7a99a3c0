"""One simulated 100 m drive shared by the estimation tests (simulating it takes ~1.5 s)."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.sim.world import DriveResult, simulate_drive


@pytest.fixture(scope="session")
def drive() -> DriveResult:
    return simulate_drive(np.random.default_rng(1))

"""The Lepton adapter on a fake camera: whole frames only, damage counted, CCI commands
as the interface document numbers them."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.robot import FakeLepton, Lepton


def _frames(lepton: int, n: int = 5) -> np.ndarray:
    shape = (60, 80) if lepton == 2 else (120, 160)
    rng = np.random.default_rng(lepton)
    return rng.integers(27_000, 33_000, (n, *shape)).astype(np.uint16)


@pytest.mark.parametrize(("lepton", "damage_every"), [(2, 0), (3, 0), (2, 151), (3, 503)])
def test_frames_read_whole_never_mixed(lepton: int, damage_every: int) -> None:
    source = _frames(lepton)
    camera = Lepton(FakeLepton(source, lepton=lepton, damage_every=damage_every), lepton=lepton)
    seen = set()
    for _ in range(12):
        frame = camera.read_frame()
        assert frame is not None
        matches = [k for k in range(len(source)) if np.array_equal(frame, source[k])]
        assert len(matches) == 1  # exactly one of the camera's frames, never two put together
        seen.add(matches[0])
    # frames split across reads are assembled (with damage, the looped stream's damaged
    # frames are damaged on every pass: fewer distinct frames get through)
    assert len(seen) >= (2 if damage_every else 3)
    if damage_every:
        assert camera.stats.bad_packets > 0
    else:
        assert camera.stats.bad_packets == 0


def test_cci_commands_follow_the_interface_document() -> None:
    fake = FakeLepton(_frames(2, 1), lepton=2, busy_reads=3)
    camera = Lepton(fake, cci=fake, lepton=2)
    camera.run_ffc()
    camera.enable_tlinear()
    assert fake.commands == [(0x0242, ()), (0x4EC1, (1, 0))]  # SYS run FFC; RAD TLinear set


def test_a_stuck_or_missing_cci_is_a_clear_error() -> None:
    fake = FakeLepton(_frames(2, 1), lepton=2, busy_reads=10**9)
    with pytest.raises(InputError, match="stayed busy"):
        Lepton(fake, cci=fake, lepton=2)._command(0x0242, timeout_s=0.05)
    with pytest.raises(InputError, match="no CCI bus"):
        Lepton(fake, lepton=2).run_ffc()
    with pytest.raises(InputError, match="lepton must be 2 or 3"):
        Lepton(fake, lepton=4)

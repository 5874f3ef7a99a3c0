"""The FLIR Lepton on the robot: video over SPI (VoSPI), control over I2C (CCI).

Video: the adapter reads the SPI bus in blocks of whole packets (``spidev``'s
``readbytes``) and assembles frames with :func:`firefleet.perception.vospi.parse_vospi`,
the parser the ``thermal`` command and its tests use, which drops and counts damaged
packets and never raises on them. It parses windows of two frames' worth of packets
(each byte once, so the counts are true): any two frames' worth of consecutive packets
of an undamaged stream holds one whole frame, and the camera sends each frame about
three times (27 Hz of video for 9 Hz of new frames), so the frames missed between
windows are repeats.

Control (CCI, the Lepton Software Interface Description Document 110-0144): I2C address
0x2A, 16-bit big-endian registers: STATUS 0x0002 (bit 0 busy), COMMAND 0x0004,
DATA LENGTH 0x0006 (in 16-bit words), DATA 0 at 0x0008. A command ID is the module's base
plus the command's offset plus its type (0 get, 1 set, 2 run); the radiometry module
needs the OEM bit 0x4000. Used here: SYS run FFC (flat-field correction) ``0x0242``, and
RAD TLinear enable set ``0x4EC1`` (frames in centikelvin instead of Raw14 counts). The
adapter waits for the busy bit to clear before and after each command.

Both talk to small interfaces (:class:`SpiReader`, :class:`CciBus`): on the robot an
``spidev.SpiDev`` and :class:`LinuxI2c` (``/dev/i2c-N`` through ``ioctl(I2C_SLAVE)``, no
extra library); in tests :class:`FakeLepton`, which streams a VoSPI encoding of given
frames, damaged at a chosen rate, and models the CCI registers.

References
----------
FLIR Lepton Engineering Datasheet 500-0659-00-09 rev 203, sections 4.2 (VoSPI) and
4.1 (CCI). FLIR Lepton Software Interface Description Document 110-0144-04.
"""

from __future__ import annotations

import os
import time
from dataclasses import fields
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError
from firefleet.perception.vospi import PACKET_BYTES, VospiStats, encode_vospi, parse_vospi

__all__ = ["CciBus", "FakeLepton", "Lepton", "LinuxI2c", "SpiReader"]

CCI_ADDRESS = 0x2A
STATUS, COMMAND, DATA_LENGTH, DATA0 = 0x0002, 0x0004, 0x0006, 0x0008
BUSY = 0x0001
SYS_RUN_FFC = 0x0242
RAD_TLINEAR_SET = 0x4EC1
_READ_PACKETS = 20


class SpiReader(Protocol):
    """What the video side needs of an SPI device (spidev's ``readbytes``)."""

    def readbytes(self, n: int) -> list[int]: ...


class CciBus(Protocol):
    """What the control side needs: 16-bit register reads and writes."""

    def read_register(self, register: int) -> int: ...

    def write_register(self, register: int, value: int) -> None: ...


class LinuxI2c:
    """The Lepton's CCI on a Linux I2C bus (``/dev/i2c-1`` on a Raspberry Pi)."""

    def __init__(self, bus: int = 1, address: int = CCI_ADDRESS) -> None:
        import fcntl

        self._fd = os.open(f"/dev/i2c-{bus}", os.O_RDWR)
        fcntl.ioctl(self._fd, 0x0703, address)  # I2C_SLAVE

    def read_register(self, register: int) -> int:
        """The 16-bit value of a register."""
        os.write(self._fd, register.to_bytes(2, "big"))
        return int.from_bytes(os.read(self._fd, 2), "big")

    def write_register(self, register: int, value: int) -> None:
        """Write a 16-bit value to a register."""
        os.write(self._fd, register.to_bytes(2, "big") + (value & 0xFFFF).to_bytes(2, "big"))

    def close(self) -> None:
        """Close the bus."""
        os.close(self._fd)


class Lepton:
    """A Lepton 2.x (80 x 60) or 3.x (160 x 120) on SPI, with its CCI if given.

    Parameters
    ----------
    spi : SpiReader
        The VoSPI bus (mode 3, up to 20 MHz).
    cci : CciBus, optional, keyword-only
        The control bus.
    lepton : {2, 3}, keyword-only
        The camera's generation.

    Attributes
    ----------
    stats : VospiStats
        The parser's counts, summed over every read.

    Examples
    --------
    >>> import numpy as np
    >>> from firefleet.robot import FakeLepton, Lepton
    >>> scene = np.full((3, 60, 80), 29_815, np.uint16)  # 25 deg C in centikelvin
    >>> camera = Lepton(FakeLepton(scene, lepton=2), lepton=2)
    >>> frame = camera.read_frame()
    >>> frame.shape, int(frame[0, 0])
    ((60, 80), 29815)
    """

    def __init__(self, spi: SpiReader, *, cci: CciBus | None = None, lepton: int = 2) -> None:
        if lepton not in (2, 3):
            raise InputError(f"lepton must be 2 or 3, got {lepton!r}")
        self._spi = spi
        self._cci = cci
        self.lepton = lepton
        packets_per_frame = 60 if lepton == 2 else 240
        self._window = 2 * packets_per_frame * PACKET_BYTES
        self.stats = VospiStats()

    def read_frame(self, *, max_windows: int = 20) -> NDArray[np.uint16] | None:
        """The newest whole frame of the next window of two frames' worth of packets
        (any 2 x 60 consecutive packets of an undamaged stream hold a whole frame);
        None if ``max_windows`` windows in a row held none."""
        for _ in range(max_windows):
            data = bytearray()
            while len(data) < self._window:
                data += bytes(self._spi.readbytes(_READ_PACKETS * PACKET_BYTES))
            result = parse_vospi(bytes(data), lepton=2 if self.lepton == 2 else 3)
            self._add(result.stats)
            if result.frames.shape[0]:
                return np.asarray(result.frames[-1])
        return None

    def _add(self, stats: VospiStats) -> None:
        summed = {
            f.name: getattr(self.stats, f.name) + getattr(stats, f.name) for f in fields(stats)
        }
        summed["trailing_bytes"] = stats.trailing_bytes  # the last read's, not a sum
        self.stats = VospiStats(**summed)

    def _command(
        self, command_id: int, data: tuple[int, ...] = (), *, timeout_s: float = 1.0
    ) -> None:
        if self._cci is None:
            raise InputError("this Lepton has no CCI bus: pass cci= to send commands")
        self._wait(timeout_s)
        for k, word in enumerate(data):
            self._cci.write_register(DATA0 + 2 * k, word)
        self._cci.write_register(DATA_LENGTH, len(data))
        self._cci.write_register(COMMAND, command_id)
        self._wait(timeout_s)

    def _wait(self, timeout_s: float) -> None:
        assert self._cci is not None
        end = time.monotonic() + timeout_s
        while self._cci.read_register(STATUS) & BUSY:
            if time.monotonic() > end:
                raise InputError(f"Lepton CCI stayed busy for {timeout_s} s")
            time.sleep(0.001)

    def run_ffc(self) -> None:
        """Flat-field correction now (the shutter closes for about a third of a second)."""
        self._command(SYS_RUN_FFC)

    def enable_tlinear(self) -> None:
        """Frames in centikelvin (radiometric TLinear) instead of Raw14 counts."""
        self._command(RAD_TLINEAR_SET, (1, 0))  # a 32-bit enum, little word first


class FakeLepton:
    """A Lepton for tests and ``--fake``: VoSPI of given frames, and the CCI registers.

    Parameters
    ----------
    frames : array_like of uint16, shape (F, 60, 80) or (F, 120, 160)
        Frames to stream, in a loop.
    lepton : {2, 3}, keyword-only
    damage_every : int, keyword-only
        Flip a byte in every k-th packet (0: none).
    busy_reads : int, keyword-only
        STATUS reads that report busy after each command.

    Attributes
    ----------
    commands : list of tuple
        ``(command_id, data words)`` of every command received.
    """

    def __init__(
        self,
        frames: NDArray[np.uint16],
        *,
        lepton: int = 2,
        damage_every: int = 0,
        busy_reads: int = 2,
    ) -> None:
        stream = bytearray(encode_vospi(frames, lepton=2 if lepton == 2 else 3, discards_between=3))
        if damage_every:
            for start in range(0, len(stream), PACKET_BYTES * damage_every):
                stream[start + 50] ^= 0xA5
        self._stream = bytes(stream)
        self._pos = 0
        self._registers: dict[int, int] = {}
        self._busy_left = 0
        self._busy_reads = busy_reads
        self.commands: list[tuple[int, tuple[int, ...]]] = []

    def readbytes(self, n: int) -> list[int]:
        """The next ``n`` bytes of the stream (looping)."""
        out = bytearray()
        while len(out) < n:
            take = min(n - len(out), len(self._stream) - self._pos)
            out += self._stream[self._pos : self._pos + take]
            self._pos = (self._pos + take) % len(self._stream)
        return list(out)

    def read_register(self, register: int) -> int:
        """CCI read: STATUS is busy for ``busy_reads`` reads after a command."""
        if register == STATUS:
            if self._busy_left:
                self._busy_left -= 1
                return BUSY | 0x0006  # busy, booted
            return 0x0006
        return self._registers.get(register, 0)

    def write_register(self, register: int, value: int) -> None:
        """CCI write; a write to COMMAND runs the command."""
        self._registers[register] = value
        if register == COMMAND:
            words = self._registers.get(DATA_LENGTH, 0)
            data = tuple(self._registers.get(DATA0 + 2 * k, 0) for k in range(words))
            self.commands.append((value, data))
            self._busy_left = self._busy_reads

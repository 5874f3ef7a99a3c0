"""Frames of the motor link (firmware/arduino/PROTOCOL.md: the one description).

``A5 5A | length | type | payload | CRC-16/CCITT-FALSE (little-endian)``; the CRC covers
length, type and payload. :class:`FrameDecoder` takes bytes as they arrive, in any
pieces, and returns the valid frames; corrupted ones are counted and dropped, and the
hunt for the next sync resumes one byte after a dropped frame's start.
"""

from __future__ import annotations

import binascii
from dataclasses import dataclass

from firefleet.errors import InputError

__all__ = ["MAX_PAYLOAD", "SYNC", "Frame", "FrameDecoder", "crc16", "encode_frame"]

SYNC = b"\xa5\x5a"
MAX_PAYLOAD = 32


def crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE (poly 0x1021, init 0xFFFF, no reflection, no final XOR).

    Examples
    --------
    >>> from firefleet.robot import crc16
    >>> hex(crc16(b"123456789"))  # the catalogue's check value
    '0x29b1'
    """
    return binascii.crc_hqx(data, 0xFFFF)


@dataclass(frozen=True)
class Frame:
    """One valid frame: its type and payload."""

    kind: int
    payload: bytes


def encode_frame(kind: int, payload: bytes) -> bytes:
    """The bytes of one frame.

    Examples
    --------
    >>> from firefleet.robot import encode_frame
    >>> encode_frame(0x03, b"").hex(" ")  # ESTOP
    'a5 5a 00 03 6c 2d'
    """
    if not 0 <= kind <= 0xFF:
        raise InputError(f"frame type {kind} must fit a byte")
    if len(payload) > MAX_PAYLOAD:
        raise InputError(f"payload of {len(payload)} bytes exceeds {MAX_PAYLOAD}")
    body = bytes((len(payload), kind)) + payload
    return SYNC + body + crc16(body).to_bytes(2, "little")


class FrameDecoder:
    """A streaming decoder: :meth:`feed` bytes, get the valid frames.

    Attributes
    ----------
    crc_errors : int
        Frames dropped for a wrong CRC.
    framing_errors : int
        Frames dropped for a length over ``MAX_PAYLOAD`` or not the type's
        (``expected_lengths``).
    skipped_bytes : int
        Bytes discarded while hunting for a sync (noise, and the rest of a dropped frame).

    Examples
    --------
    >>> from firefleet.robot import FrameDecoder, encode_frame
    >>> d = FrameDecoder()
    >>> good = encode_frame(0x01, b"\\x10\\x00\\x20\\x00")
    >>> bad = bytearray(good); bad[5] ^= 0xFF
    >>> frames = d.feed(b"noise" + bytes(bad) + good[:3]) + d.feed(good[3:])
    >>> [(f.kind, f.payload.hex()) for f in frames], d.crc_errors, d.skipped_bytes
    ([(1, '10002000')], 1, 14)
    """

    def __init__(self, expected_lengths: dict[int, int] | None = None) -> None:
        self._buffer = bytearray()
        self._expected = dict(expected_lengths or {})
        self.crc_errors = 0
        self.framing_errors = 0
        self.skipped_bytes = 0

    def feed(self, data: bytes) -> list[Frame]:
        """The frames completed by ``data`` (bytes in arrival order, any split)."""
        buf = self._buffer
        buf.extend(data)
        frames: list[Frame] = []
        while True:
            start = buf.find(SYNC)
            if start < 0:
                keep = 1 if buf[-1:] == SYNC[:1] else 0  # a sync may be split across reads
                self.skipped_bytes += len(buf) - keep
                del buf[: len(buf) - keep]
                return frames
            self.skipped_bytes += start
            del buf[:start]
            if len(buf) < 4:
                return frames
            length, kind = buf[2], buf[3]
            expected = self._expected.get(kind)
            if length > MAX_PAYLOAD or (expected is not None and length != expected):
                self.framing_errors += 1
                del buf[:1]
                continue
            if len(buf) < 6 + length:
                return frames
            body = bytes(buf[2 : 4 + length])
            crc = int.from_bytes(buf[4 + length : 6 + length], "little")
            if crc != crc16(body):
                self.crc_errors += 1
                del buf[:1]
                continue
            frames.append(Frame(kind=kind, payload=bytes(body[2:])))
            del buf[: 6 + length]

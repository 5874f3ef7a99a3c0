"""The messages of the motor link, version 1 (firmware/arduino/PROTOCOL.md).

Each message is a frozen dataclass with SI fields; :func:`pack` turns one into the bytes
of its frame (converting to the wire's integer units, refusing values that do not fit)
and :func:`unpack` a decoded :class:`~firefleet.robot.Frame` back (``None`` for a type
this side does not know, counted by the caller).
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass

from firefleet.errors import InputError
from firefleet.robot._frames import Frame, encode_frame

__all__ = [
    "LENGTHS",
    "EStop",
    "EStopClear",
    "Encoders",
    "Message",
    "Pwm",
    "Setpoint",
    "Status",
    "pack",
    "unpack",
]

SETPOINT, PWM, ESTOP, ESTOP_CLEAR, ENCODERS, STATUS = 0x01, 0x02, 0x03, 0x04, 0x81, 0x82

WATCHDOG_TRIPPED, ESTOP_ACTIVE, SUPPLY_LOW = 0x01, 0x02, 0x04
"""STATUS flag bits."""


@dataclass(frozen=True)
class Setpoint:
    """Wheel speed references [rad/s] (on the wire: int16 mrad/s, +-32.767 rad/s)."""

    right_rad_s: float
    left_rad_s: float


@dataclass(frozen=True)
class Pwm:
    """Open-loop duty of each motor, -1..1 of the supply (on the wire: int16 1/1000)."""

    right: float
    left: float


@dataclass(frozen=True)
class EStop:
    """Motors off until an :class:`EStopClear` and a new command."""


@dataclass(frozen=True)
class EStopClear:
    """Allow motion again after an :class:`EStop`."""


@dataclass(frozen=True)
class Encoders:
    """Encoder counts since power-up, at the Arduino's clock (``micros()``, wrapping)."""

    time_us: int
    right_counts: int
    left_counts: int


@dataclass(frozen=True)
class Status:
    """The Arduino's state: flag bits, supply voltage, receive errors (wrapping at 2^16)."""

    flags: int
    supply_v: float
    receive_errors: int

    @property
    def watchdog_tripped(self) -> bool:
        """No valid command for 200 ms: motors off."""
        return bool(self.flags & WATCHDOG_TRIPPED)

    @property
    def estop(self) -> bool:
        """An e-stop is active."""
        return bool(self.flags & ESTOP_ACTIVE)


Message = Setpoint | Pwm | EStop | EStopClear | Encoders | Status

LENGTHS = {SETPOINT: 4, PWM: 4, ESTOP: 0, ESTOP_CLEAR: 0, ENCODERS: 12, STATUS: 6}
"""Payload length of each type: a frame of a known type with another length is a
framing error."""


def _int16(value: float, scale: float, name: str) -> int:
    if not math.isfinite(value):
        raise InputError(f"{name} must be finite, got {value}")
    raw = round(value * scale)
    if not -32768 <= raw <= 32767:
        raise InputError(f"{name} {value} does not fit the wire's int16 at scale {scale}")
    return raw


def pack(message: Message) -> bytes:
    """The frame of a message.

    Examples
    --------
    >>> from firefleet.robot import Setpoint, pack
    >>> pack(Setpoint(1.5, -0.25)).hex(" ")  # 1500 and -250 mrad/s
    'a5 5a 04 01 dc 05 06 ff 77 1a'
    """
    if isinstance(message, Setpoint):
        payload = struct.pack(
            "<hh",
            _int16(message.right_rad_s, 1000.0, "setpoint right_rad_s"),
            _int16(message.left_rad_s, 1000.0, "setpoint left_rad_s"),
        )
        return encode_frame(SETPOINT, payload)
    if isinstance(message, Pwm):
        for name, v in (("right", message.right), ("left", message.left)):
            if not (math.isfinite(v) and -1.0 <= v <= 1.0):
                raise InputError(f"pwm {name} {v} must be within -1..1")
        payload = struct.pack("<hh", round(message.right * 1000), round(message.left * 1000))
        return encode_frame(PWM, payload)
    if isinstance(message, EStop):
        return encode_frame(ESTOP, b"")
    if isinstance(message, EStopClear):
        return encode_frame(ESTOP_CLEAR, b"")
    if isinstance(message, Encoders):
        payload = struct.pack(
            "<Iii", message.time_us & 0xFFFFFFFF, message.right_counts, message.left_counts
        )
        return encode_frame(ENCODERS, payload)
    supply_mv = round(message.supply_v * 1000.0)
    if not 0 <= supply_mv <= 0xFFFF:
        raise InputError(f"status supply_v {message.supply_v} out of 0..65.535 V")
    payload = struct.pack(
        "<BBHH", message.flags & 0xFF, 0, supply_mv, message.receive_errors & 0xFFFF
    )
    return encode_frame(STATUS, payload)


def unpack(frame: Frame) -> Message | None:
    """The message of a valid frame (``None`` for an unknown type).

    Examples
    --------
    >>> from firefleet.robot import Encoders, FrameDecoder, pack, unpack
    >>> (frame,) = FrameDecoder().feed(pack(Encoders(123, -5, 7)))
    >>> unpack(frame)
    Encoders(time_us=123, right_counts=-5, left_counts=7)
    """
    p = frame.payload
    if frame.kind in LENGTHS and len(p) != LENGTHS[frame.kind]:
        raise InputError(f"frame type {frame.kind:#04x} with {len(p)} payload bytes")
    if frame.kind == SETPOINT:
        r, left = struct.unpack("<hh", p)
        return Setpoint(r / 1000.0, left / 1000.0)
    if frame.kind == PWM:
        r, left = struct.unpack("<hh", p)
        return Pwm(r / 1000.0, left / 1000.0)
    if frame.kind == ESTOP:
        return EStop()
    if frame.kind == ESTOP_CLEAR:
        return EStopClear()
    if frame.kind == ENCODERS:
        t, r, left = struct.unpack("<Iii", p)
        return Encoders(t, r, left)
    if frame.kind == STATUS:
        flags, _, mv, errors = struct.unpack("<BBHH", p)
        return Status(flags, mv / 1000.0, errors)
    return None

"""On the robot: the serial link to the Arduino motor controller and its fake.

The bytes on the wire are described once, in ``firmware/arduino/PROTOCOL.md``.
"""

from firefleet.robot._frames import MAX_PAYLOAD, SYNC, Frame, FrameDecoder, crc16, encode_frame
from firefleet.robot._messages import (
    LENGTHS,
    EStop,
    EStopClear,
    Encoders,
    Message,
    Pwm,
    Setpoint,
    Status,
    pack,
    unpack,
)

__all__ = [
    "LENGTHS",
    "MAX_PAYLOAD",
    "SYNC",
    "EStop",
    "EStopClear",
    "Encoders",
    "Frame",
    "FrameDecoder",
    "Message",
    "Pwm",
    "Setpoint",
    "Status",
    "crc16",
    "encode_frame",
    "pack",
    "unpack",
]

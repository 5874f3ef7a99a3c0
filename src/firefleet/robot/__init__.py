"""On the robot: the serial link to the Arduino motor controller, and a fake board on a
pseudo-terminal that runs the sketch's logic on simulated motors.

The bytes on the wire are described once, in ``firmware/arduino/PROTOCOL.md``.
"""

from firefleet.robot._arduino import ArduinoLink
from firefleet.robot._fake_board import BoardLog, FakeBoard
from firefleet.robot._frames import MAX_PAYLOAD, SYNC, Frame, FrameDecoder, crc16, encode_frame
from firefleet.robot._lepton import FakeLepton, Lepton, LinuxI2c
from firefleet.robot._messages import (
    LENGTHS,
    Encoders,
    EStop,
    EStopClear,
    Message,
    Pwm,
    Setpoint,
    Status,
    pack,
    unpack,
)
from firefleet.robot._pt100 import (
    FakeMax31865,
    Pt100,
    Pt100Reading,
    cvd_resistance_ohm,
    cvd_temperature_c,
)

__all__ = [
    "LENGTHS",
    "MAX_PAYLOAD",
    "SYNC",
    "ArduinoLink",
    "BoardLog",
    "EStop",
    "EStopClear",
    "Encoders",
    "FakeBoard",
    "FakeLepton",
    "FakeMax31865",
    "Frame",
    "FrameDecoder",
    "Lepton",
    "LinuxI2c",
    "Message",
    "Pt100",
    "Pt100Reading",
    "Pwm",
    "Setpoint",
    "Status",
    "crc16",
    "cvd_resistance_ohm",
    "cvd_temperature_c",
    "encode_frame",
    "pack",
    "unpack",
]

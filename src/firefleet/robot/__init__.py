"""On the robot: the serial link to the Arduino motor controller, and a fake board on a
pseudo-terminal that runs the sketch's logic on simulated motors; the Lepton, the PT100,
the HC-SR04 ultrasonic range finder and the webcams, each with its fake.

The bytes on the wire are described once, in ``firmware/arduino/PROTOCOL.md``.
"""

from firefleet.robot._arduino import ArduinoLink
from firefleet.robot._config import (
    HardwareConfig,
    RobotConfig,
    parse_robot_config,
    read_robot_config,
)
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
from firefleet.robot._runtime import (
    Adapters,
    OnboardResult,
    load_role,
    open_adapters,
    run_onboard,
)
from firefleet.robot._ultrasonic import FakeHcSr04, HcSr04, RangeReading, speed_of_sound_m_s
from firefleet.robot._webcam import WebcamFrame, Webcams

__all__ = [
    "LENGTHS",
    "MAX_PAYLOAD",
    "SYNC",
    "Adapters",
    "ArduinoLink",
    "BoardLog",
    "EStop",
    "EStopClear",
    "Encoders",
    "FakeBoard",
    "FakeHcSr04",
    "FakeLepton",
    "FakeMax31865",
    "Frame",
    "FrameDecoder",
    "HardwareConfig",
    "HcSr04",
    "Lepton",
    "LinuxI2c",
    "Message",
    "OnboardResult",
    "Pt100",
    "Pt100Reading",
    "Pwm",
    "RangeReading",
    "RobotConfig",
    "Setpoint",
    "Status",
    "WebcamFrame",
    "Webcams",
    "crc16",
    "cvd_resistance_ohm",
    "cvd_temperature_c",
    "encode_frame",
    "load_role",
    "open_adapters",
    "pack",
    "parse_robot_config",
    "read_robot_config",
    "run_onboard",
    "speed_of_sound_m_s",
    "unpack",
]

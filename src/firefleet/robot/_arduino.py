"""The Pi's end of the motor link: an adapter over a serial port.

:class:`ArduinoLink` opens the port (``pyserial``, from the optional extra
``firefleet[robot]``, imported only here), sends commands and returns the messages that
arrived whole; damaged bytes are counted and dropped, never acted on
(firmware/arduino/PROTOCOL.md). Closing it commands both wheels to zero and sends an
e-stop, so a robot whose program ends stops.
"""

from __future__ import annotations

from typing import Any

from firefleet.errors import InputError
from firefleet.robot._frames import FrameDecoder
from firefleet.robot._messages import (
    LENGTHS,
    Encoders,
    EStop,
    Message,
    Setpoint,
    Status,
    pack,
    unpack,
)

__all__ = ["ArduinoLink"]


class ArduinoLink:
    """A serial link to the motor board.

    Parameters
    ----------
    port : str
        Serial device (``/dev/ttyACM0`` on a robot, a fake board's pty in tests).
    baud : int, keyword-only
        115,200 (PROTOCOL.md).

    Attributes
    ----------
    encoders : Encoders or None
        The latest encoder counts received.
    status : Status or None
        The latest status received.
    unknown_messages : int
        Valid frames of a type this side does not know (counted, ignored).
    """

    def __init__(self, port: str, *, baud: int = 115_200) -> None:
        try:
            import serial
        except ImportError as error:  # pragma: no cover - the extra is installed in tests
            raise InputError(
                "the motor link needs pyserial: pip install 'firefleet[robot]'"
            ) from error
        try:
            self._serial: Any = serial.Serial(port, baud, timeout=0, write_timeout=0.1)
        except (OSError, serial.SerialException) as error:
            raise InputError(f"cannot open serial port {port!r}: {error}") from error
        self._decoder = FrameDecoder(LENGTHS)
        self.encoders: Encoders | None = None
        self.status: Status | None = None
        self.unknown_messages = 0

    @property
    def crc_errors(self) -> int:
        """Frames dropped for a wrong CRC."""
        return self._decoder.crc_errors

    @property
    def framing_errors(self) -> int:
        """Frames dropped for a bad length."""
        return self._decoder.framing_errors

    def send(self, message: Message) -> None:
        """Send one command (SETPOINT, PWM, ESTOP, ESTOP_CLEAR)."""
        self._serial.write(pack(message))

    def poll(self) -> list[Message]:
        """The messages that arrived whole since the last call, in order."""
        waiting = self._serial.in_waiting
        data = self._serial.read(waiting) if waiting else b""
        out: list[Message] = []
        for frame in self._decoder.feed(data):
            message = unpack(frame)
            if message is None:
                self.unknown_messages += 1
                continue
            if isinstance(message, Encoders):
                self.encoders = message
            elif isinstance(message, Status):
                self.status = message
            out.append(message)
        return out

    def close(self) -> None:
        """Stop the wheels (zero setpoint, e-stop) and close the port."""
        try:
            self.send(Setpoint(0.0, 0.0))
            self.send(EStop())
            self._serial.flush()
        except Exception:
            pass
        self._serial.close()

    def __enter__(self) -> ArduinoLink:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

"""The team's message schema, version 1: what robots and the plant say, in bytes.

Every message is a fixed 20-byte header and a body whose size the message type fixes
(two types add a count of 8-byte items). All numbers are little-endian: unsigned
integers of the stated width, IEEE-754 float64 (``d``) for every physical quantity, so
a value crosses the wire unchanged and a networked run can equal the in-process one
bit for bit.

Header (20 B, ``struct`` format ``<2sBBQHIH``)::

    magic     2 B   b"FF"
    version   u8    SCHEMA_VERSION (1)
    type      u8    the message type (table below)
    run_id    u64   the run the message belongs to (random per run)
    robot     u16   the sender or the robot it is about, 0 .. 65534; PLANT (65535): the plant
    tick      u32   the tick k (time k dt) it belongs to
    length    u16   the body's size in bytes

Bodies (sizes in bytes, without the header):

=============  ====  =========================================================  ==========
type           code  fields [unit]                                               body
=============  ====  =========================================================  ==========
Hello          1     pid [u32], n_robots [u16], dt_s [s]                         14
Bye            2     reason [u8: 0 done, 1 failed, 2 stopped, 3 timed out]       1
Tick           3     t_s [s], last_tick [u32], stop [u8: 1 = the run ends]       13
Sensors        4     t_s [s], encoder counts (2) [counts], measured wheel        40
                     speeds (2) [rad/s]
State          5     t_s [s], pose (x, y [m], heading [rad]), wheel speeds (2)   61
                     [rad/s], segment [u32], fraction along it [1], arrived [u8]
Command        6     t_s [s], wheel-speed references (2) [rad/s], count [u8],    25 + 8 n
                     n values: the robot's row of what the kind records, then
                     of what it broadcasts (n <= 64; NaN allowed: "none")
TeamProgress   7     count n [u16], width m [u8], n x m broadcast values         3 + 8 n m
                     (robot-major; NaN: never heard), n ages [s] (+inf: never   + 9 n
                     heard), n alive flags [u8]
=============  ====  =========================================================  ==========

Why a struct layout rather than msgpack or CBOR: every message is a handful of numbers
whose count the type fixes, so a self-describing format would only add a type tag per
field (msgpack: 1 B per float64, plus the field names or positions of a map or
array) and make the size depend on the values; a fixed layout makes the size a
constant of the type (:func:`encoded_size`, what a link model needs to compute airtime),
checking it is one comparison, and ``struct`` is in the standard library and encodes a
state message in about a microsecond. The header's version byte is the way to change
the layout later.

Every received message is validated by :func:`decode`: magic, schema version, type,
declared and actual size (and at most :data:`MAX_MESSAGE_BYTES`), the run id and robot
range when the caller gives them, every float finite and within its range (times in
``[0, 1e7]`` s, positions within 1e6 m, wheel speeds within 1e4 rad/s, fractions in
``[0, 1]``; NaN only where a field says "none", +inf only for a never-heard age).
Anything else raises :class:`MessageError`, whose ``reason`` (one of :data:`REASONS`) a
receiver counts before dropping the message; :func:`decode` raises nothing else,
whatever the bytes.

Examples
--------
>>> from firefleet.net.messages import State, decode, encode, encoded_size
>>> msg = State(run_id=7, robot=1, tick=100, t_s=1.0, pose=(0.5, 2.0, 0.1),
...             wheel_speed_rad_s=(10.0, 9.5), segment=3, fraction=0.25, arrived=False)
>>> data = encode(msg)
>>> len(data), encoded_size(msg)
(81, 81)
>>> decode(data, run_id=7) == msg
True
>>> decode(data, run_id=8)
Traceback (most recent call last):
...
firefleet.net.messages.MessageError: foreign: run id 0000000000000008 expected, got 0000000000000007
"""

from __future__ import annotations

import abc
import math
import struct
from dataclasses import dataclass
from typing import ClassVar

__all__ = [
    "HEADER_BYTES",
    "MAX_MESSAGE_BYTES",
    "MAX_SERIES",
    "PLANT",
    "REASONS",
    "SCHEMA_VERSION",
    "Bye",
    "Command",
    "Hello",
    "Message",
    "MessageError",
    "Sensors",
    "State",
    "TeamProgress",
    "Tick",
    "decode",
    "encode",
    "encoded_size",
]

SCHEMA_VERSION = 1
"""The layout's version, the header's third byte."""

MAGIC = b"FF"
HEADER = struct.Struct("<2sBBQHIH")
HEADER_BYTES = HEADER.size
"""Size of the header [bytes] (20)."""

MAX_MESSAGE_BYTES = 16384
"""The largest message accepted [bytes]."""

MAX_SERIES = 64
"""Most values a :class:`Command` carries."""

PLANT = 0xFFFF
"""The ``robot`` field of what the plant (the simulated world) sends about the team."""

MAX_ROBOTS = 1024
"""Most robots a :class:`TeamProgress` lists."""

REASONS = (
    "short",
    "magic",
    "version",
    "type",
    "size",
    "oversized",
    "foreign",
    "robot",
    "nonfinite",
    "range",
)
"""Why a message is refused, as :attr:`MessageError.reason` says it."""

_T_MAX_S = 1e7
_POS_MAX_M = 1e6
_SPEED_MAX_RAD_S = 1e4
_COUNTS_MAX = 2.0**53
_VALUE_MAX = 1e12
_U32 = 2**32 - 1
_U64 = 2**64 - 1


class MessageError(ValueError):
    """A message that cannot be accepted: ``reason`` (one of :data:`REASONS`) and why.

    Examples
    --------
    >>> from firefleet.net.messages import MessageError, decode
    >>> try:
    ...     decode(b"hello")
    ... except MessageError as error:
    ...     print(error.reason)
    short
    """

    def __init__(self, reason: str, detail: str) -> None:
        super().__init__(f"{reason}: {detail}")
        self.reason = reason


def _finite(name: str, values: tuple[float, ...], bound: float) -> None:
    for v in values:
        if not math.isfinite(v):
            raise MessageError("nonfinite", f"{name} must be finite, got {v}")
        if abs(v) > bound:
            raise MessageError("range", f"{name} must be within +-{bound:g}, got {v}")


def _time(t_s: float) -> None:
    _finite("t_s", (t_s,), _T_MAX_S)
    if t_s < 0:
        raise MessageError("range", f"t_s must be >= 0, got {t_s}")


def _uint(name: str, value: int, top: int) -> None:
    if not 0 <= value <= top:
        raise MessageError("range", f"{name} must be in 0 .. {top}, got {value}")


@dataclass(frozen=True)
class _Base(abc.ABC):
    """The header's fields: the run, the robot (or :data:`PLANT`), the tick."""

    run_id: int
    robot: int
    tick: int

    CODE: ClassVar[int] = 0
    BODY: ClassVar[struct.Struct] = struct.Struct("<")

    def check(self) -> None:
        """Raise :class:`MessageError` unless every field is in range."""
        _uint("run_id", self.run_id, _U64)
        _uint("robot", self.robot, PLANT)
        _uint("tick", self.tick, _U32)

    @abc.abstractmethod
    def body(self) -> bytes:
        """The body's bytes (each message type lays out its own)."""

    def body_size(self) -> int:
        return self.BODY.size


@dataclass(frozen=True)
class Hello(_Base):
    """A process joins: its process id, the team's size and tick [s] as it knows them."""

    pid: int
    n_robots: int
    dt_s: float

    CODE: ClassVar[int] = 1
    BODY: ClassVar[struct.Struct] = struct.Struct("<IHd")

    def check(self) -> None:
        super().check()
        _uint("pid", self.pid, _U32)
        _uint("n_robots", self.n_robots, MAX_ROBOTS)
        _finite("dt_s", (self.dt_s,), _T_MAX_S)
        if self.dt_s <= 0:
            raise MessageError("range", f"dt_s must be > 0, got {self.dt_s}")

    def body(self) -> bytes:
        return self.BODY.pack(self.pid, self.n_robots, self.dt_s)


BYE_REASONS = ("done", "failed", "stopped", "timed out")
"""What :attr:`Bye.reason` codes mean, by index."""


@dataclass(frozen=True)
class Bye(_Base):
    """A process leaves: ``reason`` indexes :data:`BYE_REASONS`."""

    reason: int

    CODE: ClassVar[int] = 2
    BODY: ClassVar[struct.Struct] = struct.Struct("<B")

    def check(self) -> None:
        super().check()
        _uint("reason", self.reason, len(BYE_REASONS) - 1)

    def body(self) -> bytes:
        return self.BODY.pack(self.reason)


@dataclass(frozen=True)
class Tick(_Base):
    """The plant's clock: tick ``tick`` is at ``t_s`` [s]; the run's last tick; stop."""

    t_s: float
    last_tick: int
    stop: bool

    CODE: ClassVar[int] = 3
    BODY: ClassVar[struct.Struct] = struct.Struct("<dIB")

    def check(self) -> None:
        super().check()
        _time(self.t_s)
        _uint("last_tick", self.last_tick, _U32)

    def body(self) -> bytes:
        return self.BODY.pack(self.t_s, self.last_tick, int(self.stop))


@dataclass(frozen=True)
class Sensors(_Base):
    """What robot ``robot``'s sensors read at tick ``tick`` (time ``t_s`` [s]).

    ``counts``: the two wheel encoders' counts [counts]; ``measured_rad_s``: their
    measured wheel speeds [rad/s] (right, left: the drive stack's order)."""

    t_s: float
    counts: tuple[float, float]
    measured_rad_s: tuple[float, float]

    CODE: ClassVar[int] = 4
    BODY: ClassVar[struct.Struct] = struct.Struct("<5d")

    def check(self) -> None:
        super().check()
        _time(self.t_s)
        _finite("counts", self.counts, _COUNTS_MAX)
        _finite("measured_rad_s", self.measured_rad_s, _SPEED_MAX_RAD_S)

    def body(self) -> bytes:
        return self.BODY.pack(self.t_s, *self.counts, *self.measured_rad_s)


@dataclass(frozen=True)
class State(_Base):
    """Robot ``robot``'s state as it believes it: pose (x, y [m], heading [rad]), wheel
    speeds [rad/s], progress (``segment`` index and ``fraction`` along it, zeta =
    segment + fraction) and whether it has arrived."""

    t_s: float
    pose: tuple[float, float, float]
    wheel_speed_rad_s: tuple[float, float]
    segment: int
    fraction: float
    arrived: bool

    CODE: ClassVar[int] = 5
    BODY: ClassVar[struct.Struct] = struct.Struct("<6dIdB")

    def check(self) -> None:
        super().check()
        _time(self.t_s)
        _finite("pose", self.pose, _POS_MAX_M)
        _finite("wheel_speed_rad_s", self.wheel_speed_rad_s, _SPEED_MAX_RAD_S)
        _uint("segment", self.segment, _U32)
        _finite("fraction", (self.fraction,), 1.0)
        if self.fraction < 0:
            raise MessageError("range", f"fraction must be in [0, 1], got {self.fraction}")

    def body(self) -> bytes:
        return self.BODY.pack(
            self.t_s,
            *self.pose,
            *self.wheel_speed_rad_s,
            self.segment,
            self.fraction,
            int(self.arrived),
        )


@dataclass(frozen=True)
class Command(_Base):
    """Robot ``robot``'s decision at tick ``tick``: wheel-speed references [rad/s] (left,
    right) and ``series``, its row of the values the kind records then of what it
    broadcasts (at most :data:`MAX_SERIES`, each within 1e12 or NaN: "none", in the
    order of the kind's series and outbox)."""

    t_s: float
    reference_rad_s: tuple[float, float]
    series: tuple[float, ...] = ()

    CODE: ClassVar[int] = 6
    BODY: ClassVar[struct.Struct] = struct.Struct("<3dB")

    def check(self) -> None:
        super().check()
        _time(self.t_s)
        _finite("reference_rad_s", self.reference_rad_s, _SPEED_MAX_RAD_S)
        if len(self.series) > MAX_SERIES:
            raise MessageError(
                "size", f"at most {MAX_SERIES} series values, got {len(self.series)}"
            )
        _finite("series", tuple(v for v in self.series if not math.isnan(v)), _VALUE_MAX)

    def body(self) -> bytes:
        n = len(self.series)
        return self.BODY.pack(self.t_s, *self.reference_rad_s, n) + struct.pack(
            f"<{n}d", *self.series
        )

    def body_size(self) -> int:
        return self.BODY.size + 8 * len(self.series)


@dataclass(frozen=True)
class TeamProgress(_Base):
    """What the team broadcast at tick ``tick``, as the plant relays it to everyone.

    For each of n robots: ``width`` values (``values``, robot-major, n x width: its row
    of the kind's broadcast, for path following its progress zeta [segments] and rate
    [segments/s]; NaN where never heard), their age at the next tick (``age_s`` [s]:
    one tick when fresh, more when held, +inf when never heard) and whether its process
    is alive."""

    width: int
    values: tuple[float, ...]
    age_s: tuple[float, ...]
    alive: tuple[bool, ...]

    CODE: ClassVar[int] = 7
    BODY: ClassVar[struct.Struct] = struct.Struct("<HB")

    def check(self) -> None:
        super().check()
        n = len(self.alive)
        if (
            n > MAX_ROBOTS
            or not 0 <= self.width <= 255
            or len(self.values) != n * self.width
            or len(self.age_s) != n
        ):
            raise MessageError(
                "size",
                f"n = len(alive) <= {MAX_ROBOTS} robots, width in 0 .. 255, n x width values "
                f"and n ages expected; got n = {n}, width {self.width}, "
                f"{len(self.values)} values, {len(self.age_s)} ages",
            )
        _finite("values", tuple(v for v in self.values if not math.isnan(v)), _VALUE_MAX)
        for age in self.age_s:
            if not (age >= 0 and (age <= _T_MAX_S or age == math.inf)):
                raise MessageError("range", f"age_s must be in [0, 1e7] or +inf, got {age}")

    def body(self) -> bytes:
        n = len(self.alive)
        return (
            self.BODY.pack(n, self.width)
            + struct.pack(f"<{len(self.values)}d", *self.values)
            + struct.pack(f"<{n}d", *self.age_s)
            + bytes(int(a) for a in self.alive)
        )

    def body_size(self) -> int:
        return self.BODY.size + 8 * len(self.values) + 9 * len(self.alive)


Message = Hello | Bye | Tick | Sensors | State | Command | TeamProgress
"""Any message of the schema."""

_TYPES: dict[int, type[_Base]] = {
    cls.CODE: cls for cls in (Hello, Bye, Tick, Sensors, State, Command, TeamProgress)
}


def encoded_size(message: Message) -> int:
    """Size of ``message`` on the wire [bytes], header included (as ``len(encode(m))``).

    Examples
    --------
    >>> from firefleet.net.messages import Command, encoded_size
    >>> encoded_size(Command(run_id=1, robot=0, tick=0, t_s=0.0, reference_rad_s=(1.0, 1.0)))
    45
    """
    return HEADER_BYTES + message.body_size()


def encode(message: Message) -> bytes:
    """The bytes of ``message``; raises :class:`MessageError` if a field is out of range.

    Examples
    --------
    >>> from firefleet.net.messages import Bye, encode
    >>> data = encode(Bye(run_id=1, robot=2, tick=3, reason=0))
    >>> data[:2], data[2], len(data), data.hex()[-10:]
    (b'FF', 1, 21, '0000010000')
    """
    message.check()
    body = message.body()
    head = HEADER.pack(
        MAGIC, SCHEMA_VERSION, message.CODE, message.run_id, message.robot, message.tick, len(body)
    )
    return head + body


def _floats(data: bytes, offset: int, n: int) -> tuple[float, ...]:
    return struct.unpack_from(f"<{n}d", data, offset)


def _flag(name: str, value: int) -> None:
    if value > 1:
        raise MessageError("range", f"{name} must be 0 or 1, got {value}")


def _body(code: int, data: bytes, run_id: int, robot: int, tick: int) -> Message:
    """The message of type ``code`` from its body (size checked by the caller)."""
    head = (run_id, robot, tick)
    if code == Hello.CODE:
        pid, n, dt = Hello.BODY.unpack(data)
        return Hello(*head, pid=pid, n_robots=n, dt_s=dt)
    if code == Bye.CODE:
        return Bye(*head, reason=Bye.BODY.unpack(data)[0])
    if code == Tick.CODE:
        t, last, stop = Tick.BODY.unpack(data)
        _flag("stop", stop)
        return Tick(*head, t_s=t, last_tick=last, stop=bool(stop))
    if code == Sensors.CODE:
        t, c0, c1, w0, w1 = Sensors.BODY.unpack(data)
        return Sensors(*head, t_s=t, counts=(c0, c1), measured_rad_s=(w0, w1))
    if code == State.CODE:
        t, x, y, th, w0, w1, seg, frac, arr = State.BODY.unpack(data)
        _flag("arrived", arr)
        return State(
            *head,
            t_s=t,
            pose=(x, y, th),
            wheel_speed_rad_s=(w0, w1),
            segment=seg,
            fraction=frac,
            arrived=bool(arr),
        )
    if code == Command.CODE:
        t, r0, r1, _ = Command.BODY.unpack_from(data)
        n = (len(data) - Command.BODY.size) // 8
        return Command(
            *head, t_s=t, reference_rad_s=(r0, r1), series=_floats(data, Command.BODY.size, n)
        )
    n, width = TeamProgress.BODY.unpack_from(data)
    at = TeamProgress.BODY.size
    values = _floats(data, at, n * width)
    ages = _floats(data, at + 8 * n * width, n)
    flags = data[at + 8 * n * width + 8 * n :]
    if any(b > 1 for b in flags):
        raise MessageError("range", "alive flags must be 0 or 1")
    return TeamProgress(
        *head, width=width, values=values, age_s=ages, alive=tuple(bool(b) for b in flags)
    )


def _expected_body(code: int, data: bytes) -> int:
    """The body size the type (and its count field, if any) declares; -1 if unreadable."""
    cls = _TYPES[code]
    if code == Command.CODE:
        if len(data) < Command.BODY.size:
            return -1
        return Command.BODY.size + 8 * int(data[Command.BODY.size - 1])
    if code == TeamProgress.CODE:
        if len(data) < TeamProgress.BODY.size:
            return -1
        n, width = TeamProgress.BODY.unpack_from(data)
        return int(TeamProgress.BODY.size + 8 * n * width + 9 * n)
    return cls.BODY.size


def decode(
    data: bytes | bytearray | memoryview,
    *,
    run_id: int | None = None,
    n_robots: int | None = None,
) -> Message:
    """The message in ``data``, validated; raises :class:`MessageError` and nothing else.

    Parameters
    ----------
    data : bytes-like
        One message as received.
    run_id : int, optional
        The run it must belong to (else ``reason`` ``"foreign"``).
    n_robots : int, optional
        The team's size: the ``robot`` field must be below it or :data:`PLANT` (else
        ``reason`` ``"robot"``).

    Returns
    -------
    Message

    Examples
    --------
    >>> from firefleet.net.messages import Tick, decode, encode
    >>> data = encode(Tick(run_id=5, robot=0xFFFF, tick=2, t_s=0.02, last_tick=10, stop=False))
    >>> decode(data, run_id=5, n_robots=3).t_s
    0.02
    >>> decode(data[:-1])
    Traceback (most recent call last):
    ...
    firefleet.net.messages.MessageError: size: body of 12 bytes, the header says 13
    """
    raw = bytes(data)
    if len(raw) > MAX_MESSAGE_BYTES:
        raise MessageError("oversized", f"{len(raw)} bytes, at most {MAX_MESSAGE_BYTES}")
    if len(raw) < HEADER_BYTES:
        raise MessageError("short", f"{len(raw)} bytes, a header is {HEADER_BYTES}")
    magic, version, code, rid, robot, tick, length = HEADER.unpack_from(raw)
    if magic != MAGIC:
        raise MessageError("magic", f"expected {MAGIC!r}, got {magic!r}")
    if version != SCHEMA_VERSION:
        raise MessageError("version", f"schema {SCHEMA_VERSION} expected, got {version}")
    if code not in _TYPES:
        raise MessageError("type", f"unknown message type {code}")
    body = raw[HEADER_BYTES:]
    if len(body) != length:
        raise MessageError("size", f"body of {len(body)} bytes, the header says {length}")
    expected = _expected_body(code, body)
    if expected != length:
        raise MessageError(
            "size", f"{_TYPES[code].__name__} body of {length} bytes, expected {expected}"
        )
    if run_id is not None and rid != run_id:
        raise MessageError("foreign", f"run id {run_id:016x} expected, got {rid:016x}")
    if n_robots is not None and robot != PLANT and robot >= n_robots:
        raise MessageError("robot", f"robot {robot} of a team of {n_robots}")
    message = _body(code, body, rid, robot, tick)
    message.check()
    return message

"""The team's transport: eclipse zenoh in peer mode on the loopback interface.

Every process (the plant and each robot) opens a zenoh session in ``peer`` mode with
multicast scouting off: the plant listens on an explicit TCP endpoint on 127.0.0.1 and
every robot connects to it (and listens on a port of its own that gossip tells the
others about), so no router is needed and nothing leaves the machine. The link lease
is 0.8 s (keep-alive every 200 ms): a process that dies, or hangs, loses its links, and
with them its liveliness token, within 0.8 s at most; a process killed outright
closes its sockets at once, and the others see its token go in milliseconds.

Key expressions, under ``firefleet/<run-id>/`` (the run id as 16 hex digits)::

    hello                  Hello      robots -> plant, until the plant's first tick
    robot/<i>/sensors      Sensors    plant -> robot i, each tick
    robot/<i>/command      Command    robot i -> plant, each tick
    robot/<i>/state        State      robot i -> everyone, each tick
    team/progress          TeamProgress  plant -> everyone, each tick
    clock                  Tick       plant -> everyone (the stop)
    robot/<i>/bye          Bye        robot i -> plant, when it leaves
    team/robot/<i>         TeamProgress  robot i -> its teammates, each period (the
                                      on-board team link: its own row only)
    alive/robot/<i>        liveliness token of robot i's process
    alive/plant            liveliness token of the plant's process

Examples
--------
>>> from firefleet.net.transport import Keys
>>> keys = Keys(run_id=0xABC)
>>> keys.command(2), keys.alive_robots
('firefleet/0000000000000abc/robot/2/command', 'firefleet/0000000000000abc/alive/robot/*')
"""

from __future__ import annotations

import itertools
import json
import socket
from collections import Counter
from dataclasses import dataclass, field
from typing import Any

from firefleet.errors import InputError
from firefleet.net.messages import Message, MessageError, decode, encode

__all__ = ["LEASE_MS", "Counters", "Keys", "free_port", "open_session", "peer_config"]

LEASE_MS = 800
"""Link lease [ms]: a peer silent this long is dropped (its liveliness tokens go)."""


@dataclass(frozen=True)
class Keys:
    """The key expressions of one run (see the module notes)."""

    run_id: int

    @property
    def root(self) -> str:
        """``firefleet/<run-id>``."""
        return f"firefleet/{self.run_id:016x}"

    @property
    def hello(self) -> str:
        return f"{self.root}/hello"

    @property
    def clock(self) -> str:
        return f"{self.root}/clock"

    @property
    def progress(self) -> str:
        return f"{self.root}/team/progress"

    def sensors(self, robot: int) -> str:
        return f"{self.root}/robot/{robot}/sensors"

    def command(self, robot: int | str) -> str:
        return f"{self.root}/robot/{robot}/command"

    def state(self, robot: int | str) -> str:
        return f"{self.root}/robot/{robot}/state"

    def bye(self, robot: int | str) -> str:
        return f"{self.root}/robot/{robot}/bye"

    def team(self, robot: int | str) -> str:
        """``team/robot/<i>``: robot i's own progress, to its teammates (on board)."""
        return f"{self.root}/team/robot/{robot}"

    def alive(self, robot: int) -> str:
        return f"{self.root}/alive/robot/{robot}"

    @property
    def alive_robots(self) -> str:
        return f"{self.root}/alive/robot/*"

    @property
    def alive_plant(self) -> str:
        return f"{self.root}/alive/plant"


def robot_of_key(key: str) -> int | None:
    """The robot index in a key expression ``.../robot/<i>/...`` (None if there is none).

    Examples
    --------
    >>> from firefleet.net.transport import robot_of_key
    >>> robot_of_key("firefleet/00/alive/robot/12"), robot_of_key("firefleet/00/hello")
    (12, None)
    """
    parts = key.split("/")
    for a, b in itertools.pairwise(parts):
        if a == "robot" and b.isdigit():
            return int(b)
    return None


def free_port() -> int:
    """A TCP port on 127.0.0.1 that is free now (the OS's choice).

    Examples
    --------
    >>> from firefleet.net.transport import free_port
    >>> 1024 <= free_port() <= 65535
    True
    """
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        port: int = sock.getsockname()[1]
    return port


def peer_config(*, listen: list[str], connect: list[str]) -> dict[str, Any]:
    """The zenoh configuration of a team process, as a JSON-able dict.

    Parameters
    ----------
    listen, connect : list of str
        Zenoh endpoints (``tcp/127.0.0.1:PORT``) to listen on and to connect to.

    Examples
    --------
    >>> from firefleet.net.transport import peer_config
    >>> cfg = peer_config(listen=["tcp/127.0.0.1:7000"], connect=[])
    >>> cfg["mode"], cfg["scouting"]["multicast"]["enabled"]
    ('peer', False)
    """
    for endpoint in (*listen, *connect):
        if not endpoint.startswith("tcp/127.0.0.1:"):
            raise InputError(f"endpoint: expected tcp/127.0.0.1:PORT (loopback), got {endpoint!r}")
    return {
        "mode": "peer",
        "listen": {"endpoints": listen},
        "connect": {"endpoints": connect},
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": True}},
        "transport": {"link": {"tx": {"lease": LEASE_MS, "keep_alive": 4}}},
    }


def open_session(*, listen: list[str], connect: list[str]) -> Any:
    """Open a zenoh session with :func:`peer_config` (zenoh imported here only)."""
    import zenoh

    config = zenoh.Config.from_json5(json.dumps(peer_config(listen=listen, connect=connect)))
    return zenoh.open(config)


@dataclass
class Counters:
    """A process's network counters: messages and bytes by direction and type, drops by
    reason.

    Examples
    --------
    >>> from firefleet.net.messages import Bye, encode
    >>> from firefleet.net.transport import Counters
    >>> c = Counters()
    >>> c.receive(encode(Bye(run_id=1, robot=0, tick=0, reason=0)), run_id=1, n_robots=3)
    Bye(run_id=1, robot=0, tick=0, reason=0)
    >>> c.receive(b"junk", run_id=1, n_robots=3) is None, dict(c.dropped)
    (True, {'short': 1})
    """

    sent: Counter[str] = field(default_factory=Counter)
    received: Counter[str] = field(default_factory=Counter)
    dropped: Counter[str] = field(default_factory=Counter)
    bytes_sent: int = 0
    bytes_received: int = 0

    def send(self, message: Message) -> bytes:
        """Encode ``message`` and count it."""
        data = encode(message)
        self.sent[type(message).__name__] += 1
        self.bytes_sent += len(data)
        return data

    def receive(self, data: bytes, *, run_id: int, n_robots: int) -> Message | None:
        """Decode and count ``data``; None (and a drop counted by reason) if refused."""
        self.bytes_received += len(data)
        try:
            message = decode(data, run_id=run_id, n_robots=n_robots)
        except MessageError as error:
            self.dropped[error.reason] += 1
            return None
        self.received[type(message).__name__] += 1
        return message

    def document(self) -> dict[str, Any]:
        """The counters as a JSON-able dict."""
        return {
            "sent": dict(sorted(self.sent.items())),
            "received": dict(sorted(self.received.items())),
            "dropped": dict(sorted(self.dropped.items())),
            "bytes_sent": self.bytes_sent,
            "bytes_received": self.bytes_received,
        }

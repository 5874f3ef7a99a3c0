"""Robots as separate processes that talk over a network (issue 16, point 3).

:mod:`firefleet.net.messages` is the message schema (versioned, fixed struct layout,
sizes and units in its table) with :func:`encode`, :func:`decode` (which raises
:class:`MessageError` and nothing else) and :func:`encoded_size`. The transport (eclipse
zenoh in peer mode on loopback) and the team run build on it.

Examples
--------
>>> from firefleet.net import Bye, decode, encode
>>> decode(encode(Bye(run_id=1, robot=0, tick=5, reason=1))).reason
1
"""

from firefleet.net.messages import (
    HEADER_BYTES,
    MAX_MESSAGE_BYTES,
    PLANT,
    REASONS,
    SCHEMA_VERSION,
    Bye,
    Command,
    Hello,
    Message,
    MessageError,
    Sensors,
    State,
    TeamProgress,
    Tick,
    decode,
    encode,
    encoded_size,
)

__all__ = [
    "HEADER_BYTES",
    "MAX_MESSAGE_BYTES",
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

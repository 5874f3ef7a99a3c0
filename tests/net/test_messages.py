"""The message schema: round trips, sizes, and that no bytes crash the decoder."""

from __future__ import annotations

import math
import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.net.messages import (
    HEADER_BYTES,
    MAX_MESSAGE_BYTES,
    MAX_SERIES,
    PLANT,
    REASONS,
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

u64 = st.integers(0, 2**64 - 1)
robot = st.integers(0, PLANT)
tick = st.integers(0, 2**32 - 1)
time_s = st.floats(0.0, 1e7)
speed = st.floats(-1e4, 1e4)
pos = st.floats(-1e6, 1e6)
value = st.floats(-1e12, 1e12)

messages: st.SearchStrategy[Message] = st.one_of(
    st.builds(
        Hello,
        u64,
        robot,
        tick,
        st.integers(0, 2**32 - 1),
        st.integers(0, 1024),
        st.floats(1e-6, 1e3),
    ),
    st.builds(Bye, u64, robot, tick, st.integers(0, 3)),
    st.builds(Tick, u64, robot, tick, time_s, tick, st.booleans()),
    st.builds(
        Sensors,
        u64,
        robot,
        tick,
        time_s,
        st.tuples(st.floats(-(2.0**53), 2.0**53), value),
        st.tuples(speed, speed),
    ),
    st.builds(
        State,
        u64,
        robot,
        tick,
        time_s,
        st.tuples(pos, pos, pos),
        st.tuples(speed, speed),
        tick,
        st.floats(0.0, 1.0),
        st.booleans(),
    ),
    st.builds(
        Command,
        u64,
        robot,
        tick,
        time_s,
        st.tuples(speed, speed),
        st.lists(value, max_size=MAX_SERIES).map(tuple),
    ),
    st.integers(0, 40).flatmap(
        lambda n: st.builds(
            TeamProgress,
            u64,
            robot,
            tick,
            st.lists(st.floats(0.0, 1e6), min_size=n, max_size=n).map(tuple),
            st.lists(st.booleans(), min_size=n, max_size=n).map(tuple),
        )
    ),
)


@given(messages)
@settings(max_examples=300, deadline=None)
def test_round_trip_and_size(message: Message) -> None:
    data = encode(message)
    assert len(data) == encoded_size(message)
    back = decode(data, run_id=message.run_id)
    assert back == message
    assert type(back) is type(message)


@given(st.binary(max_size=400))
@settings(max_examples=500, deadline=None)
def test_random_bytes_raise_only_message_error(data: bytes) -> None:
    reason = None
    try:
        decode(data, run_id=3, n_robots=5)
    except MessageError as error:
        reason = error.reason
    assert reason is None or reason in REASONS


@given(messages, st.data())
@settings(max_examples=300, deadline=None)
def test_corrupted_messages_raise_only_message_error(message: Message, data: st.DataObject) -> None:
    raw = bytearray(encode(message))
    i = data.draw(st.integers(0, len(raw) - 1))
    raw[i] = data.draw(st.integers(0, 255))
    cut = data.draw(st.integers(0, len(raw)))
    for candidate in (bytes(raw), bytes(raw[:cut]), bytes(raw) + b"\x00"):
        try:
            decoded = decode(candidate)
        except MessageError as error:
            reason = error.reason
        else:  # what decodes re-encodes to the same bytes: nothing unvalidated slips in
            reason = "accepted"
            assert encode(decoded) == candidate
        assert reason in (*REASONS, "accepted")


def test_sizes_are_the_documented_ones() -> None:
    """The table of the module docstring, against struct's own arithmetic."""
    head = (1, 0, 0)
    assert HEADER_BYTES == struct.calcsize("<2sBBQHIH") == 20
    assert encoded_size(Hello(*head, pid=1, n_robots=3, dt_s=0.01)) == 20 + 14
    assert encoded_size(Bye(*head, reason=0)) == 20 + 1
    assert encoded_size(Tick(*head, t_s=0.0, last_tick=1, stop=False)) == 20 + 13
    assert encoded_size(Sensors(*head, t_s=0.0, counts=(0, 0), measured_rad_s=(0, 0))) == 60
    state = State(
        *head, t_s=0, pose=(0, 0, 0), wheel_speed_rad_s=(0, 0), segment=0, fraction=0, arrived=False
    )
    assert encoded_size(state) == 20 + 61
    assert encoded_size(Command(*head, t_s=0, reference_rad_s=(0, 0), series=(1.0,) * 13)) == (
        20 + 25 + 8 * 13
    )
    assert encoded_size(TeamProgress(*head, progress=(0.0,) * 20, alive=(True,) * 20)) == (
        20 + 2 + 9 * 20
    )


def _state(**change: object) -> State:
    fields: dict[str, object] = dict(
        run_id=9,
        robot=1,
        tick=4,
        t_s=0.04,
        pose=(1.0, 2.0, 0.3),
        wheel_speed_rad_s=(5.0, 5.0),
        segment=2,
        fraction=0.5,
        arrived=False,
    )
    fields.update(change)
    return State(**fields)  # type: ignore[arg-type]


def _raw_state(**change: object) -> bytes:
    """A state message's bytes packed by hand, skipping the encoder's checks."""
    s = _state(**change)
    body = struct.pack(
        "<6dIdB", s.t_s, *s.pose, *s.wheel_speed_rad_s, s.segment, s.fraction, int(s.arrived)
    )
    return struct.pack("<2sBBQHIH", b"FF", 1, 5, s.run_id, s.robot, s.tick, len(body)) + body


@pytest.mark.parametrize(
    ("data", "reason"),
    [
        (b"", "short"),
        (b"XX" + _raw_state()[2:], "magic"),
        (_raw_state()[:2] + b"\x02" + _raw_state()[3:], "version"),
        (_raw_state()[:3] + b"\x09" + _raw_state()[4:], "type"),
        (_raw_state()[:-1], "size"),
        (b"FF" + b"\x00" * (MAX_MESSAGE_BYTES + 1), "oversized"),
        (_raw_state(pose=(math.nan, 0.0, 0.0)), "nonfinite"),
        (_raw_state(wheel_speed_rad_s=(math.inf, 0.0)), "nonfinite"),
        (_raw_state(fraction=1.5), "range"),
        (_raw_state(t_s=-1.0), "range"),
        (_raw_state(pose=(2e6, 0.0, 0.0)), "range"),
        (_raw_state(run_id=10), "foreign"),
        (_raw_state(robot=7), "robot"),
    ],
)
def test_each_refusal_names_its_reason(data: bytes, reason: str) -> None:
    with pytest.raises(MessageError) as caught:
        decode(data, run_id=9, n_robots=3)
    assert caught.value.reason == reason


def test_encode_refuses_what_decode_would() -> None:
    with pytest.raises(MessageError, match="nonfinite"):
        encode(_state(pose=(math.nan, 0.0, 0.0)))
    with pytest.raises(MessageError, match="size"):
        encode(Command(1, 0, 0, t_s=0.0, reference_rad_s=(0, 0), series=(0.0,) * 65))
    with pytest.raises(MessageError, match="range"):
        encode(_state(robot=PLANT + 1))

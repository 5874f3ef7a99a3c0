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
    st.tuples(st.integers(0, 30), st.integers(0, 3)).flatmap(
        lambda nm: st.builds(
            TeamProgress,
            u64,
            robot,
            tick,
            st.just(nm[1]),
            st.lists(value, min_size=nm[0] * nm[1], max_size=nm[0] * nm[1]).map(tuple),
            st.lists(st.one_of(time_s, st.just(math.inf)), min_size=nm[0], max_size=nm[0]).map(
                tuple
            ),
            st.lists(st.booleans(), min_size=nm[0], max_size=nm[0]).map(tuple),
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
    team = TeamProgress(*head, width=2, values=(0.0,) * 40, age_s=(0.01,) * 20, alive=(True,) * 20)
    assert encoded_size(team) == 20 + 3 + 8 * 40 + 9 * 20


def test_none_and_never_heard_cross_as_nan_and_inf() -> None:
    """A series value may be NaN ("none") and a never-heard age +inf; nothing else
    non-finite passes."""
    cmd = Command(1, 0, 3, t_s=0.03, reference_rad_s=(1.0, 2.0), series=(math.nan, 4.0))
    back = decode(encode(cmd))
    assert isinstance(back, Command)
    assert math.isnan(back.series[0])
    assert back.series[1] == 4.0
    team = TeamProgress(
        1, PLANT, 3, width=1, values=(math.nan, 2.0), age_s=(math.inf, 0.01), alive=(False, True)
    )
    again = decode(encode(team))
    assert isinstance(again, TeamProgress)
    assert math.isnan(again.values[0])
    assert again.age_s == (math.inf, 0.01)
    with pytest.raises(MessageError, match="nonfinite"):
        encode(Command(1, 0, 3, t_s=0.0, reference_rad_s=(1.0, 2.0), series=(math.inf,)))
    with pytest.raises(MessageError, match="nonfinite"):
        encode(Command(1, 0, 3, t_s=0.0, reference_rad_s=(math.nan, 2.0)))
    with pytest.raises(MessageError, match="range"):
        encode(TeamProgress(1, PLANT, 3, width=0, values=(), age_s=(-1.0,), alive=(True,)))
    with pytest.raises(MessageError, match="size"):
        encode(TeamProgress(1, PLANT, 3, width=2, values=(1.0,), age_s=(0.0,), alive=(True,)))


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


def test_path_progress_tracks_the_whole_path_search() -> None:
    """The robot's tracked progress against the whole-path search of
    PolynomialPath.distance, along a real run of experiment 1 (robot 1's odometry)."""
    import numpy as np

    from firefleet import load_scenario, simulate
    from firefleet.net.robot import PathProgress
    from firefleet.scenarios.schema import PathFollowing

    scenario = load_scenario("coop-different-paths")
    cmd = scenario.command
    assert isinstance(cmd, PathFollowing)
    odometry = simulate(scenario, record_every=10).extra["odometry_pose"][:, 0, :2]
    path = cmd.paths[0]
    track = PathProgress(path, cmd.pieces)
    zeta = np.array([sum(track.update(x, y)) for x, y in odometry])
    _, s = path.distance(odometry)
    reference = s / path.length_m * cmd.pieces
    assert np.max(np.abs(zeta - reference)) < 0.05  # a twentieth of a piece (4.7 mm)
    assert zeta[-1] > cmd.pieces - 1


def test_transport_config_is_loopback_peer_without_multicast() -> None:
    from firefleet.errors import InputError
    from firefleet.net.transport import Keys, peer_config, robot_of_key

    cfg = peer_config(listen=["tcp/127.0.0.1:7447"], connect=["tcp/127.0.0.1:7448"])
    assert cfg["mode"] == "peer"
    assert cfg["scouting"]["multicast"]["enabled"] is False
    assert cfg["connect"]["endpoints"] == ["tcp/127.0.0.1:7448"]
    assert cfg["transport"]["link"]["tx"]["lease"] <= 1000  # a hung peer goes within 1 s
    with pytest.raises(InputError, match="loopback"):
        peer_config(listen=["tcp/0.0.0.0:7447"], connect=[])
    keys = Keys(run_id=2**64 - 1)
    assert keys.state(3) == "firefleet/ffffffffffffffff/robot/3/state"
    assert robot_of_key(keys.alive(41)) == 41
    assert robot_of_key(keys.progress) is None

"""The motor link's frames: Python and the sketch's C agree byte for byte, and both
decoders survive any damage (firmware/arduino/PROTOCOL.md)."""

from __future__ import annotations

import ctypes

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.errors import InputError
from firefleet.robot import (
    LENGTHS,
    Encoders,
    EStop,
    FrameDecoder,
    Pwm,
    Setpoint,
    Status,
    crc16,
    encode_frame,
    pack,
    unpack,
)
from tests.robot._firmware import buffer, c_decode, c_encode

KNOWN = sorted(LENGTHS)


def test_crc_is_the_catalogues_ccitt_false(firmware: ctypes.CDLL) -> None:
    # CRC-16/CCITT-FALSE's check value in the CRC catalogue (Greg Cook's reveng)
    assert crc16(b"123456789") == 0x29B1
    assert firmware.ff_crc16(buffer(b"123456789"), 9) == 0x29B1


@settings(max_examples=200, deadline=None)
@given(kind=st.integers(0, 255), payload=st.binary(max_size=32))
def test_python_and_c_encode_the_same_bytes(
    firmware: ctypes.CDLL, kind: int, payload: bytes
) -> None:
    assert c_encode(firmware, kind, payload) == encode_frame(kind, payload)


@st.composite
def damaged_streams(draw: st.DrawFn) -> bytes:
    """Valid frames of known types, noise, flipped bytes and truncations, in any order."""
    parts = []
    for _ in range(draw(st.integers(1, 8))):
        kind = draw(st.sampled_from(KNOWN))
        frame = bytearray(
            encode_frame(kind, draw(st.binary(min_size=LENGTHS[kind], max_size=LENGTHS[kind])))
        )
        action = draw(st.sampled_from(["keep", "keep", "flip", "cut", "noise"]))
        if action == "flip":
            i = draw(st.integers(0, len(frame) - 1))
            frame[i] ^= draw(st.integers(1, 255))
        elif action == "cut":
            frame = frame[: draw(st.integers(0, len(frame) - 1))]
        elif action == "noise":
            frame = bytearray(draw(st.binary(max_size=12))) + frame
        parts.append(bytes(frame))
    return b"".join(parts)


@settings(max_examples=300, deadline=None)
@given(stream=damaged_streams(), split=st.integers(0, 200))
def test_python_and_c_decoders_find_the_same_frames(
    firmware: ctypes.CDLL, stream: bytes, split: int
) -> None:
    py = FrameDecoder(LENGTHS)
    frames = py.feed(stream[:split]) + py.feed(stream[split:])
    c_frames, c_crc, c_framing = c_decode(firmware, stream)
    assert [(f.kind, f.payload) for f in frames] == c_frames
    assert (py.crc_errors, py.framing_errors) == (c_crc, c_framing)
    for f in frames:  # whatever survives is a well-formed message
        assert unpack(f) is not None


def test_a_frame_hidden_behind_a_corrupted_one_is_found(firmware: ctypes.CDLL) -> None:
    good = pack(Setpoint(1.0, 2.0))
    # a corrupted frame whose length byte swallows the good frame that follows
    bogus = bytes([0xA5, 0x5A, 4, 0x01]) + good
    py = FrameDecoder(LENGTHS)
    assert [unpack(f) for f in py.feed(bogus)] == [Setpoint(1.0, 2.0)]
    assert py.crc_errors == 1
    assert c_decode(firmware, bogus)[0] == [(0x01, good[4:8])]


@pytest.mark.parametrize(
    "message",
    [
        Setpoint(16.5, -16.5),
        Pwm(0.5, -1.0),
        EStop(),
        Encoders(2**32 - 1, -(2**31), 2**31 - 1),
        Status(0b101, 11.987, 65535),
    ],
)
def test_every_message_round_trips(message: object) -> None:
    (frame,) = FrameDecoder(LENGTHS).feed(pack(message))  # type: ignore[arg-type]
    assert unpack(frame) == message


def test_values_that_do_not_fit_the_wire_are_refused() -> None:
    with pytest.raises(InputError, match=r"setpoint right_rad_s 40\.0 does not fit"):
        pack(Setpoint(40.0, 0.0))
    with pytest.raises(InputError, match="finite"):
        pack(Setpoint(float("nan"), 0.0))
    with pytest.raises(InputError, match=r"pwm left 1\.5"):
        pack(Pwm(0.0, 1.5))
    with pytest.raises(InputError, match="exceeds 32"):
        encode_frame(0x01, bytes(33))


def test_bytes_per_second_fit_115200_baud_with_margin() -> None:
    down = 100 * len(pack(Setpoint(1.0, 1.0)))
    up = 100 * len(pack(Encoders(0, 0, 0))) + 10 * len(pack(Status(0, 12.0, 0)))
    assert (down, up) == (1000, 1920)  # PROTOCOL.md's numbers
    assert max(down, up) < 0.25 * 115_200 / 10  # 8N1: 10 bits a byte

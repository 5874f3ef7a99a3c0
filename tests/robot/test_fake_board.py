"""The fake board: the sketch's logic in Python equals the compiled C, and the link
works end to end through a pseudo-terminal (commands, watchdog, damaged bytes, e-stop)."""

from __future__ import annotations

import ctypes
import time

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.robot import (
    LENGTHS,
    ArduinoLink,
    Encoders,
    EStop,
    EStopClear,
    FakeBoard,
    FrameDecoder,
    Pwm,
    Setpoint,
    Status,
    pack,
    unpack,
)
from firefleet.robot._firmware_logic import FirmwareLogic
from tests.robot._firmware import Motor, PidGains, buffer

commands = st.one_of(
    st.builds(Setpoint, st.floats(-16, 16), st.floats(-16, 16)),
    st.builds(Pwm, st.floats(-1, 1), st.floats(-1, 1)),
    st.just(EStop()),
    st.just(EStopClear()),
    st.none(),  # a period without a command
)


@settings(max_examples=60, deadline=None)
@given(
    script=st.lists(st.tuples(commands, st.integers(-3, 40), st.integers(-3, 40)), max_size=60),
    gap_ticks=st.integers(0, 30),
)
def test_python_board_logic_equals_the_sketchs_c(
    firmware: ctypes.CDLL, script: list[tuple[object, int, int]], gap_ticks: int
) -> None:
    g = PidGains()
    firmware.ff_pid_defaults(ctypes.byref(g))
    c = Motor()
    firmware.ff_motor_init(ctypes.byref(c), ctypes.byref(g), 2048.0, 12.0, 0)
    py = FirmwareLogic(counts_per_rev=2048, supply_v=12.0, now_us=0)
    counts = np.zeros(2, dtype=np.int64)
    for k, (command, dr, dl) in enumerate(script + [(None, 1, 1)] * gap_ticks):
        now = k * 10_000
        if command is not None:
            frame = pack(command)  # type: ignore[arg-type]
            payload = frame[4:-2]
            firmware.ff_motor_command(ctypes.byref(c), frame[3], buffer(payload), len(payload), now)
            (decoded,) = FrameDecoder(LENGTHS).feed(frame)  # what the board gets: wire units
            py.command(unpack(decoded), now_us=now)  # type: ignore[arg-type]
        counts += (dr, dl)
        volts = (ctypes.c_float * 2)()
        firmware.ff_motor_tick(ctypes.byref(c), now, (ctypes.c_int32 * 2)(*counts.tolist()), volts)
        v_py = py.tick(now, (int(counts[0]), int(counts[1])))
        np.testing.assert_allclose(volts[:], v_py, rtol=2e-5, atol=1e-4)
        assert c.flags == py.flags


def _drive(link: ArduinoLink, message: object, seconds: float) -> list[object]:
    got: list[object] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        link.send(message)  # type: ignore[arg-type]
        got += link.poll()
        time.sleep(0.01)
    return got


def _wait_for(link: ArduinoLink, done: object, seconds: float = 3.0) -> list[object]:
    got: list[object] = []
    end = time.monotonic() + seconds
    while time.monotonic() < end and not done(got):  # type: ignore[operator]
        got += link.poll()
        time.sleep(0.01)
    return got


def test_speed_commands_turn_the_simulated_wheels() -> None:
    with FakeBoard() as board, ArduinoLink(board.port) as link:
        got = _drive(link, Setpoint(8.0, -4.0), 1.5)
        final = np.array(board.log.wheel_speed_rad_s[-1])
    np.testing.assert_allclose(final, [8.0, -4.0], atol=0.4)
    encoders = [m for m in got if isinstance(m, Encoders)]
    assert len(encoders) > 50
    assert encoders[-1].right_counts > 0 > encoders[-1].left_counts
    assert (link.crc_errors, link.framing_errors, board.receive_errors) == (0, 0, 0)


def test_the_watchdog_stops_the_board_when_commands_stop() -> None:
    with FakeBoard() as board, ArduinoLink(board.port) as link:
        _drive(link, Setpoint(8.0, 8.0), 0.5)
        got = _wait_for(
            link, lambda g: any(isinstance(m, Status) and m.watchdog_tripped for m in g)
        )
        trips = list(board.log.watchdog_trips_us)
        last = board.log.last_command_us
    assert any(isinstance(m, Status) and m.watchdog_tripped for m in got)
    # in the board's own clock: the first period more than 200 ms after the last command
    assert trips[-1] - last == 210_000


def test_damaged_bytes_are_counted_and_never_acted_on() -> None:
    with FakeBoard(corrupt_every=7) as board, ArduinoLink(board.port) as link:
        link._serial.write(b"\xa5\x5a\x04\x01garbage" + b"\x00" * 20)  # a frame with a bad CRC
        bad = bytearray(pack(Setpoint(16.0, 16.0)))
        bad[5] ^= 0xFF
        link._serial.write(bytes(bad))
        got = _drive(link, Pwm(0.25, 0.25), 1.0)
        time.sleep(0.15)
        got += link.poll()
        errors_seen = link.status.receive_errors if link.status else -1
        applied = board.log.commands
        final = board.log.wheel_speed_rad_s[-1]
    assert link.crc_errors > 0  # every 7th frame from the board was damaged
    assert errors_seen >= 2  # the board counted the Pi's damaged frames, and said so
    assert all(isinstance(m, Encoders | Status) for m in got)
    # the damaged 16 rad/s setpoint never moved the wheels: they run open loop at 3 V
    assert abs(final[0] - 3.0 * 1.3955) < 0.3
    assert applied > 50


def test_closing_the_link_stops_the_wheels_with_an_estop() -> None:
    with FakeBoard() as board:
        with ArduinoLink(board.port) as link:
            _drive(link, Pwm(0.5, 0.5), 0.3)
        time.sleep(0.1)
        assert board._logic.estop
        assert board._logic.tick(0, (0, 0)) == (0.0, 0.0)

"""The sketch's controller logic (ff_motor.c) against the simulator's: the same PID, the
same speed loop on the Table 2 motor, the watchdog and the e-stop of PROTOCOL.md."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

from firefleet.control.pid import PidParams, pid_init, pid_step
from firefleet.models import EncoderParams, MotorParams, discretise_motor, motor_step
from firefleet.models.encoder import encoder_init, encoder_step
from firefleet.robot import EStop, EStopClear, Pwm, Setpoint, pack
from tests.robot._firmware import Motor, Pid, PidGains, buffer

F32_REL = 2e-5  # float32 (the Arduino's float) against float64: a few ulp over a run


def _gains(dll: ctypes.CDLL) -> PidGains:
    g = PidGains()
    dll.ff_pid_defaults(ctypes.byref(g))
    return g


def test_firmware_pid_defaults_and_law_are_the_simulators(firmware: ctypes.CDLL) -> None:
    g = _gains(firmware)
    p = PidParams()
    assert [g.kp, g.ki, g.kd, g.tf, g.b, g.tt, g.limit] == pytest.approx(list(p.gains), rel=1e-7)
    rng = np.random.default_rng(0)
    refs, meas = rng.uniform(-15, 15, 300), rng.uniform(-15, 15, 300)
    c_state, state = Pid(), pid_init(0.0)
    for r, y in zip(refs, meas, strict=True):
        u_c = firmware.ff_pid_step(ctypes.byref(c_state), ctypes.byref(g), r, y, 0.01)
        state, u = pid_step(state, r, y, p, 0.01)
        assert u_c == pytest.approx(float(u), rel=F32_REL, abs=1e-4)


class _Board:
    """ff_motor.c on a simulated Table 2 motor pair with 2048-count encoders."""

    def __init__(self, dll: ctypes.CDLL) -> None:
        self.dll = dll
        self.m = Motor()
        g = _gains(dll)
        dll.ff_motor_init(ctypes.byref(self.m), ctypes.byref(g), 2048.0, 12.0, 0)
        self.t_us = 0
        self.angle = np.zeros(2)
        self.i = np.zeros(2)
        self.w = np.zeros(2)
        self.motor = discretise_motor(MotorParams(), 0.01)

    def command(self, frame: bytes) -> None:
        payload = frame[4:-2]
        self.dll.ff_motor_command(
            ctypes.byref(self.m), frame[3], buffer(payload), len(payload), self.t_us
        )

    def tick(self) -> np.ndarray:
        counts = (ctypes.c_int32 * 2)(*np.floor(self.angle * 2048 / (2 * np.pi)).astype(int))
        volts = (ctypes.c_float * 2)()
        self.dll.ff_motor_tick(ctypes.byref(self.m), self.t_us, counts, volts)
        v = np.array(volts[:], dtype=float)
        self.i, self.w, dphi = motor_step(self.i, self.w, v, 0.0, self.motor)
        self.angle = self.angle + dphi
        self.t_us = (self.t_us + 10_000) & 0xFFFFFFFF
        return v


def test_firmware_speed_loop_follows_the_simulators_wheel_stack(firmware: ctypes.CDLL) -> None:
    board = _Board(firmware)
    board.command(pack(Setpoint(10.0, -5.0)))
    # the simulator's stack: pid_step on the encoder's windowed speed, the same motor
    p, enc = PidParams(), EncoderParams()
    motor = discretise_motor(MotorParams(), 0.01)
    state, es = pid_init(np.zeros(2)), encoder_init(np.zeros(2), enc)
    i, w, speed = np.zeros(2), np.zeros(2), np.zeros(2)
    fw, sim = [], []
    for _ in range(150):  # 1.5 s, each step refreshing the setpoint as the Pi would
        board.command(pack(Setpoint(10.0, -5.0)))
        board.tick()
        fw.append(board.w.copy())
        state, u = pid_step(state, np.array([10.0, -5.0]), speed, p, 0.01)
        i, w, dphi = motor_step(i, w, u, 0.0, motor)
        es, _, speed = encoder_step(es, dphi, enc, 0.01)
        sim.append(w.copy())
    fw_a, sim_a = np.array(fw), np.array(sim)
    # float32 rounding may move a count edge by a step: a quantum (0.15 rad/s) through the
    # loop's gain is the most the speeds may differ by
    assert np.max(np.abs(fw_a - sim_a)) < 0.15
    np.testing.assert_allclose(fw_a[-1], [10.0, -5.0], atol=0.2)


def test_watchdog_stops_the_motors_200_ms_after_the_last_command(firmware: ctypes.CDLL) -> None:
    board = _Board(firmware)
    assert board.m.flags & 0x01  # tripped until the first command
    board.command(pack(Setpoint(8.0, 8.0)))
    volts = [board.tick() for _ in range(25)]  # ticks at 0, 10, ..., 240 ms
    moving = [bool(np.any(v != 0.0)) for v in volts]
    assert all(moving[:21])  # up to 200 ms: still driven
    assert not any(moving[21:])  # from 210 ms: off, flag set
    assert board.m.flags & 0x01
    board.command(pack(Setpoint(8.0, 8.0)))
    assert not board.m.flags & 0x01
    assert np.any(board.tick() != 0.0)


def test_watchdog_across_the_wrap_of_micros(firmware: ctypes.CDLL) -> None:
    board = _Board(firmware)
    board.t_us = 2**32 - 50_000  # micros() wraps 50 ms from now
    board.command(pack(Pwm(0.5, 0.5)))
    volts = [board.tick() for _ in range(25)]
    assert volts[0].tolist() == [6.0, 6.0]
    assert [bool(np.any(v)) for v in volts] == [True] * 21 + [False] * 4


def test_estop_latches_until_cleared_and_a_new_command(firmware: ctypes.CDLL) -> None:
    board = _Board(firmware)
    board.command(pack(Pwm(0.25, 0.25)))
    assert board.tick().tolist() == [3.0, 3.0]
    board.command(pack(EStop()))
    assert board.tick().tolist() == [0.0, 0.0]
    board.command(pack(Pwm(0.25, 0.25)))  # refused while latched
    assert board.tick().tolist() == [0.0, 0.0]
    assert board.m.flags & 0x02
    board.command(pack(EStopClear()))
    board.command(pack(Pwm(0.25, 0.25)))
    assert board.tick().tolist() == [3.0, 3.0]

"""The staged loop's quiet stretches (sim/loop.py, sim/_quiet_stretch.py,
sim/_kernels/_stretch.py): the same numbers as the tick-by-tick loop, bit for bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import firefleet
from firefleet.control.pid import PidParams
from firefleet.models import EncoderParams, MotorParams, RobotGeometry
from firefleet.sim import _quiet_stretch as qs
from firefleet.sim._kernels import _stretch
from firefleet.sim.drive import discretise_drive, drive_init, drive_step, speed_control
from firefleet.sim.kinds._mission_odometry import MissionOdometry
from firefleet.sim.loop import Odometry


@pytest.mark.parametrize("odometry", [Odometry(), MissionOdometry()])
def test_stretch_equals_the_ticks_it_replaces(odometry: Odometry) -> None:
    """speed_control, the fault's scale, drive_step and the odometry's step, tick by tick
    (the NumPy functions), against one compiled stretch: equal bit for bit."""
    rng = np.random.default_rng(3)
    n, m = 4, 37
    stack = discretise_drive(
        RobotGeometry(), MotorParams(), PidParams(), EncoderParams(window_steps=3), 0.01
    )
    drive = drive_init(rng.uniform(-2, 2, (n, 3)), rng.uniform(0, 0.003, (n, 2)), stack)
    est = odometry.init(drive.pose, drive)
    for _ in range(5):  # a moving start: PID memory, counts and odometry away from zero
        drive, volt = speed_control(drive, rng.uniform(-8, 8, (n, 2)), stack)
        drive = drive_step(drive, volt, stack)
        est = odometry.step(est, drive, stack, {})
    reference = rng.uniform(-12, 12, (n, 2))
    scale = np.array([1.0, 0.0, 1.0, 0.5])
    load = rng.uniform(0.0, 0.01, (n, 2))
    fast, pose, counts, poses = _stretch.stretch_drive(
        m, drive, stack, reference, scale, load, est.pose, est.counts
    )
    seen = []
    for _ in range(m):
        est = odometry.step(est, drive, stack, {})
        seen.append(drive.pose)
        drive, volt = speed_control(drive, reference, stack)
        drive = drive_step(drive, volt * scale[:, None], stack, load_torque_n_m=load)
    np.testing.assert_array_equal(poses, np.array(seen))
    np.testing.assert_array_equal(pose, est.pose)
    np.testing.assert_array_equal(counts, est.counts)
    for name in ("pose", "current_a", "speed_rad_s", "measured_rad_s"):
        np.testing.assert_array_equal(getattr(fast, name), getattr(drive, name))
    for a, b in ((fast.pid, drive.pid), (fast.encoder, drive.encoder)):
        for f in dataclasses.fields(a):
            np.testing.assert_array_equal(getattr(a, f.name), getattr(b, f.name))
    assert float(np.abs(poses[-1] - poses[0]).max()) > 1e-3  # the robots moved
    one, volt_one = _stretch.drive_tick(drive, stack, reference, scale, load)
    after, volt = speed_control(drive, reference, stack)
    after = drive_step(after, volt * scale[:, None], stack, load_torque_n_m=load)
    np.testing.assert_array_equal(volt_one, volt * scale[:, None])
    for name in ("pose", "current_a", "speed_rad_s", "measured_rad_s"):
        np.testing.assert_array_equal(getattr(one, name), getattr(after, name))


def test_mission_with_stretches_equals_the_tick_by_tick_loop(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A mission-office run of 12 s (exploration, the first frames, range scans,
    the contact test) with the quiet stretches and without: every array equal, and the
    stretches covered most ticks (74 %: those after a tick that changed the decision's
    state and those with a range scan too; 50 % without either)."""
    scenario = dataclasses.replace(firefleet.load_scenario("mission-office"), duration_s=12.0)
    ticks = []
    real = qs.stretch_drive

    def counted(m: int, *args: object, **kwargs: object) -> object:
        ticks.append(m)
        return real(m, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(qs, "stretch_drive", counted)
    fast = firefleet.simulate(scenario).arrays()
    monkeypatch.setattr(qs, "stretch_ok", lambda *a: False)
    slow = firefleet.simulate(scenario).arrays()
    assert sum(ticks) > 0.7 * scenario.n_steps, sum(ticks)
    assert fast.keys() == slow.keys()
    for name in fast:
        a, b = np.asarray(fast[name]), np.asarray(slow[name])
        if a.dtype.names:
            assert a.tobytes() == b.tobytes(), name
        else:
            np.testing.assert_array_equal(a, b, err_msg=name)

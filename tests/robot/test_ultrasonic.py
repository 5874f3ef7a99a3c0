"""The HC-SR04 adapter on gpiozero's MockFactory with exactly timed echoes: the
datasheet's range formula at the air's speed of sound, the median against spikes,
missing echoes and out-of-range targets, the PT100's temperature compensation, and the
on-board loop's readings."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.robot import (
    FakeHcSr04,
    FakeMax31865,
    HcSr04,
    Pt100,
    load_role,
    open_adapters,
    parse_robot_config,
    run_onboard,
)

pytestmark = pytest.mark.filterwarnings("ignore::gpiozero.DistanceSensorNoEcho")


def datasheet_echo_s(distance_m: float, air_c: float) -> float:
    """HC-SR04 manual: range = echo time * velocity / 2; velocity 331.3 + 0.606 T m/s."""
    return 2.0 * distance_m / (331.3 + 0.606 * air_c)


def sonar(echo_s: Callable[[int], float | None], **kwargs: float) -> HcSr04:
    fake = FakeHcSr04(23, 24, echo_s=echo_s)
    return HcSr04(23, 24, pin_factory=fake.factory, stale_s=3600.0, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize(("distance_m", "air_c"), [(0.02, 20.0), (1.5, -10.0), (3.9, 40.0)])
def test_distance_is_the_datasheet_formula_exactly(distance_m: float, air_c: float) -> None:
    echo = datasheet_echo_s(distance_m, air_c)
    with sonar(lambda _: echo, air_temperature_c=air_c) as s:
        reading = s.wait_for_reading(timeout_s=30.0)
    assert reading.shots == 5
    assert reading.echo_s == pytest.approx(echo, rel=1e-12)
    assert reading.distance_m == pytest.approx(distance_m, rel=1e-12)
    assert reading.speed_of_sound_m_s == pytest.approx(331.3 + 0.606 * air_c, rel=1e-15)


def test_the_median_drops_spikes_and_missing_echoes_are_counted() -> None:
    echo = datasheet_echo_s(0.8, 20.0)
    spike = datasheet_echo_s(0.15, 20.0)  # a stray near echo, one shot in five

    def script(shot: int) -> float | None:
        return {2: spike, 4: None}.get(shot % 5, echo)

    s = sonar(script, air_temperature_c=20.0)
    try:
        while s.shots_fired < 12:
            threading.Event().wait(0.02)
    finally:
        s.close()  # the sampling thread stops: the counters are final
    fired = s.shots_fired
    assert s.no_echoes == len([k for k in range(fired) if k % 5 == 4])
    reading = s.read()
    assert reading.shots == 4  # five latest shots, one without an echo
    assert reading.distance_m == pytest.approx(0.8, rel=1e-12)


def test_out_of_range_is_inf_and_no_echo_is_nan() -> None:
    with sonar(lambda _: datasheet_echo_s(2.5, 20.0), max_distance_m=2.0) as s:
        far = s.wait_for_reading(timeout_s=30.0)
    assert far.distance_m == np.inf
    assert far.shots == 5
    with sonar(lambda _: datasheet_echo_s(1.999, 20.0), max_distance_m=2.0) as s:
        near = s.wait_for_reading(timeout_s=30.0)
    assert near.distance_m == pytest.approx(1.999, rel=1e-12)
    with sonar(lambda _: None) as s:
        while s.no_echoes < 2:
            threading.Event().wait(0.02)
        silent = s.read()
    assert np.isnan(silent.distance_m)
    assert silent.shots == 0


def test_old_shots_are_not_used() -> None:
    now = [100.0]
    fake = FakeHcSr04(23, 24, echo_s=lambda _: datasheet_echo_s(1.0, 20.0))
    with HcSr04(23, 24, pin_factory=fake.factory, stale_s=0.5, clock=lambda: now[0]) as s:
        assert s.wait_for_reading(timeout_s=30.0).shots == 5
        s.close()
        now[0] += 0.51  # the sensor went quiet half a second ago
        assert np.isnan(s.read().distance_m)


def test_the_pt100_compensates_the_speed_of_sound() -> None:
    air_c, distance_m = 35.0, 2.0
    echo = datasheet_echo_s(distance_m, air_c)
    with sonar(lambda _: echo, air_temperature_c=20.0) as s:
        uncompensated = s.wait_for_reading(timeout_s=30.0).distance_m
        s.set_air_temperature(Pt100(FakeMax31865(temperature_c=air_c)).read().temperature_c)
        compensated = s.read().distance_m
    # 15 deg C of error is 2.6 % of range; the PT100 reads to 0.034 deg C (6e-5 of range)
    assert uncompensated == pytest.approx(distance_m * (343.42 / (331.3 + 0.606 * air_c)), 1e-12)
    assert abs(uncompensated - distance_m) > 0.05
    assert compensated == pytest.approx(distance_m, rel=1e-4)


def test_bad_parameters_name_the_key() -> None:
    with pytest.raises(InputError, match=r"max_distance_m: 5\.0 m, expected 0 < max <= 4\.0"):
        HcSr04(23, 24, max_distance_m=5.0)
    with pytest.raises(InputError, match="trigger_gpio and echo_gpio are both GPIO24"):
        HcSr04(24, 24)
    with pytest.raises(InputError, match=r"r\.yaml: hardware\.ultrasonic\.echo_gpio: .*28"):
        parse_robot_config(
            {"scenario": "x", "hardware": {"ultrasonic": {"echo_gpio": 28}}}, origin="r.yaml"
        )


def test_the_onboard_loop_reads_the_range_at_the_pt100s_temperature() -> None:
    config = parse_robot_config({
        "scenario": "coop-different-paths", "robot": 0, "duration_s": 1.5,
        "hardware": {"pt100": {"adapter": "fake", "rate_hz": 5.0},
                     "ultrasonic": {"adapter": "fake", "fake_distance_m": 1.25}},
    })  # fmt: skip
    before = threading.active_count()
    with open_adapters(config, fake=True) as adapters:
        result = run_onboard(config, load_role(config, Path(".")), adapters, stop=threading.Event())
    assert threading.active_count() == before  # the sampling thread is gone
    distances = np.array([d for _, d in result.range_m])
    assert len(distances) == 15  # 10 Hz for 1.5 s
    valid = distances[np.isfinite(distances)]
    assert len(valid) >= 13  # the first period or two may come before the first shot
    # the fake's air is the fake PT100's 23.5 deg C; the loop uses the PT100's reading
    np.testing.assert_allclose(valid, 1.25, rtol=1e-4)
    assert result.summary()["range_no_echo"] == len(distances) - len(valid)

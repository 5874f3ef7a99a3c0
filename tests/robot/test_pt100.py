"""The PT100 on a MAX31865 against IEC 60751's table and the data sheet's registers."""

from __future__ import annotations

import math

import pytest

from firefleet.errors import InputError
from firefleet.robot import FakeMax31865, Pt100, cvd_resistance_ohm, cvd_temperature_c

# IEC 60751 resistance table for Pt100 (ohm, printed to 0.01 ohm)
IEC_TABLE = [
    (-200.0, 18.52), (-100.0, 60.26), (-50.0, 80.31), (0.0, 100.00), (50.0, 119.40),
    (100.0, 138.51), (200.0, 175.86), (300.0, 212.05), (400.0, 247.09), (600.0, 313.71),
    (850.0, 390.48),
]  # fmt: skip


@pytest.mark.parametrize(("temperature_c", "ohm"), IEC_TABLE)
def test_callendar_van_dusen_reproduces_the_iec_table(temperature_c: float, ohm: float) -> None:
    assert cvd_resistance_ohm(temperature_c) == pytest.approx(ohm, abs=0.005)
    # the table rounds to 0.005 ohm: 0.013 deg C at 0.39 ohm/deg C, 0.025 where the slope
    # falls to 0.33 ohm/deg C at 850 deg C
    assert cvd_temperature_c(ohm) == pytest.approx(temperature_c, abs=0.025)


@pytest.mark.parametrize("temperature_c", [-40.0, 0.0, 21.5, 60.0, 150.0, 400.0])
def test_the_adapter_reads_the_chips_code_to_its_resolution(temperature_c: float) -> None:
    chip = FakeMax31865(temperature_c=temperature_c)
    reading = Pt100(chip, wires=3, mains_hz=50).read()
    # one code is 430 / 32768 = 0.0131 ohm, 0.034 deg C at 0.39 ohm/deg C; rounding: half
    assert reading.temperature_c == pytest.approx(temperature_c, abs=0.02)
    assert reading.fault == 0


def test_configuration_bytes_follow_the_data_sheet() -> None:
    chip = FakeMax31865()
    Pt100(chip, wires=4, mains_hz=60)
    assert chip.registers[0] == 0b1100_0000  # Vbias, auto; 2/4 wires; 60 Hz
    Pt100(chip, wires=3, mains_hz=50)
    assert chip.registers[0] == 0b1101_0001  # plus the 3-wire bit and the 50 Hz filter


def test_a_fault_is_reported_as_nan_with_its_bits_then_cleared() -> None:
    chip = FakeMax31865(temperature_c=25.0)
    probe = Pt100(chip)
    chip.fault = 0x80  # RTD high threshold: an open probe reads full scale
    reading = probe.read()
    assert math.isnan(reading.temperature_c)
    assert reading.fault == 0x80
    chip.fault = 0
    assert probe.read().temperature_c == pytest.approx(25.0, abs=0.02)
    with pytest.raises(InputError, match="wires must be 2, 3 or 4"):
        Pt100(chip, wires=5)
    assert math.isnan(cvd_temperature_c(-1.0))

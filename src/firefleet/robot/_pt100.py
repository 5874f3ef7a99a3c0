"""The PT100 air-temperature probe through a MAX31865 RTD-to-digital converter on SPI.

Section 2.7.2's future work adds a PT100 to the robot. The MAX31865 (Maxim 19-6478)
measures the RTD's resistance as a ratio to a reference resistor, a 15-bit code
``ADC = R_rtd / R_ref * 2^15``; the resistance gives the temperature through the
Callendar-Van Dusen equation of IEC 60751 (platinum, alpha = 0.00385):

    R(T) = R0 (1 + A T + B T^2)                      T >= 0 deg C
    R(T) = R0 (1 + A T + B T^2 + C (T - 100) T^3)    T <  0 deg C
    A = 3.9083e-3, B = -5.775e-7, C = -4.183e-12, R0 = 100 ohm,

inverted in closed form above 0 deg C and by Newton's method below. Registers (the
datasheet's table 1): 0x00 configuration (write at 0x80), 0x01-0x02 RTD code (bit 0 of
0x02 is the fault bit), 0x07 fault status. SPI mode 1 or 3, up to 5 MHz; a transfer is
an address byte followed by data, auto-incrementing.

The adapter talks to any object with spidev's ``xfer2(list[int]) -> list[int]`` (an
``spidev.SpiDev`` on the robot; :class:`FakeMax31865`, a register-level model, in tests).
A faulted conversion is reported as NaN with its fault bits, never as a temperature.

References
----------
Maxim Integrated, MAX31865 RTD-to-digital converter, data sheet 19-6478, rev 3.
IEC 60751:2008, Industrial platinum resistance thermometers and platinum temperature
sensors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

from firefleet.errors import InputError
from firefleet.models.pt100 import pt100_resistance_ohm, pt100_temperature_c

__all__ = ["FakeMax31865", "Pt100", "Pt100Reading", "cvd_resistance_ohm", "cvd_temperature_c"]

CONFIG, RTD_MSB, FAULT_STATUS = 0x00, 0x01, 0x07
WRITE = 0x80
VBIAS, AUTO, THREE_WIRE, FAULT_CLEAR, FILTER_50HZ = 0x80, 0x40, 0x10, 0x02, 0x01


def cvd_resistance_ohm(temperature_c: float) -> float:
    """A PT100's resistance at a temperature (IEC 60751) [ohm]: the scalar of
    :func:`firefleet.models.pt100.pt100_resistance_ohm`.

    Examples
    --------
    >>> from firefleet.robot import cvd_resistance_ohm
    >>> round(cvd_resistance_ohm(100.0), 2), round(cvd_resistance_ohm(-100.0), 2)  # IEC table
    (138.51, 60.26)
    """
    return float(pt100_resistance_ohm(temperature_c))


def cvd_temperature_c(resistance_ohm: float) -> float:
    """The temperature of a PT100 of this resistance (IEC 60751 inverted) [deg C]: the
    scalar of :func:`firefleet.models.pt100.pt100_temperature_c`; NaN for a resistance
    that is not a positive number.

    Examples
    --------
    >>> from firefleet.robot import cvd_temperature_c
    >>> round(cvd_temperature_c(119.40), 1), round(cvd_temperature_c(80.31), 1)  # IEC table
    (50.0, -50.0)
    """
    if not (math.isfinite(resistance_ohm) and resistance_ohm > 0.0):
        return math.nan
    return float(pt100_temperature_c(resistance_ohm))


class Spi(Protocol):
    """What the adapter needs of an SPI device (spidev's full-duplex transfer)."""

    def xfer2(self, data: list[int]) -> list[int]: ...


@dataclass(frozen=True)
class Pt100Reading:
    """One conversion.

    Attributes
    ----------
    temperature_c : float
        Air temperature [deg C]; NaN when the converter reports a fault.
    resistance_ohm : float
        Measured resistance [ohm] (NaN on a fault).
    fault : int
        The fault status register (0: none). Bits (datasheet table 7): 0x80 RTD high
        threshold, 0x40 RTD low threshold, 0x20 REFIN- > 0.85 VBIAS, 0x10 REFIN- < 0.85
        VBIAS (FORCE- open), 0x08 RTDIN- < 0.85 VBIAS (FORCE- open), 0x04 over/under
        voltage.
    """

    temperature_c: float
    resistance_ohm: float
    fault: int


class Pt100:
    """A PT100 on a MAX31865 (module notes).

    Parameters
    ----------
    spi : object with ``xfer2``
        The SPI device, already opened in mode 1 or 3.
    ref_ohm : float, keyword-only
        The board's reference resistor (430 ohm on the usual PT100 boards).
    wires : int, keyword-only
        2, 3 or 4 (the configuration's 3-wire bit).
    mains_hz : int, keyword-only
        50 or 60: the notch filter.

    Examples
    --------
    >>> from firefleet.robot import FakeMax31865, Pt100
    >>> chip = FakeMax31865(temperature_c=85.0)
    >>> probe = Pt100(chip, wires=3)
    >>> hex(chip.registers[0])  # Vbias on, automatic conversion, 3 wires, 50 Hz
    '0xd1'
    >>> round(probe.read().temperature_c, 1)
    85.0
    """

    def __init__(
        self, spi: Spi, *, ref_ohm: float = 430.0, wires: int = 3, mains_hz: int = 50
    ) -> None:
        if wires not in (2, 3, 4):
            raise InputError(f"pt100 wires must be 2, 3 or 4, got {wires}")
        if mains_hz not in (50, 60):
            raise InputError(f"pt100 mains_hz must be 50 or 60, got {mains_hz}")
        if not ref_ohm > 0.0:
            raise InputError(f"pt100 ref_ohm must be > 0, got {ref_ohm}")
        self._spi = spi
        self.ref_ohm = ref_ohm
        self.config = VBIAS | AUTO | (THREE_WIRE if wires == 3 else 0)
        self.config |= FILTER_50HZ if mains_hz == 50 else 0
        self._spi.xfer2([CONFIG | WRITE, self.config | FAULT_CLEAR])

    def read(self) -> Pt100Reading:
        """The latest conversion (automatic mode: one every 20 ms at 50 Hz)."""
        msb, lsb = self._spi.xfer2([RTD_MSB, 0, 0])[1:3]
        if lsb & 0x01:
            fault = self._spi.xfer2([FAULT_STATUS, 0])[1]
            self._spi.xfer2([CONFIG | WRITE, self.config | FAULT_CLEAR])
            return Pt100Reading(math.nan, math.nan, fault or 0x01)
        code = ((msb << 8) | lsb) >> 1
        resistance = code * self.ref_ohm / 32768.0
        return Pt100Reading(cvd_temperature_c(resistance), resistance, 0)


class FakeMax31865:
    """A register-level MAX31865 with a PT100 at a set temperature (for tests and --fake).

    Attributes
    ----------
    temperature_c : float
        The probe's temperature; change it at will.
    fault : int
        Fault bits to report (0: none), e.g. 0x80 for an open RTD reading full scale.
    registers : list of int
        The eight registers.
    """

    def __init__(self, *, temperature_c: float = 20.0, ref_ohm: float = 430.0) -> None:
        self.temperature_c = temperature_c
        self.ref_ohm = ref_ohm
        self.fault = 0
        self.registers = [0] * 8

    def _convert(self) -> None:
        if self.fault:
            self.registers[1], self.registers[2] = 0xFF, 0xFF
            self.registers[7] = self.fault
            return
        code = round(cvd_resistance_ohm(self.temperature_c) / self.ref_ohm * 32768.0)
        code = min(max(code, 0), 0x7FFF)
        self.registers[1] = (code >> 7) & 0xFF
        self.registers[2] = (code << 1) & 0xFE
        self.registers[7] = 0

    def xfer2(self, data: list[int]) -> list[int]:
        """An SPI transaction: address byte, then data (auto-increment)."""
        address, payload = data[0], data[1:]
        if address & WRITE:
            reg = address & 0x7F
            for k, value in enumerate(payload):
                if reg + k == CONFIG:
                    self.registers[CONFIG] = value & ~FAULT_CLEAR & 0xFF
                    if value & FAULT_CLEAR:
                        self.registers[7] = 0
                elif reg + k < 8:
                    self.registers[reg + k] = value & 0xFF
            return [0xFF] * len(data)
        if self.registers[CONFIG] & VBIAS and self.registers[CONFIG] & AUTO:
            self._convert()
        return [0xFF] + [self.registers[(address + k) % 8] for k in range(len(payload))]

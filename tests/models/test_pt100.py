"""The PT100 probe against IEC 60751's table, the first-order lag's analytic response and
the MAX31865's quantum."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.models.pt100 import (
    Pt100Params,
    pt100_read,
    pt100_resistance_ohm,
    pt100_step,
    pt100_temperature_c,
)

# IEC 60751 reference table (resistance of a PT100 [ohm], printed to 0.01 ohm).
IEC_TABLE = {
    -200.0: 18.52,
    -100.0: 60.26,
    0.0: 100.00,
    100.0: 138.51,
    200.0: 175.86,
    300.0: 212.05,
    400.0: 247.09,
    500.0: 280.98,
    600.0: 313.71,
    800.0: 375.70,
    850.0: 390.48,
}


def test_resistance_matches_the_iec_table() -> None:
    t = np.array(list(IEC_TABLE))
    r = pt100_resistance_ohm(t)
    np.testing.assert_allclose(r, list(IEC_TABLE.values()), atol=0.005)


def test_temperature_inverts_resistance_over_the_range() -> None:
    t = np.linspace(-200.0, 850.0, 211)
    np.testing.assert_allclose(pt100_temperature_c(pt100_resistance_ohm(t)), t, atol=1e-9)


def test_lag_is_the_analytic_first_order_response() -> None:
    p = Pt100Params(time_constant_s=8.0)
    probe = np.array([20.0, 300.0])
    air = np.array([200.0, 20.0])
    # one step of 8 s is 1 - 1/e of the way; 80 steps of 0.1 s land on the same value
    one = pt100_step(probe, air, p, 8.0)
    many = probe.copy()
    for _ in range(80):
        many = pt100_step(many, air, p, 0.1)
    expected = air + (probe - air) * np.exp(-1.0)
    np.testing.assert_allclose(one, expected, rtol=1e-12)
    np.testing.assert_allclose(many, expected, rtol=1e-12)


def test_reading_is_within_one_converter_step_below_the_truth() -> None:
    p = Pt100Params()
    t = np.linspace(-50.0, 800.0, 997)
    reading = pt100_read(t, p)
    # one step in temperature: the resistance step over dR/dt at each temperature
    slope_ohm_c = 100.0 * (3.9083e-3 + 2.0 * -5.775e-7 * t)
    step_c = p.resolution_ohm / slope_ohm_c
    assert np.all(reading <= t + 1e-9)
    assert np.all(t - reading < step_c + 1e-9)
    assert float(np.max(t - reading)) > 0.5 * float(step_c.min())  # it does quantise


def test_ideal_converter_reads_the_probe() -> None:
    t = np.array([-20.0, 37.0, 450.0])
    np.testing.assert_allclose(pt100_read(t, Pt100Params(adc_bits=0)), t, atol=1e-9)


@pytest.mark.parametrize(
    ("kwargs", "key"),
    [
        ({"time_constant_s": 0.0}, "sensors.pt100.time_constant_s"),
        ({"ref_ohm": -1.0}, "sensors.pt100.ref_ohm"),
        ({"adc_bits": 40}, "sensors.pt100.adc_bits"),
    ],
)
def test_bad_parameters_name_the_key(kwargs: dict[str, float], key: str) -> None:
    with pytest.raises(InputError, match=key):
        Pt100Params(**kwargs)  # type: ignore[arg-type]

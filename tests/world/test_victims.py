"""The victims' survival clock against ISO 13571's tolerance times."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.errors import InputError
from firefleet.world import VictimParams, VictimState, victim_dose_rate, victim_step


@pytest.mark.parametrize(
    ("temperature_c", "minutes"),
    # ISO 13571 convective heat, t_I = 5e7 T^-3.4 min: worked by hand
    [(60.0, 5e7 / 60.0**3.4), (80.0, 16.93), (120.0, 4.263)],
)
def test_time_to_incapacitation_in_heat_is_iso_13571s(temperature_c: float, minutes: float) -> None:
    rate = victim_dose_rate([temperature_c], [0.0], VictimParams())
    assert 1.0 / rate[0] / 60.0 == pytest.approx(minutes, rel=5e-3)


def test_co_dose_from_smoke_and_doses_add() -> None:
    params = VictimParams()
    # K = 1 /m: 115 ppm of CO; 35,000 ppm min / 115 ppm = 304 min
    assert 1.0 / victim_dose_rate([20.0], [1.0], params)[0] / 60.0 == pytest.approx(304.3, rel=1e-3)
    both = victim_dose_rate([80.0], [1.0], params)[0]
    assert both == pytest.approx(
        victim_dose_rate([80.0], [0.0], params)[0] + victim_dose_rate([20.0], [1.0], params)[0]
    )
    assert victim_dose_rate([39.9], [0.0], params)[0] == 0.0  # below the heat threshold


def test_a_victim_dies_when_the_dose_reaches_one() -> None:
    state = VictimState(position_m=np.zeros((2, 2)), dose=np.zeros(2))
    t_i_s = 5e7 * 80.0**-3.4 * 60.0
    steps = int(np.ceil(t_i_s))  # 1 s steps: victim 0 at 80 deg C, victim 1 in clean air
    alive_at = []
    for _ in range(steps + 1):
        state = victim_step(state, [80.0, 20.0], [0.0, 0.0], VictimParams(), 1.0)
        alive_at.append(state.alive.tolist())
    assert alive_at[steps - 2] == [True, True]
    assert alive_at[steps] == [False, True]


def test_bad_victim_input() -> None:
    state = VictimState(position_m=np.zeros((2, 2)), dose=np.zeros(2))
    with pytest.raises(InputError, match="1 readings for 2 victims"):
        victim_step(state, [80.0], [0.0], VictimParams(), 1.0)
    with pytest.raises(InputError, match="must match"):
        victim_dose_rate([80.0, 20.0], [0.0], VictimParams())
    with pytest.raises(InputError, match="co_ppm_per_od"):
        VictimParams(co_ppm_per_od=0.0)

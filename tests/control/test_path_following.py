"""The deliverable's path-following controller and its compiled evaluation."""

from __future__ import annotations

import math

import numpy as np
import pytest

from firefleet.control.fuzzy import evaluate
from firefleet.control.fuzzy_kernel import compile_system, eval_one
from firefleet.control.path_following import PathFollowingController, controller_inputs
from firefleet.errors import InputError

CTL = PathFollowingController.builtin()


def test_inputs_by_hand() -> None:
    # robot at the origin facing +y (phi = 90 deg); its point at (1, 1) on a path heading +x
    out = controller_inputs([[0.0, 0.0, math.pi / 2]], [[1.0, 1.0, 0.0]])[0]
    assert out[0] == pytest.approx(math.sqrt(2), abs=1e-15)  # eq. 9
    assert out[1] == pytest.approx(1.0, abs=1e-15)  # along the path
    assert out[2] == pytest.approx(-1.0, abs=1e-15)  # eq. 10: the point is to the right
    assert out[3] == pytest.approx(-math.pi / 4, abs=1e-15)  # eqs. 10-11
    # a point exactly on the robot: alpha is 0, not atan2's arbitrary value
    assert controller_inputs([[2.0, 3.0, 1.0]], [[2.0, 3.0, 0.0]])[0, 3] == 0.0


def test_rule_11_stops_a_robot_ahead_of_its_point() -> None:
    # x_err < -5 cm: only rule 11 fires, v = omega = 0 (2.6.2.4), whatever D and alpha
    inputs = np.array([[d, -0.2, y, a] for d in (0.1, 2.0) for y in (-1, 1) for a in (-2, 0, 2)])
    v, omega, _ = CTL.command(inputs)
    np.testing.assert_array_equal(v, 0.0)
    np.testing.assert_array_equal(omega, 0.0)


def test_speed_grows_with_distance_and_turn_follows_alpha() -> None:
    d = np.linspace(0.0, 3.0, 31)
    inputs = np.stack([d, np.ones_like(d), np.zeros_like(d), np.zeros_like(d)], axis=1)
    v, omega, _ = CTL.command(inputs)
    assert np.all(np.diff(v) >= 0)  # Figure 16
    assert v[-1] > v[0]
    np.testing.assert_allclose(omega, 0.0, atol=1e-12)
    # with alpha = 0 and x_err Positive, v = (v_D(D) + VeryVerySlow) / 2 (Table 1):
    # at the peak of Far (0.8 m) that is (0.8 + 0.02) / 2
    assert float(v[8]) == pytest.approx(0.41, abs=1e-12)
    a = np.radians(np.linspace(-170, 170, 35))
    inputs = np.stack([np.full_like(a, 0.5), np.ones_like(a), np.zeros_like(a), a], axis=1)
    _, omega, _ = CTL.command(inputs)
    assert np.all(np.sign(omega) == np.sign(a))  # Figure 17: turn towards the point
    assert np.all(np.diff(omega) >= 0)


def test_lambda_turns_towards_the_path() -> None:
    y = np.array([-3.0, -0.5, 0.0, 0.5, 3.0])
    inputs = np.stack([np.ones(5), np.ones(5), y, np.zeros(5)], axis=1)
    _, omega, lam = CTL.command(inputs)
    np.testing.assert_allclose(np.degrees(lam), [-40, -10, 0, 10, 40], atol=1e-12)
    assert np.all(np.sign(omega) == np.sign(y))


def test_compiled_evaluation_equals_the_reference_engine() -> None:
    rng = np.random.default_rng(7)
    x = np.stack(
        [rng.uniform(-0.5, 3.5, 500), rng.uniform(-0.2, 0.2, 500), rng.uniform(-200, 200, 500)],
        axis=1,
    )
    ref = evaluate(CTL.main, x)
    tables = compile_system(CTL.main)
    out = np.empty(2)
    for k in range(x.shape[0]):
        eval_one(x[k], *tables, out, np.empty(64))
        np.testing.assert_allclose(out, ref[k], rtol=0, atol=1e-12)


def test_a_system_with_other_variables_is_rejected() -> None:
    with pytest.raises(InputError, match="needs inputs D_rp, x_err, alpha"):
        PathFollowingController(main=CTL.correction, correction=CTL.correction)


def test_arrival_once_the_last_point_is_out_and_the_robot_is_past_the_end() -> None:
    from firefleet.control.path_following import arrival

    # path end at (5, 0) heading +x; a second one at (0, 3) heading +y
    end = np.array([[5.0, 0.0, 0.0], [0.0, 3.0, math.pi / 2]])
    before = np.zeros(2, dtype=bool)
    past = np.array([[5.01, 1.0, 0.0], [2.0, 3.0, 0.0]])  # robot 2 exactly on the end line
    np.testing.assert_array_equal(arrival(before, past, end, 50, 50), [True, True])
    # not yet released: nobody arrives, however far
    np.testing.assert_array_equal(arrival(before, past, end, 49, 50), [False, False])
    short = np.array([[4.99, 0.0, 0.0], [0.0, 2.9, 0.0]])
    np.testing.assert_array_equal(arrival(before, short, end, 60, 50), [False, False])
    # once arrived, a robot stays arrived
    np.testing.assert_array_equal(
        arrival(np.array([True, False]), short, end, 60, 50), [True, False]
    )

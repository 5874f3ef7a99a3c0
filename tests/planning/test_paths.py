"""Polynomial paths: arc length, tangent, curvature, equal-arc sampling, distance."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from firefleet.errors import InputError
from firefleet.planning.paths import PolynomialPath, straight_line

QUINTIC = PolynomialPath((1.58, 0.2, 0.0009, -0.0302, 0.0045, -0.00018), 0.01, 10.01)


def test_parabola_arc_length_is_the_analytic_value() -> None:
    # y = x^2 on [0, a]: L = a/2 sqrt(1 + 4a^2) + asinh(2a)/4
    a = 2.0
    exact = a / 2 * math.sqrt(1 + 4 * a * a) + math.asinh(2 * a) / 4
    path = PolynomialPath((0.0, 0.0, 1.0), 0.0, a)
    assert path.length_m == pytest.approx(exact, abs=1e-9)  # issue: 1e-6 m
    # travelled the other way: same length
    assert PolynomialPath((0.0, 0.0, 1.0), a, 0.0).length_m == pytest.approx(exact, abs=1e-9)


def test_quintic_arc_length_matches_adaptive_quadrature() -> None:
    d1 = np.polynomial.polynomial.polyder(QUINTIC.coefficients)

    def speed(x: float) -> float:
        return math.sqrt(1 + np.polynomial.polynomial.polyval(x, d1) ** 2)

    exact, _ = quad(speed, 0.01, 10.01, epsabs=1e-13, epsrel=1e-13)
    assert QUINTIC.length_m == pytest.approx(exact, abs=1e-9)
    partial, _ = quad(speed, 0.01, 4.3, epsabs=1e-13, epsrel=1e-13)
    assert float(QUINTIC.arc_length(4.3)) == pytest.approx(partial, abs=1e-9)


def test_straight_line_length_heading_curvature() -> None:
    line = straight_line((1.0, 2.0), (4.0, 6.0))
    assert line.length_m == pytest.approx(5.0, abs=1e-12)
    assert float(line.heading(2.0)) == pytest.approx(math.atan2(4, 3), abs=1e-15)
    assert float(line.curvature(2.0)) == 0.0
    back = straight_line((4.0, 6.0), (1.0, 2.0))
    assert float(back.heading(2.0)) == pytest.approx(math.atan2(-4, -3), abs=1e-15)


def test_parabola_curvature_and_heading() -> None:
    path = PolynomialPath((0.0, 0.0, 1.0), -1.0, 1.0)
    x = np.array([-0.5, 0.0, 0.7])
    np.testing.assert_allclose(path.curvature(x), 2 / (1 + 4 * x * x) ** 1.5, rtol=1e-14)
    np.testing.assert_allclose(path.heading(x), np.arctan(2 * x), rtol=1e-14)
    # travelled towards -x the parabola turns right: negative curvature
    assert float(PolynomialPath((0.0, 0.0, 1.0), 1.0, -1.0).curvature(0.0)) == -2.0


def test_sample_is_equally_spaced_in_arc_length() -> None:
    pts = QUINTIC.sample(50)
    assert pts.shape == (51, 3)
    assert pts[0, 0] == 0.01
    assert pts[-1, 0] == 10.01
    s = QUINTIC.arc_length(pts[:, 0])
    np.testing.assert_allclose(np.diff(s), QUINTIC.length_m / 50, atol=1e-10)
    np.testing.assert_allclose(pts[:, 1], QUINTIC.y(pts[:, 0]), rtol=0, atol=0)
    np.testing.assert_allclose(pts[:, 2], QUINTIC.heading(pts[:, 0]), rtol=0, atol=0)


def test_distance_to_the_path() -> None:
    line = straight_line((0.0, 0.0), (10.0, 0.0))
    d, s = line.distance(np.array([[3.0, 1.5], [12.0, 0.0], [-3.0, 4.0], [5.0, 0.0]]))
    np.testing.assert_allclose(d, [1.5, 2.0, 5.0, 0.0], atol=1e-12)  # ends are clamped
    np.testing.assert_allclose(s, [3.0, 10.0, 0.0, 5.0], atol=1e-12)
    # a point on the quintic, pushed off along the normal: distance is the push
    x0 = 6.2
    normal = float(QUINTIC.heading(x0)) + math.pi / 2
    p = np.array([x0, float(QUINTIC.y(x0))]) + 0.3 * np.array([math.cos(normal), math.sin(normal)])
    d, s = QUINTIC.distance(p[None, :])
    assert float(d[0]) == pytest.approx(0.3, abs=1e-9)  # 0.3 m < radius of curvature
    assert float(s[0]) == pytest.approx(float(QUINTIC.arc_length(x0)), abs=1e-9)


def test_bad_paths() -> None:
    with pytest.raises(InputError, match="vertical"):
        straight_line((1.0, 0.0), (1.0, 5.0))
    with pytest.raises(InputError, match="1 to 6 coefficients"):
        PolynomialPath(tuple(range(7)), 0.0, 1.0)
    with pytest.raises(InputError, match="x_end_m != x_start_m"):
        PolynomialPath((0.0,), 1.0, 1.0)
    with pytest.raises(InputError, match="finite"):
        PolynomialPath((math.nan,), 0.0, 1.0)
    with pytest.raises(InputError, match="n >= 1"):
        QUINTIC.sample(0)
    with pytest.raises(InputError, match=r"shape \(..., 2\)"):
        QUINTIC.distance(np.zeros((4, 3)))

"""perception/thermal/_select.py: the bucketed order statistics equal quickselect's and
NumPy's, bit for bit (the detector's column steps and background rest on them)."""

from __future__ import annotations

import numpy as np
import pytest

from firefleet.perception.thermal._select import _pair_by_select, order_pair, quickselect


def _sets(rng: np.random.Generator) -> list[np.ndarray]:
    """Sets the detector meets and the cases that break bucketing: normal values,
    quantised ones (many ties), signed zeros, a far outlier, one value, all equal."""
    out = []
    for m in (1, 2, 3, 8, 59, 60, 61, 4800):
        out += [
            rng.normal(20.0, 3.0, m),
            np.round(rng.normal(0.0, 0.05, m), 2),
            rng.choice([0.0, -0.0, 1.0, -1.0], m),
            np.r_[np.full(m - 1, 20.0), [1999.0]],
            np.full(m, 7.5),
            np.r_[rng.normal(size=m - 1), [1e300]],
        ]
    return out


@pytest.mark.parametrize("buckets", [2, 16, 1024])
def test_order_pair_equals_quickselect_and_sorting(buckets: int) -> None:
    rng = np.random.default_rng(15)
    for x in _sets(rng):
        m = x.size
        for k in sorted({0, m // 2, m - 1, int(rng.integers(0, m))}):
            got = order_pair(x, m, k, np.zeros(buckets, np.int64), np.empty(m))
            ref = _pair_by_select(x, m, k, np.empty(m))
            assert np.array(got).tobytes() == np.array(ref).tobytes(), (m, k)
            s = np.sort(x)
            assert got[1] == s[k]
            assert got[0] == s[max(k - 1, 0)]
        if m % 2 == 0 and m > 1:  # the median as np.median gives it
            lower, upper = order_pair(x, m, m // 2, np.zeros(buckets, np.int64), np.empty(m))
            assert (lower + upper) / 2 == np.median(x)


def test_quickselect_leaves_the_k_smallest_first() -> None:
    x = np.random.default_rng(3).permutation(np.arange(50.0))
    assert quickselect(x, 50, 20) == 20.0
    assert sorted(x[:20]) == list(np.arange(20.0))

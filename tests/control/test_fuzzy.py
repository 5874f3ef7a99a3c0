"""The Takagi-Sugeno engine: membership functions, inference, .fis files, bad input.

References: hand-computed values (MATLAB's definitions), scikit-fuzzy's membership
functions (an independent implementation), and hand-written MATLAB-style files.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import skfuzzy
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.control.fuzzy import (
    FuzzyInput,
    FuzzyOutput,
    MembershipFunction,
    MfKind,
    Rule,
    SugenoOutputMf,
    SugenoSystem,
    evaluate,
    membership,
)
from firefleet.errors import InputError
from tests.control.fuzzy_systems import every_feature, finite, systems

DATA = Path(__file__).resolve().parents[1] / "data" / "fuzzy"

EXACT = 1e-12
"""Same closed form in float64 on both sides: only rounding (~1e-16) may differ."""


# ------------------------------------------------------------------ membership functions

HAND_CASES: list[tuple[MfKind, list[float], list[float], list[float]]] = [
    # kind, params, x, expected (MATLAB's definitions worked by hand)
    ("trimf", [0, 2, 4], [-1, 0, 1, 2, 3, 4, 5], [0, 0, 0.5, 1, 0.5, 0, 0]),
    # vertical left side: 1 at the shoulder itself, MATLAB's trimf "x == b" rule
    ("trimf", [0, 0, 4], [-1, 0, 1, 4], [0, 1, 0.75, 0]),
    ("trimf", [0, 4, 4], [0, 3, 4, 5], [0, 0.75, 1, 0]),
    ("trimf", [1, 1, 1], [0.5, 1, 1.5], [0, 1, 0]),
    ("trapmf", [0, 1, 3, 4], [-1, 0.5, 1, 2, 3, 3.5, 4], [0, 0.5, 1, 1, 1, 0.5, 0]),
    ("trapmf", [0, 0, 3, 3], [-0.1, 0, 1, 3, 3.1], [0, 1, 1, 1, 0]),
    # b > c: MATLAB's min(y1, y2), a flat-topped triangle below 1
    ("trapmf", [0, 4, 2, 6], [2, 3, 4], [0.5, 0.75, 0.5]),
    ("gaussmf", [2, 1], [1, 3, -1], [1, math.exp(-0.5), math.exp(-0.5)]),
    ("gaussmf", [-2, 1], [3], [math.exp(-0.5)]),  # sigma enters squared
    ("gbellmf", [2, 1, 0], [0, 2, -4], [1, 0.5, 0.2]),
    ("gbellmf", [1, 0, 0], [0, 5], [0.5, 0.5]),  # b = 0: 1/2 everywhere
    ("gbellmf", [1, -1, 0], [0, 1], [0, 0.5]),  # b < 0: MATLAB returns 0 at the centre
    ("sigmf", [2, 1], [1, 1 + math.log(3) / 2], [0.5, 0.75]),
    ("sigmf", [-800, 0], [1, -1], [0, 1]),  # no overflow warning far in the tails
    ("smf", [0, 4], [-1, 0, 1, 2, 3, 4, 5], [0, 0, 0.125, 0.5, 0.875, 1, 1]),
    ("zmf", [0, 4], [-1, 0, 1, 2, 3, 4, 5], [1, 1, 0.875, 0.5, 0.125, 0, 0]),
    # a >= b: MATLAB's step at the midpoint, x >= (a+b)/2 for smf, x <= for zmf
    ("smf", [4, 2], [2.9, 3, 3.1], [0, 1, 1]),
    ("zmf", [4, 2], [2.9, 3, 3.1], [1, 1, 0]),
]


@pytest.mark.parametrize(("kind", "params", "x", "expected"), HAND_CASES)
def test_membership_hand_values(
    kind: MfKind, params: list[float], x: list[float], expected: list[float]
) -> None:
    np.testing.assert_allclose(membership(kind, params, x), expected, rtol=0, atol=EXACT)


def _skfuzzy(kind: str, p: list[float], x: np.ndarray) -> np.ndarray:
    """scikit-fuzzy's version of MATLAB's (kind, params); its argument orders differ."""
    m = skfuzzy.membership
    out: np.ndarray
    if kind == "trimf":
        out = m.trimf(x, p)
    elif kind == "trapmf":
        out = m.trapmf(x, p)
    elif kind == "gaussmf":
        out = m.gaussmf(x, p[1], p[0])  # (mean, sigma)
    elif kind == "gbellmf":
        out = m.gbellmf(x, p[0], p[1], p[2])
    elif kind == "sigmf":
        out = m.sigmf(x, p[1], p[0])  # (centre, slope)
    elif kind == "smf":
        out = m.smf(x, p[0], p[1])
    else:
        out = m.zmf(x, p[0], p[1])
    return out


@pytest.mark.parametrize("kind", ["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"])
def test_membership_matches_scikit_fuzzy(kind: str) -> None:
    rng = np.random.default_rng(7)
    for _ in range(20):
        if kind in ("trimf", "trapmf", "smf", "zmf"):
            n = {"trimf": 3, "trapmf": 4}.get(kind, 2)
            p = np.sort(rng.uniform(-5, 5, n)).tolist()
        elif kind == "gaussmf":
            p = [rng.uniform(0.1, 3), rng.uniform(-5, 5)]
        elif kind == "gbellmf":
            p = [rng.uniform(0.2, 3), rng.uniform(0.5, 4), rng.uniform(-5, 5)]
        else:
            p = [rng.uniform(-5, 5), rng.uniform(-5, 5)]
        # a dense grid plus every breakpoint exactly (where piecewise forms switch)
        x = np.unique(np.concatenate([np.linspace(-7, 7, 1401), p]))
        ours = membership(kind, p, x)  # type: ignore[arg-type]
        np.testing.assert_allclose(ours, _skfuzzy(kind, p, x), rtol=0, atol=EXACT)


@pytest.mark.parametrize(
    ("kind", "params", "message"),
    [
        ("trimf", [2, 1, 3], "a <= b <= c"),
        ("trimf", [0, 1], "takes 3 parameters"),
        ("trapmf", [0, 1, 2], "takes 4 parameters"),
        ("trapmf", [2, 1, 3, 4], "a <= b and c <= d"),
        ("gaussmf", [0, 1], "sigma != 0"),
        ("gbellmf", [0, 1, 1], "a != 0"),
        ("sigmf", [1, math.nan], "finite"),
        ("cosmf", [1, 2], "unknown membership function type 'cosmf'"),
    ],
)
def test_membership_rejects_bad_parameters(kind: str, params: list[float], message: str) -> None:
    with pytest.raises(InputError, match=message):
        membership(kind, params, [0.0])  # type: ignore[arg-type]


def test_membership_rejects_nan_points() -> None:
    with pytest.raises(InputError, match="x must be finite"):
        membership("trimf", [0, 1, 2], [0.5, math.nan])


# ------------------------------------------------------------------ inference, by hand


def _ramps(
    rules: list[Rule],
    *,
    outputs: list[SugenoOutputMf] | None = None,
    and_method: str = "prod",
    or_method: str = "probor",
    defuzz: str = "wtaver",
) -> SugenoSystem:
    """Two inputs on [0, 10], each with 'lo' = trimf [0 0 10] (1 - x/10) and 'hi' =
    trimf [0 10 10] (x/10); one output on [0, 100] with consequents 10 and 30."""
    lo = MembershipFunction("lo", "trimf", (0, 0, 10))
    hi = MembershipFunction("hi", "trimf", (0, 10, 10))
    mfs = outputs or [
        SugenoOutputMf("ten", "constant", (10,)),
        SugenoOutputMf("thirty", "constant", (30,)),
    ]
    return SugenoSystem(
        name="ramps",
        inputs=(FuzzyInput("a", (0, 10), (lo, hi)), FuzzyInput("b", (0, 10), (lo, hi))),
        outputs=(FuzzyOutput("y", (0, 100), tuple(mfs)),),
        rules=tuple(rules),
        and_method=and_method,  # type: ignore[arg-type]
        or_method=or_method,  # type: ignore[arg-type]
        defuzz=defuzz,  # type: ignore[arg-type]
    )


# At x = (2, 5): a.lo = 0.8, a.hi = 0.2, b.lo = 0.5, b.hi = 0.5.
X = [2.0, 5.0]
TWO_RULES = [Rule((1, 1), (1,)), Rule((2, 2), (2,))]
HAND_INFERENCE = [
    # prod AND: w = 0.4, 0.1 -> (4 + 3) / 0.5
    (_ramps(TWO_RULES), 14.0),
    # wtsum: 0.4 * 10 + 0.1 * 30
    (_ramps(TWO_RULES, defuzz="wtsum"), 7.0),
    # min AND: w = 0.5, 0.2 -> (5 + 6) / 0.7
    (_ramps(TWO_RULES, and_method="min"), 11.0 / 0.7),
    # max OR: w = 0.8, 0.5 -> (8 + 15) / 1.3
    (
        _ramps(
            [Rule((1, 1), (1,), connective="or"), Rule((2, 2), (2,), connective="or")],
            or_method="max",
        ),
        23.0 / 1.3,
    ),
    # probor OR: w = 0.8 + 0.5 - 0.4 = 0.9, 0.2 + 0.5 - 0.1 = 0.6 -> (9 + 18) / 1.5
    (_ramps([Rule((1, 1), (1,), connective="or"), Rule((2, 2), (2,), connective="or")]), 18.0),
    # NOT: w = 1 - a.lo = 0.2 (b unused), and b.lo * (1 - a.hi) = 0.5 * 0.8 = 0.4
    (_ramps([Rule((-1, 0), (1,)), Rule((-2, 1), (2,))]), (2.0 + 12.0) / 0.6),
    # weights 0.5 and 1: w = 0.2, 0.1 -> (2 + 3) / 0.3
    (_ramps([Rule((1, 1), (1,), weight=0.5), Rule((2, 2), (2,))]), 5.0 / 0.3),
    # mixed AND and OR rules: w = 0.4 (prod), 0.6 (probor)
    (_ramps([Rule((1, 1), (1,)), Rule((2, 2), (2,), connective="or")]), (4.0 + 18.0) / 1.0),
    # first order: z1 = 1 a + 2 b + 3 = 15, z2 = -1 a + 0 b + 50 = 48; w = 0.4, 0.1
    (
        _ramps(
            TWO_RULES,
            outputs=[
                SugenoOutputMf("l1", "linear", (1, 2, 3)),
                SugenoOutputMf("l2", "linear", (-1, 0, 50)),
            ],
        ),
        (0.4 * 15 + 0.1 * 48) / 0.5,
    ),
]


@pytest.mark.parametrize(("system", "expected"), HAND_INFERENCE)
def test_inference_hand_computed(system: SugenoSystem, expected: float) -> None:
    np.testing.assert_allclose(evaluate(system, X), [expected], rtol=0, atol=EXACT)
    # and the vectorised path (N > 1) gives the same
    batch = evaluate(system, [X, X, X])
    np.testing.assert_allclose(batch, [[expected]] * 3, rtol=0, atol=EXACT)


def test_no_rule_fires_gives_range_midpoint_without_warnings() -> None:
    # 'hi' and 'hi' at a = b = 0 are both 0: nothing fires; MATLAB returns mid-range
    system = _ramps([Rule((2, 2), (1,))])
    assert evaluate(system, [0.0, 0.0]).tolist() == [50.0]
    assert evaluate(system, [[0.0, 0.0], [10.0, 10.0]]).tolist() == [[50.0], [10.0]]
    wtsum = _ramps([Rule((2, 2), (1,))], defuzz="wtsum")
    assert evaluate(wtsum, [[0.0, 0.0], [0.0, 0.0]]).tolist() == [[0.0], [0.0]]


def test_inputs_are_clipped_to_their_ranges() -> None:
    system = _ramps(
        TWO_RULES,
        outputs=[SugenoOutputMf("l", "linear", (1, 1, 0)), SugenoOutputMf("c", "constant", (0,))],
    )
    outside = np.array([[-5.0, 3.0], [25.0, 3.0], [4.0, 1e9]])
    inside = np.array([[0.0, 3.0], [10.0, 3.0], [4.0, 10.0]])
    np.testing.assert_array_equal(evaluate(system, outside), evaluate(system, inside))
    np.testing.assert_array_equal(evaluate(system, outside[0]), evaluate(system, inside[0]))


# ------------------------------------------------------------------ batch = one by one


def test_batch_equals_one_by_one() -> None:
    system = every_feature()
    rng = np.random.default_rng(3)
    x = rng.uniform([-4, -1, -1.5], [4, 6, 1.5], size=(500, 3))  # some outside the ranges
    batch = evaluate(system, x)
    assert batch.shape == (500, 2)
    singles = np.array([evaluate(system, row) for row in x])
    ones = np.vstack([evaluate(system, row[None, :]) for row in x])
    # scalar and vectorised arithmetic differ only in rounding order
    np.testing.assert_allclose(batch, singles, rtol=0, atol=EXACT)
    np.testing.assert_allclose(batch, ones, rtol=0, atol=EXACT)
    assert np.all(np.isfinite(batch))


@settings(max_examples=60, deadline=None)
@given(st.data())
def test_batch_equals_one_by_one_random_systems(data: st.DataObject) -> None:
    system = data.draw(systems())
    n_in = len(system.inputs)
    rows = data.draw(
        st.lists(st.lists(finite(-12, 12), min_size=n_in, max_size=n_in), min_size=2, max_size=6)
    )
    x = np.array(rows)
    np.testing.assert_allclose(
        evaluate(system, x), np.array([evaluate(system, r) for r in x]), rtol=1e-12, atol=1e-9
    )


# ------------------------------------------------------------------ bad input


def test_evaluate_rejects_bad_shapes_and_nan() -> None:
    system = every_feature()
    for bad in ([1.0, 2.0], np.zeros((4, 2)), np.zeros((2, 3, 1))):
        with pytest.raises(InputError, match=r"shape \(3,\) or \(N, 3\)"):
            evaluate(system, bad)
    for bad_x in ([1.0, math.nan, 0.0], [[1.0, 0.0, math.inf], [0.0, 0.0, 0.0]], [[math.nan] * 3]):
        with pytest.raises(InputError, match="finite"):
            evaluate(system, bad_x)


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Rule((0, 0), (1,)), "uses no input"),
        (lambda: Rule((1, 1), (-1,)), "negative (NOT) consequents"),
        (lambda: Rule((1, 1), (1,), weight=1.5), "weight must be in [0, 1]"),
        (lambda: Rule((1, 1.5), (1,)), "must be integers"),  # type: ignore[arg-type]
        (lambda: _ramps([Rule((3, 1), (1,))]), "rules[1].antecedent: index 3 out of range"),
        (lambda: _ramps([Rule((1,), (1,))]), "rules[1].antecedent: 1 indices for 2 inputs"),
        (lambda: _ramps([Rule((1, 1), (3,))]), "rules[1].consequent: index 3 out of range"),
        (lambda: _ramps(TWO_RULES, and_method="mean"), "system.and_method must be one of"),
        (
            lambda: _ramps(TWO_RULES, outputs=[SugenoOutputMf("l", "linear", (1, 2))]),
            "linear takes 3 parameters",
        ),
        (
            lambda: FuzzyInput("x", (1, 0), (MembershipFunction("a", "trimf", (0, 1, 2)),)),
            "min <= max",
        ),
        (
            lambda: FuzzyInput("x'", (0, 1), (MembershipFunction("a", "trimf", (0, 1, 2)),)),
            "quotes",
        ),
        (lambda: FuzzyOutput("y", (0, 1), ()), "non-empty"),
    ],
)
def test_invalid_systems_are_rejected(build: object, message: str) -> None:
    with pytest.raises(InputError, match=None) as info:
        build()  # type: ignore[operator]
    assert message in str(info.value)

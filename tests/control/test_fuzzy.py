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
    evaluate_csv,
    fis_text,
    membership,
    parse_fis,
    read_fis,
)
from firefleet.errors import InputError

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


def _every_feature() -> SugenoSystem:
    """Three inputs, every MF kind, NOT, weights, AND and OR, constant and linear."""
    mf = MembershipFunction
    return SugenoSystem(
        name="everything",
        inputs=(
            FuzzyInput(
                "p",
                (-3, 3),
                (
                    mf("t", "trimf", (-3, -1, 1)),
                    mf("tr", "trapmf", (-1, 0, 1, 3)),
                    mf("tv", "trimf", (0, 0, 2)),
                ),
            ),
            FuzzyInput(
                "q",
                (0, 5),
                (
                    mf("g", "gaussmf", (1, 1)),
                    mf("b", "gbellmf", (1.5, 2, 4)),
                    mf("s", "sigmf", (3, 2.5)),
                ),
            ),
            FuzzyInput(
                "r",
                (-1, 1),
                (
                    mf("sm", "smf", (-0.5, 0.5)),
                    mf("zm", "zmf", (-0.5, 0.5)),
                    mf("st", "smf", (0.3, 0.3)),
                ),
            ),
        ),
        outputs=(
            FuzzyOutput(
                "u",
                (-5, 5),
                (
                    SugenoOutputMf("c1", "constant", (-2,)),
                    SugenoOutputMf("l1", "linear", (0.5, -1, 2, 0.25)),
                ),
            ),
            FuzzyOutput(
                "v",
                (0, 1),
                (
                    SugenoOutputMf("c2", "constant", (0.7,)),
                    SugenoOutputMf("c3", "constant", (0.1,)),
                ),
            ),
        ),
        rules=(
            Rule((1, 2, 0), (1, 2)),
            Rule((2, 0, -1), (2, 0), weight=0.7),
            Rule((3, 3, 2), (0, 1), connective="or"),
            Rule((-2, 1, 3), (2, 1)),
            Rule((0, -3, 1), (1, 2), weight=0.3, connective="or"),
        ),
        and_method="min",
        or_method="probor",
    )


def test_batch_equals_one_by_one() -> None:
    system = _every_feature()
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
    system = data.draw(_systems())
    n_in = len(system.inputs)
    rows = data.draw(
        st.lists(st.lists(_finite(-12, 12), min_size=n_in, max_size=n_in), min_size=2, max_size=6)
    )
    x = np.array(rows)
    np.testing.assert_allclose(
        evaluate(system, x), np.array([evaluate(system, r) for r in x]), rtol=1e-12, atol=1e-9
    )


# ------------------------------------------------------------------ .fis files


def test_round_trip_write_read_same_outputs(tmp_path: Path) -> None:
    system = _every_feature()
    path = tmp_path / "every.fis"
    path.write_text(fis_text(system), encoding="utf-8")
    again = read_fis(path)
    assert again == system
    x = np.random.default_rng(5).uniform(-4, 6, size=(200, 3))
    np.testing.assert_allclose(evaluate(again, x), evaluate(system, x), rtol=0, atol=EXACT)
    assert [p.name for p in tmp_path.iterdir()] == ["every.fis"]  # no temporary left


def _finite(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


@st.composite
def _mfs(draw: st.DrawFn) -> MembershipFunction:
    kinds: list[MfKind] = ["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"]
    kind = draw(st.sampled_from(kinds))
    if kind in ("trimf", "trapmf"):
        p = sorted(
            draw(
                st.lists(
                    _finite(-10, 10),
                    min_size=3 + (kind == "trapmf"),
                    max_size=3 + (kind == "trapmf"),
                )
            )
        )
    elif kind in ("gaussmf", "gbellmf"):
        extra = 1 if kind == "gaussmf" else 2
        p = [
            draw(st.one_of(_finite(0.01, 5), _finite(-5, -0.01))),
            *draw(st.lists(_finite(-10, 10), min_size=extra, max_size=extra)),
        ]
    else:
        p = draw(st.lists(_finite(-10, 10), min_size=2, max_size=2))
    return MembershipFunction(draw(st.sampled_from(["A", "mf 2", "Very_Far"])), kind, tuple(p))


@st.composite
def _systems(draw: st.DrawFn) -> SugenoSystem:
    n_in = draw(st.integers(1, 3))
    n_out = draw(st.integers(1, 2))
    inputs = []
    for i in range(n_in):
        lo = draw(_finite(-10, 9))
        inputs.append(
            FuzzyInput(
                f"in{i}",
                (lo, lo + draw(_finite(0.5, 10))),
                tuple(draw(st.lists(_mfs(), min_size=1, max_size=4))),
            )
        )
    outputs = []
    for j in range(n_out):
        mfs = []
        for _ in range(draw(st.integers(1, 3))):
            if draw(st.booleans()):
                mfs.append(SugenoOutputMf("c", "constant", (draw(_finite(-100, 100)),)))
            else:
                coeffs = draw(st.lists(_finite(-10, 10), min_size=n_in + 1, max_size=n_in + 1))
                mfs.append(SugenoOutputMf("l", "linear", tuple(coeffs)))
        outputs.append(FuzzyOutput(f"out{j}", (-5, 5), tuple(mfs)))
    rules = []
    for _ in range(draw(st.integers(1, 5))):
        ante = [draw(st.integers(-len(v.mfs), len(v.mfs))) for v in inputs]
        if not any(ante):
            ante[0] = 1
        cons = [draw(st.integers(0, len(o.mfs))) for o in outputs]
        if not any(cons):
            cons[0] = 1
        rules.append(
            Rule(
                tuple(ante), tuple(cons), draw(_finite(0, 1)), draw(st.sampled_from(["and", "or"]))
            )
        )
    return SugenoSystem(
        "random",
        tuple(inputs),
        tuple(outputs),
        tuple(rules),
        and_method=draw(st.sampled_from(["min", "prod"])),
        or_method=draw(st.sampled_from(["max", "probor"])),
        defuzz=draw(st.sampled_from(["wtaver", "wtsum"])),
    )


@settings(max_examples=80, deadline=None)
@given(_systems())
def test_fis_text_round_trip_property(system: SugenoSystem) -> None:
    assert parse_fis(fis_text(system)) == system


def test_matlab_v2_file_hand_values() -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    assert [v.name for v in system.inputs] == ["dist", "angle"]
    assert system.rules[1].weight == 0.5
    assert system.rules[3].antecedent == (0, -1)
    # (1.5, 0.5): near = far = 0.25, left = 0.25, not left = 0.75
    #   speed = (0.25 * 0.2 + 0.5 * 0.25 * (0.25 * 1.5)) / (0.25 + 0.125); turn = 0.5
    # (3.5, -1): far = 1, left = 1: speed = 0.25 * 3.5, turn = -1
    # (10, 5) is clipped to (4, 1): speed = 0.25 * 4 (linear sees the clipped input), turn = 1
    x = np.array([[1.5, 0.5], [3.5, -1.0], [10.0, 5.0]])
    expected = [[0.096875 / 0.375, 0.5], [0.875, -1.0], [1.0, 1.0]]
    np.testing.assert_allclose(evaluate(system, x), expected, rtol=0, atol=EXACT)
    # written back in MATLAB's layout, it is the same file (numbers and all)
    assert fis_text(system) == (DATA / "matlab_v2_sugeno.fis").read_text()


def test_matlab_legacy_file_hand_values() -> None:
    system = read_fis(DATA / "matlab_legacy_sugeno.fis")
    assert system.inputs[0].mfs[0].params == (1.0, 2.0, -1.0)  # padding dropped
    assert system.outputs[0].mfs[1].params == (-1.0,)
    assert system.outputs[0].range == (0.0, 0.0)
    assert (system.and_method, system.or_method, system.defuzz) == ("min", "max", "wtsum")
    # (0, 0): every MF is 1/2; rule 1 (min) 0.5 * z(0, 0) = 0; rule 2 (max) 0.5 * -1
    # (1, 0.25): low = 1/17, high = 1, rising = 1/(1 + e^-1), falling = 1/(1 + e):
    #   rule 1 = min(1/17, rising) * (1 + 0.5 * 0.25); rule 2 = max(1, falling) * -1
    x = np.array([[0.0, 0.0], [1.0, 0.25]])
    expected = [[-0.5], [1.125 / 17 - 1.0]]
    np.testing.assert_allclose(evaluate(system, x), expected, rtol=0, atol=EXACT)


GOOD = (DATA / "matlab_v2_sugeno.fis").read_text()


def _edit(old: str, new: str) -> str:
    assert old in GOOD
    return GOOD.replace(old, new, 1)


@pytest.mark.parametrize(
    ("text", "line", "message"),
    [
        ("", 1, "missing [System] section"),
        (GOOD.replace("[System]", "[Sistem]"), 1, "unknown section [Sistem]"),
        (_edit("Type='sugeno'", "Type='mamdani'"), 3, "only Sugeno"),
        (
            GOOD[: GOOD.index("[Input2]")] + GOOD[GOOD.index("[Output1]") :],
            5,
            "no [Input2] section",
        ),
        (_edit("[Input2]", "[Input3]"), 21, "[Input3] but NumInputs=2"),
        (GOOD[: GOOD.index("[Rules]")], 7, "NumRules=4 but there is no [Rules] section"),
        (_edit("Range=[0 4]", "Range=[0 4x]"), 16, "bad number '4x'"),
        (_edit("Range=[0 4]", "Range=[4 0]"), 16, "min <= max"),
        (_edit("MF1='near':'trimf',[0 0 2]", "MF1='near':'trimf',[0 2]"), 18, "takes 3 parameters"),
        (_edit("MF1='near':'trimf',[0 0 2]", "MF1='near':'trimf',[2 0 4]"), 18, "a <= b <= c"),
        (
            _edit("MF1='near':'trimf'", "MF1='near':'cosmf'"),
            18,
            "unknown membership function type 'cosmf'",
        ),
        (
            _edit("MF1='near':'trimf',[0 0 2]", "MF1=near trimf 0 0 2"),
            18,
            "expected 'name':'type',[params]",
        ),
        (_edit("NumMFs=2\nMF1='near'", "NumMFs=3\nMF1='near'"), 17, "missing MF3"),
        (
            _edit("MF1='slow':'constant',[0.2]", "MF1='slow':'trimf',[0 1 2]"),
            32,
            "'constant' or 'linear'",
        ),
        (
            _edit("MF2='fast':'linear',[0.25 0 0]", "MF2='fast':'linear',[0.25 1]"),
            33,
            "takes 3 parameter",
        ),
        (
            _edit("1 0, 1 0 (1) : 1", "3 0, 1 0 (1) : 1"),
            43,
            "input 1 ('dist') has no membership function 3",
        ),
        (
            _edit("1 0, 1 0 (1) : 1", "1 0, 1 5 (1) : 1"),
            43,
            "output 2 ('turn') has no membership function 5",
        ),
        (_edit("1 0, 1 0 (1) : 1", "1 0 0, 1 0 (1) : 1"), 43, "3 antecedent indices for 2 inputs"),
        (
            _edit("1 0, 1 0 (1) : 1", "1 0, 1 0 (1.5) : 1"),
            43,
            "weight must be one number in [0, 1]",
        ),
        (_edit("1 0, 1 0 (1) : 1", "1 0, 1 0 (1) : 3"), 43, "connective must be 1 (AND) or 2 (OR)"),
        (_edit("1 0, 1 0 (1) : 1", "1.2 0, 1 0 (1) : 1"), 43, "hedges are not supported"),
        (_edit("NumRules=4", "NumRules=5"), 7, "NumRules=5 but [Rules] (line 42) has 4 rule(s)"),
        (_edit("AndMethod='prod'", "AndMethod='mymin'"), 8, "AndMethod 'mymin' is not supported"),
        (_edit("Version=2.0", "Version=3.0"), 4, "only .fis versions 1.0 and 2.0"),
        (_edit("Name='dist'", "Nme='dist'"), 15, "unknown key 'Nme' in [Input1]"),
        (_edit("NumInputs=2", "NumInputs=two"), 5, "NumInputs must be a whole number"),
    ],
)
def test_malformed_fis_names_the_line(text: str, line: int, message: str) -> None:
    with pytest.raises(InputError) as info:
        parse_fis(text, origin="bad.fis")
    assert str(info.value).startswith(f"bad.fis:{line}: "), str(info.value)
    assert message in str(info.value)


def test_variants_matlab_tolerates() -> None:
    # rule lines without the comma, without weight and connective; '#' comments; CRLF
    text = (
        GOOD.replace("1 0, 1 0 (1) : 1", "1 0 1 0")
        .replace("0 1, 0 1 (1) : 1", "0 1 0 1 (1) : 1")
        .replace("[Input1]", "# a comment\n[Input1]")
        .replace("\n", "\r\n")
    )
    assert parse_fis(text) == parse_fis(GOOD)


def test_read_fis_missing_file(tmp_path: Path) -> None:
    with pytest.raises(InputError, match="no such file"):
        read_fis(tmp_path / "absent.fis")


# ------------------------------------------------------------------ bad input


def test_evaluate_rejects_bad_shapes_and_nan() -> None:
    system = _every_feature()
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


# ------------------------------------------------------------------ CSV


def test_evaluate_csv_columns_by_name() -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    table = evaluate_csv(system, "angle,dist\n0.5,1.5\n-1,3.5\n")
    lines = table.splitlines()
    assert lines[0] == "speed,turn"
    got = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    np.testing.assert_allclose(got, [[0.096875 / 0.375, 0.5], [0.875, -1.0]], rtol=0, atol=EXACT)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "in.csv:1: empty file"),
        ("dist\n1\n", "in.csv:1: missing column 'angle'"),
        ("dist,angle,extra\n1,2,3\n", "in.csv:1: column 'extra' is not an input"),
        ("dist,angle\n", "in.csv:1: no data rows"),
        ("dist,angle\n1,x\n", "in.csv:2: column 'angle': bad number 'x'"),
        ("dist,angle\n1,2\n1\n", "in.csv:3: 1 fields, the header has 2"),
        ("dist,angle\n1,nan\n", "in.csv:2: column 'angle': nan is not finite"),
    ],
)
def test_evaluate_csv_errors(text: str, message: str) -> None:
    system = read_fis(DATA / "matlab_v2_sugeno.fis")
    with pytest.raises(InputError) as info:
        evaluate_csv(system, text, origin="in.csv")
    assert message in str(info.value)


# ------------------------------------------------------------------ ranges and the README


@pytest.mark.parametrize("value", ["[0 1e308]", "[-1e16 0]", "[-2e15 2e15]"])
def test_fis_range_beyond_float_resolution_names_file_line_and_key(value: str) -> None:
    # Range=[0 1e308] used to be read, then crash the plots (matplotlib's arange)
    with pytest.raises(InputError) as info:
        parse_fis(_edit("Range=[0 4]", f"Range={value}"), origin="big.fis")
    message = str(info.value)
    assert message.startswith("big.fis:16: [Input1] Range=" + value), message
    assert "within +-1e+15" in message


def test_fis_range_at_the_limit_is_accepted() -> None:
    system = parse_fis(_edit("Range=[0 4]", "Range=[-1e15 1e15]"))
    assert system.inputs[0].range == (-1e15, 1e15)
    with pytest.raises(InputError, match=r"input 'x': range ends must lie within \+-1e\+15"):
        FuzzyInput("x", (0, 1e308), (MembershipFunction("a", "trimf", (0, 1, 2)),))


def test_readme_fuzzy_example_runs_as_printed(capsys: pytest.CaptureFixture[str]) -> None:
    readme = (Path(__file__).resolve().parents[2] / "README.md").read_text(encoding="utf-8")
    anchor = readme.index("from firefleet.control.fuzzy import evaluate, read_fis")
    start = readme.rindex("```python\n", 0, anchor) + len("```python\n")
    code = readme[start : readme.index("```", start)]
    namespace: dict[str, object] = {}
    exec(compile(code, "README.md", "exec"), namespace)
    v_omega = namespace["v_omega"]
    assert isinstance(v_omega, np.ndarray)
    assert v_omega.shape == (2, 2)
    np.testing.assert_array_equal(namespace["one"], v_omega[0])
    assert "['D_rp', 'x_err', 'alpha']" in capsys.readouterr().out

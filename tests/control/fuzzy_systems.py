"""Fuzzy systems for the tests: one with every feature, and hypothesis strategies."""

from __future__ import annotations

from hypothesis import strategies as st

from firefleet.control.fuzzy import (
    FuzzyInput,
    FuzzyOutput,
    MembershipFunction,
    MfKind,
    Rule,
    SugenoOutputMf,
    SugenoSystem,
)


def every_feature() -> SugenoSystem:
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


def finite(lo: float, hi: float) -> st.SearchStrategy[float]:
    return st.floats(lo, hi, allow_nan=False, allow_infinity=False)


@st.composite
def membership_functions(draw: st.DrawFn) -> MembershipFunction:
    kinds: list[MfKind] = ["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"]
    kind = draw(st.sampled_from(kinds))
    if kind in ("trimf", "trapmf"):
        p = sorted(
            draw(
                st.lists(
                    finite(-10, 10),
                    min_size=3 + (kind == "trapmf"),
                    max_size=3 + (kind == "trapmf"),
                )
            )
        )
    elif kind in ("gaussmf", "gbellmf"):
        extra = 1 if kind == "gaussmf" else 2
        p = [
            draw(st.one_of(finite(0.01, 5), finite(-5, -0.01))),
            *draw(st.lists(finite(-10, 10), min_size=extra, max_size=extra)),
        ]
    else:
        p = draw(st.lists(finite(-10, 10), min_size=2, max_size=2))
    return MembershipFunction(draw(st.sampled_from(["A", "mf 2", "Very_Far"])), kind, tuple(p))


@st.composite
def systems(draw: st.DrawFn) -> SugenoSystem:
    n_in = draw(st.integers(1, 3))
    n_out = draw(st.integers(1, 2))
    inputs = []
    for i in range(n_in):
        lo = draw(finite(-10, 9))
        inputs.append(
            FuzzyInput(
                f"in{i}",
                (lo, lo + draw(finite(0.5, 10))),
                tuple(draw(st.lists(membership_functions(), min_size=1, max_size=4))),
            )
        )
    outputs = []
    for j in range(n_out):
        mfs = []
        for _ in range(draw(st.integers(1, 3))):
            if draw(st.booleans()):
                mfs.append(SugenoOutputMf("c", "constant", (draw(finite(-100, 100)),)))
            else:
                coeffs = draw(st.lists(finite(-10, 10), min_size=n_in + 1, max_size=n_in + 1))
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
            Rule(tuple(ante), tuple(cons), draw(finite(0, 1)), draw(st.sampled_from(["and", "or"])))
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

"""The compiled fuzzy engine against a NumPy reference written from MATLAB's formulas.

The engine has one definition of each membership function (the compiled scalar
``membership_one``) and one evaluation of a system (the compiled ``eval_one``), used by
``membership``, ``evaluate`` (one sample and batch) and the simulator. Here both are
compared with an independent vectorised NumPy transcription of the Fuzzy Logic
Toolbox's definitions (``trimf.m``, ``trapmf.m``, ... and ``evalfis`` for a Sugeno
system) on random parameters, points and systems, breakpoints and degenerate shapes
included.
"""

from __future__ import annotations

import numpy as np
import scipy.special
from hypothesis import given, settings
from hypothesis import strategies as st

from firefleet.control.fuzzy import MfKind, SugenoSystem, evaluate, membership
from firefleet.control.fuzzy_kernel import compile_system, eval_one
from tests.control.fuzzy_systems import finite, systems

FloatArray = np.ndarray

REL = 1e-12
"""Same closed forms in float64 (NumPy's vector ``exp``/``pow`` against libm's scalar
ones may differ in the last ulp)."""


def _ref_membership(kind: str, p: list[float], x: FloatArray) -> FloatArray:
    """MATLAB's membership functions, vectorised (the toolbox's .m files' logic)."""
    x = np.asarray(x, dtype=np.float64)
    if kind in ("trimf", "trapmf"):
        a, b, c, d = (p[0], p[1], p[1], p[2]) if kind == "trimf" else p
        with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
            up = np.where(a == b, (x >= b) * 1.0, (x - a) / (b - a))
            down = np.where(c == d, (x <= c) * 1.0, (d - x) / (d - c))
        return np.clip(np.minimum(up, down), 0.0, 1.0)
    if kind == "gaussmf":
        sigma, c = p
        return np.exp(-((x - c) ** 2) / (2.0 * sigma * sigma))
    if kind == "gbellmf":
        a, b, c = p  # gbellmf.m: 1 ./ (1 + abs((x - c) / a).^(2 * b)); 0^(-k) = Inf gives 0
        with np.errstate(over="ignore", divide="ignore"):
            return 1.0 / (1.0 + np.abs((x - c) / a) ** (2.0 * b))
    if kind == "sigmf":
        a, c = p
        return np.asarray(scipy.special.expit(a * (x - c)))
    a, b = p  # smf.m and zmf.m: two quadratic pieces meeting at the midpoint
    mid = 0.5 * (a + b)
    if a >= b:  # MATLAB: the step at the midpoint
        return ((x >= mid) if kind == "smf" else (x <= mid)) * 1.0
    with np.errstate(over="ignore"):  # np.select computes every piece everywhere
        rise = 2.0 * ((x - a) / (b - a)) ** 2  # the piece from a to the midpoint
        fall = 2.0 * ((x - b) / (b - a)) ** 2  # the piece from the midpoint to b
    if kind == "smf":
        return np.select([x <= a, x <= mid, x <= b], [0.0 * x, rise, 1.0 - fall], 1.0)
    return np.select([x <= a, x <= mid, x <= b], [1.0 + 0.0 * x, 1.0 - rise, fall], 0.0)


def _ref_evaluate(system: SugenoSystem, x: FloatArray) -> FloatArray:
    """MATLAB's evalfis for a Sugeno system, vectorised over the rows of ``x``."""
    lo = np.array([v.range[0] for v in system.inputs])
    hi = np.array([v.range[1] for v in system.inputs])
    xc = np.clip(x, lo, hi)
    n = x.shape[0]
    num = np.zeros((n, len(system.outputs)))
    den = np.zeros((n, len(system.outputs)))
    for rule in system.rules:
        w: FloatArray | None = None
        for i, a in enumerate(rule.antecedent):
            if a == 0:
                continue
            mf = system.inputs[i].mfs[abs(a) - 1]
            mu = _ref_membership(mf.kind, list(mf.params), xc[:, i])
            term = 1.0 - mu if a < 0 else mu
            if w is None:
                w = term
            elif rule.connective == "and":
                w = w * term if system.and_method == "prod" else np.minimum(w, term)
            else:
                w = np.maximum(w, term) if system.or_method == "max" else w + term - w * term
        assert w is not None
        w = w * rule.weight
        for j, c in enumerate(rule.consequent):
            if c == 0:
                continue
            omf = system.outputs[j].mfs[c - 1]
            z = omf.params[-1] + (xc @ np.array(omf.params[:-1]) if omf.kind == "linear" else 0.0)
            num[:, j] += w * z
            den[:, j] += w
    if system.defuzz == "wtsum":
        return num
    mids = np.array([0.5 * (o.range[0] + o.range[1]) for o in system.outputs])
    fired = den > 0.0
    return np.where(fired, num / np.where(fired, den, 1.0), mids)


@st.composite
def _mf_case(draw: st.DrawFn) -> tuple[MfKind, list[float], list[float]]:
    """A kind, MATLAB-valid parameters (ties allowed: a == b, c == d, a >= b for
    smf/zmf) and points: random ones plus every breakpoint exactly."""
    kind: MfKind = draw(
        st.sampled_from(["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"])
    )
    grid = st.sampled_from([-2.0, -1.0, -0.5, 0.0, 0.5, 1.0, 2.0])  # ties likely
    value = st.one_of(grid, finite(-10, 10))
    if kind in ("trimf", "trapmf"):
        n = 3 if kind == "trimf" else 4
        p = sorted(draw(st.lists(value, min_size=n, max_size=n)))
        if kind == "trapmf" and draw(st.booleans()):  # b > c: MATLAB's flat-topped triangle
            p = [p[0], p[2], p[1], p[3]]
    elif kind == "gaussmf":
        p = [draw(st.one_of(finite(0.01, 5), finite(-5, -0.01))), draw(value)]
    elif kind == "gbellmf":
        a = draw(st.one_of(finite(0.01, 5), finite(-5, -0.01)))
        p = [a, draw(st.one_of(grid, finite(-4, 4))), draw(value)]
    else:  # sigmf, smf, zmf: any two numbers (smf/zmf with a >= b are steps)
        p = draw(st.lists(value, min_size=2, max_size=2))
    points = draw(st.lists(value, min_size=1, max_size=20))
    mids = [0.5 * (p[0] + p[1])] if kind in ("smf", "zmf") else []
    return kind, p, points + p + mids


@settings(max_examples=400, deadline=None)
@given(_mf_case())
def test_compiled_membership_equals_numpy_reference(
    case: tuple[MfKind, list[float], list[float]],
) -> None:
    kind, p, points = case
    x = np.array(points)
    ours = membership(kind, p, x)
    ref = _ref_membership(kind, p, x)
    assert np.all((ours >= 0.0) & (ours <= 1.0))
    np.testing.assert_allclose(ours, ref, rtol=REL, atol=1e-300)


def test_compiled_membership_breakpoints_exactly() -> None:
    """The degenerate shapes at their breakpoints, value by value (MATLAB's rules)."""
    cases: list[tuple[MfKind, list[float], list[float], list[float]]] = [
        ("trimf", [1, 1, 3], [1, 1 - 1e-12, 3], [1, 0, 0]),  # a == b: 1 at the shoulder
        ("trimf", [1, 3, 3], [3, 3 + 1e-12, 1], [1, 0, 0]),  # b == c
        ("trimf", [2, 2, 2], [2, 1.999, 2.001], [1, 0, 0]),  # a == b == c
        ("trapmf", [0, 0, 2, 2], [0, 2, -1e-12, 2 + 1e-12], [1, 1, 0, 0]),
        ("trapmf", [0, 1, 1, 2], [1, 0.5, 1.5], [1, 0.5, 0.5]),  # b == c: a triangle
        ("smf", [1, 1], [1, 1 - 1e-12], [1, 0]),  # a == b: the step at the midpoint
        ("zmf", [1, 1], [1, 1 + 1e-12], [1, 0]),
        ("smf", [0, 2], [0, 1, 2], [0, 0.5, 1]),
        ("zmf", [0, 2], [0, 1, 2], [1, 0.5, 0]),
        ("gbellmf", [1, -2, 0], [0, 1], [0, 0.5]),  # b < 0: 0 at the centre
        ("gbellmf", [1e-3, 400, 0], [5.0], [0.0]),  # |r|^(2b) beyond 1e308: 0, no NaN
        ("sigmf", [-1000, 0], [1, -1], [0, 1]),
    ]
    for kind, p, x, expected in cases:
        np.testing.assert_array_equal(membership(kind, p, x), expected, err_msg=f"{kind} {p}")
        np.testing.assert_array_equal(_ref_membership(kind, p, np.array(x)), expected)


@settings(max_examples=80, deadline=None)
@given(st.data())
def test_evaluate_equals_numpy_reference_random_systems(data: st.DataObject) -> None:
    system = data.draw(systems())
    n_in = len(system.inputs)
    rows = data.draw(
        st.lists(st.lists(finite(-12, 12), min_size=n_in, max_size=n_in), min_size=1, max_size=8)
    )
    x = np.array(rows)
    batch = evaluate(system, x)
    np.testing.assert_allclose(batch, _ref_evaluate(system, x), rtol=1e-9, atol=1e-9)
    # one sample at a time, and the simulator's inlined kernel, give the same bits
    singles = np.array([evaluate(system, row) for row in x])
    np.testing.assert_array_equal(singles, batch)
    t = compile_system(system)
    work = np.empty(n_in + t.mf_kind.shape[0] + 2 * len(system.outputs))
    for row, expected in zip(x, batch, strict=True):
        out = np.empty(len(system.outputs))
        eval_one(row, *t, out, work)
        np.testing.assert_array_equal(out, expected)

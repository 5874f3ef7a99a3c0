"""Takagi-Sugeno fuzzy inference, vectorised over a team, with MATLAB ``.fis`` files.

The deliverable's high-level controller is a Takagi-Sugeno system designed in MATLAB's
Fuzzy Logic Toolbox (section 2.5.1; eq. 12; rule base of Table 1, section 2.6.2.7).
This module evaluates such systems exactly as the toolbox does, for one robot or a
whole team in one call, and reads and writes the toolbox's ``.fis`` text files so a
controller designed there loads as it is and ours opens there.

What a system expresses (MATLAB semantics throughout):

* membership functions ``trimf``, ``trapmf``, ``gaussmf``, ``gbellmf``, ``sigmf``,
  ``smf``, ``zmf`` with MATLAB's parameter order and its degenerate cases
  (:func:`membership`);
* rules over any subset of the inputs (index 0 = input not used), negated antecedents
  (negative index = NOT, ``1 - mu``), a weight in [0, 1], AND or OR connective;
* AND by ``min`` or ``prod``, OR by ``max`` or ``probor`` (``a + b - a b``);
* zero-order (constant) and first-order (linear) consequents;
* ``wtaver`` (weighted average) or ``wtsum`` (weighted sum) output.

Evaluation (:func:`evaluate`), per sample and per output ``j``::

    x      <- clip(x, input ranges)                              (MATLAB clips too)
    w_r    =  weight_r * AND/OR over used inputs of mu(x_i) (or 1 - mu for NOT)
    z_rj   =  c_rj  (constant)   or   p_rj . x + q_rj  (linear, MATLAB order)
    y_j    =  sum_r w_r z_rj / sum_r w_r     (wtaver; rules with consequent 0 skipped)
           =  sum_r w_r z_rj                  (wtsum)

When no rule fires for an output under ``wtaver`` (``sum w_r = 0``) the output is the
midpoint of its range, as MATLAB's ``evalfis`` does (it also warns; we log nothing per
sample). The implication (``ImpMethod``) and aggregation (``AggMethod``) methods of a
``.fis`` file play no part in a Sugeno system's output; MATLAB ignores them and so do
we (they are read, and written as ``prod`` and ``sum``).

Speed. A system compiles once (cached on the frozen object) into index and parameter
arrays. A batch ``(N, n_inputs)`` is evaluated in one vectorised pass: membership
values of every membership function used by a rule, grouped by shape, then the rules'
firing strengths by gathering those values, then one matrix product for the outputs.
A single sample (``(n_inputs,)`` or ``(1, n_inputs)``) takes a scalar path on Python
floats with the same arithmetic, which avoids numpy's per-call overhead on tiny
arrays (about 10x cheaper at N = 1); the tests check both paths agree.

References
----------
MathWorks, Fuzzy Logic Toolbox User's Guide: ``trimf``, ``trapmf``, ``gaussmf``,
``gbellmf``, ``sigmf``, ``smf``, ``zmf``, ``evalfis``, ``readfis``, ``writefis``.
T. Takagi and M. Sugeno, "Fuzzy identification of systems and its applications to
modeling and control", IEEE Trans. SMC 15(1), 1985.
"""

from __future__ import annotations

import csv
import functools
import io
import logging
import math
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, NoReturn, get_args

import numpy as np
import scipy.special
from numpy.typing import ArrayLike, NDArray

from firefleet.errors import InputError
from firefleet.outputs import write_text_atomic

__all__ = [
    "FuzzyInput",
    "FuzzyOutput",
    "MembershipFunction",
    "MfKind",
    "Rule",
    "SugenoOutputMf",
    "SugenoSystem",
    "evaluate",
    "evaluate_csv",
    "evaluate_csv_file",
    "fis_text",
    "membership",
    "parse_fis",
    "read_fis",
    "write_fis",
]

logger = logging.getLogger(__name__)

FloatArray = NDArray[np.float64]

MfKind = Literal["trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"]
"""Input membership function shapes (MATLAB names)."""

_MF_KINDS: tuple[str, ...] = get_args(MfKind)
_N_PARAMS: dict[str, int] = {
    "trimf": 3,
    "trapmf": 4,
    "gaussmf": 2,
    "gbellmf": 3,
    "sigmf": 2,
    "smf": 2,
    "zmf": 2,
}
_PARAM_NAMES: dict[str, str] = {
    "trimf": "[a b c]",
    "trapmf": "[a b c d]",
    "gaussmf": "[sigma c]",
    "gbellmf": "[a b c]",
    "sigmf": "[a c]",
    "smf": "[a b]",
    "zmf": "[a b]",
}
_AND_METHODS = ("min", "prod")
_OR_METHODS = ("max", "probor")
_DEFUZZ_METHODS = ("wtaver", "wtsum")


# ------------------------------------------------------------------ membership functions


def _check_mf_params(kind: str, params: Sequence[float], where: str) -> tuple[float, ...]:
    """Validate ``params`` for ``kind`` as MATLAB does; returns them as floats."""
    if kind not in _N_PARAMS:
        raise InputError(
            f"{where}: unknown membership function type {kind!r}; "
            f"expected one of {', '.join(_MF_KINDS)}"
        )
    try:
        values = tuple(float(p) for p in params)
    except (TypeError, ValueError):
        raise InputError(f"{where}: {kind} parameters must be numbers, got {params!r}") from None
    n = _N_PARAMS[kind]
    if len(values) != n:
        raise InputError(
            f"{where}: {kind} takes {n} parameters {_PARAM_NAMES[kind]}, got {len(values)}"
        )
    if not all(math.isfinite(v) for v in values):
        raise InputError(f"{where}: {kind} parameters must be finite, got {list(values)}")
    if kind == "trimf":
        a, b, c = values
        if not a <= b <= c:
            raise InputError(f"{where}: trimf [a b c] needs a <= b <= c, got {list(values)}")
    elif kind == "trapmf":
        a, b, c, d = values
        if not (a <= b and c <= d):
            raise InputError(
                f"{where}: trapmf [a b c d] needs a <= b and c <= d, got {list(values)}"
            )
    elif kind == "gaussmf" and values[0] == 0.0:
        raise InputError(f"{where}: gaussmf [sigma c] needs sigma != 0")
    elif kind == "gbellmf" and values[0] == 0.0:
        raise InputError(f"{where}: gbellmf [a b c] needs a != 0")
    return values


def _ramp_up(x: FloatArray, a: FloatArray, b: FloatArray, steep: FloatArray | None) -> FloatArray:
    """``(x - a) / (b - a)``, or the step ``x >= b`` where ``a == b`` (``steep``)."""
    if steep is None:
        return (x - a) / (b - a)
    return np.where(steep, (x >= b).astype(np.float64), (x - a) / np.where(steep, 1.0, b - a))


def _ramp_down(x: FloatArray, c: FloatArray, d: FloatArray, steep: FloatArray | None) -> FloatArray:
    """``(d - x) / (d - c)``, or the step ``x <= c`` where ``c == d`` (``steep``)."""
    if steep is None:
        return (d - x) / (d - c)
    return np.where(steep, (x <= c).astype(np.float64), (d - x) / np.where(steep, 1.0, d - c))


def _trap(x: FloatArray, p: FloatArray) -> FloatArray:
    """MATLAB trapmf, p = (a, b, c, d) on the last axis; trimf is (a, b, b, c)."""
    a, b, c, d = p[..., 0], p[..., 1], p[..., 2], p[..., 3]
    up = _ramp_up(x, a, b, a == b if np.any(a == b) else None)
    down = _ramp_down(x, c, d, c == d if np.any(c == d) else None)
    return np.clip(np.minimum(up, down), 0.0, 1.0)


def _gauss(x: FloatArray, p: FloatArray) -> FloatArray:
    sigma, c = p[..., 0], p[..., 1]
    return np.exp(-((x - c) ** 2) / (2.0 * sigma * sigma))


def _gbell(x: FloatArray, p: FloatArray) -> FloatArray:
    a, b, c = p[..., 0], p[..., 1], p[..., 2]
    t = ((x - c) / a) ** 2
    with np.errstate(over="ignore"):  # t**b beyond 1e308 is inf: the degree is 0
        if np.any(b < 0):  # MATLAB: 0 where (x - c) / a == 0 and b < 0 (no 1 / 0)
            hit = (t == 0.0) & (b < 0)
            return np.where(hit, 0.0, 1.0 / (1.0 + np.where(hit, 1.0, t) ** b))
        return 1.0 / (1.0 + t**b)


def _sig(x: FloatArray, p: FloatArray) -> FloatArray:
    a, c = p[..., 0], p[..., 1]
    result: FloatArray = scipy.special.expit(a * (x - c))  # 1 / (1 + exp(-a (x - c)))
    return result


def _s_or_z(x: FloatArray, p: FloatArray, *, s_shape: bool) -> FloatArray:
    """MATLAB smf / zmf; where a >= b, the step at the midpoint (x >= m, x <= m)."""
    a, b = p[..., 0], p[..., 1]
    flat = a >= b
    width = np.where(flat, 1.0, b - a)
    t = np.clip((x - a) / width, 0.0, 1.0)  # rising fraction
    u = np.clip((b - x) / width, 0.0, 1.0)  # remaining fraction
    mid = 0.5 * (a + b)
    first = x <= mid
    if s_shape:
        y = np.where(first, 2.0 * t * t, 1.0 - 2.0 * u * u)
        step = x >= mid
    else:
        y = np.where(first, 1.0 - 2.0 * t * t, 2.0 * u * u)
        step = x <= mid
    if np.any(flat):
        y = np.where(flat, step.astype(np.float64), y)
    return y


def _s(x: FloatArray, p: FloatArray) -> FloatArray:
    return _s_or_z(x, p, s_shape=True)


def _z(x: FloatArray, p: FloatArray) -> FloatArray:
    return _s_or_z(x, p, s_shape=False)


_Vectorised = Callable[[FloatArray, FloatArray], FloatArray]

# trimf and trapmf share one evaluator: trimf [a b c] is trapmf [a b b c] exactly,
# degenerate shoulders included (checked against MATLAB's trimf code in the tests).
_GROUP: dict[str, str] = {
    "trimf": "trap",
    "trapmf": "trap",
    "gaussmf": "gauss",
    "gbellmf": "gbell",
    "sigmf": "sig",
    "smf": "s",
    "zmf": "z",
}
_GROUP_FN: dict[str, _Vectorised] = {
    "trap": _trap,
    "gauss": _gauss,
    "gbell": _gbell,
    "sig": _sig,
    "s": _s,
    "z": _z,
}


def _group_params(kind: str, params: tuple[float, ...]) -> tuple[float, ...]:
    if kind == "trimf":
        a, b, c = params
        return (a, b, b, c)
    return params


def membership(kind: MfKind, params: Sequence[float], x: ArrayLike) -> FloatArray:
    """Membership degrees of ``x`` in one MATLAB membership function.

    Parameters
    ----------
    kind : {"trimf", "trapmf", "gaussmf", "gbellmf", "sigmf", "smf", "zmf"}
        The shape, with MATLAB's parameters:

        * ``trimf [a b c]``: triangle, feet a and c, peak b; a <= b <= c;
        * ``trapmf [a b c d]``: trapezoid ``min((x - a)/(b - a), 1, (d - x)/(d - c))``
          clipped to [0, 1]; a <= b, c <= d (b > c gives MATLAB's flat-topped
          triangle below 1);
        * ``gaussmf [sigma c]``: ``exp(-(x - c)^2 / (2 sigma^2))``, sigma != 0;
        * ``gbellmf [a b c]``: ``1 / (1 + |(x - c)/a|^(2 b))``, a != 0;
        * ``sigmf [a c]``: ``1 / (1 + exp(-a (x - c)))``;
        * ``smf [a b]``, ``zmf [a b]``: quadratic S and Z splines from a to b; for
          a >= b MATLAB's step at the midpoint (``x >= (a + b)/2``, ``x <= ...``).

        A vertical side (a == b or c == d in trimf and trapmf) is MATLAB's: the
        membership is 1 at the shoulder itself.
    params : sequence of float
        The parameters, in MATLAB's order.
    x : array_like
        Points, any shape.

    Returns
    -------
    ndarray of float64
        Degrees in [0, 1], the shape of ``x``.

    Raises
    ------
    InputError
        Unknown ``kind``, wrong number of parameters, parameters MATLAB rejects, or
        non-finite ``x``.
    """
    values = _check_mf_params(kind, params, "membership")
    arr = np.asarray(x, dtype=np.float64)
    if not np.all(np.isfinite(arr)):
        raise InputError("membership: x must be finite, got non-finite values")
    p = np.asarray(_group_params(kind, values), dtype=np.float64)
    return np.asarray(_GROUP_FN[_GROUP[kind]](arr, p), dtype=np.float64)


# ------------------------------------------------------------------ system description


def _check_name(name: object, where: str) -> None:
    if not isinstance(name, str) or not name.strip():
        raise InputError(f"{where}: name must be a non-empty string, got {name!r}")
    if any(c in name for c in "'\n\r"):
        raise InputError(f"{where}: name {name!r} must not contain quotes or line breaks")


def _check_range(rng: object, where: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in rng)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(f"{where}: range must be two numbers (min, max), got {rng!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        raise InputError(f"{where}: range must be finite with min <= max, got [{lo:g} {hi:g}]")
    return lo, hi


@dataclass(frozen=True)
class MembershipFunction:
    """One membership function of an input variable.

    Attributes
    ----------
    name : str
        Its linguistic label (``"VeryClose"``).
    kind : MfKind
        Its shape (see :func:`membership`).
    params : tuple of float
        Its parameters, in MATLAB's order, in the input's units.
    """

    name: str
    kind: MfKind
    params: tuple[float, ...]

    def __post_init__(self) -> None:
        _check_name(self.name, "membership function")
        where = f"membership function {self.name!r}"
        object.__setattr__(self, "params", _check_mf_params(self.kind, self.params, where))


@dataclass(frozen=True)
class FuzzyInput:
    """An input variable.

    Attributes
    ----------
    name : str
        Its name (a column name in ``firefleet fis --eval``); a unit may follow in
        brackets, ``"D_rp [m]"``, and is shown on plots.
    range : tuple of float
        (min, max) of the variable; inputs outside are clipped to it.
    mfs : tuple of MembershipFunction
        Its membership functions; rules refer to them by 1-based position.
    """

    name: str
    range: tuple[float, float]
    mfs: tuple[MembershipFunction, ...]

    def __post_init__(self) -> None:
        _check_name(self.name, "input")
        object.__setattr__(self, "range", _check_range(self.range, f"input {self.name!r}"))
        object.__setattr__(self, "mfs", tuple(self.mfs))
        if not self.mfs or not all(isinstance(m, MembershipFunction) for m in self.mfs):
            raise InputError(
                f"input {self.name!r}: mfs must be a non-empty sequence of MembershipFunction"
            )


@dataclass(frozen=True)
class SugenoOutputMf:
    """One consequent of a Sugeno output.

    Attributes
    ----------
    name : str
        Its label (``"VerySlow"``).
    kind : {"constant", "linear"}
        Zero order (one number) or first order.
    params : tuple of float
        ``(c,)`` for a constant; for linear, one coefficient per input then the
        constant, ``z = p_1 x_1 + ... + p_n x_n + q`` (MATLAB's order).
    """

    name: str
    kind: Literal["constant", "linear"]
    params: tuple[float, ...]

    def __post_init__(self) -> None:
        _check_name(self.name, "output membership function")
        where = f"output membership function {self.name!r}"
        if self.kind not in ("constant", "linear"):
            raise InputError(f"{where}: kind must be 'constant' or 'linear', got {self.kind!r}")
        try:
            values = tuple(float(p) for p in self.params)
        except (TypeError, ValueError):
            raise InputError(f"{where}: parameters must be numbers, got {self.params!r}") from None
        if not all(math.isfinite(v) for v in values):
            raise InputError(f"{where}: parameters must be finite, got {list(values)}")
        if self.kind == "constant" and len(values) != 1:
            raise InputError(f"{where}: constant takes 1 parameter, got {len(values)}")
        if self.kind == "linear" and len(values) < 2:
            raise InputError(f"{where}: linear takes n_inputs + 1 parameters, got {len(values)}")
        object.__setattr__(self, "params", values)


@dataclass(frozen=True)
class FuzzyOutput:
    """An output variable of a Sugeno system.

    Attributes
    ----------
    name : str
        Its name (a unit may follow in brackets, ``"v [m/s]"``).
    range : tuple of float
        (min, max); its midpoint is the output when no rule fires (``wtaver``).
        Sugeno outputs are not clipped to it (MATLAB does not clip them either).
    mfs : tuple of SugenoOutputMf
        Its consequents; rules refer to them by 1-based position.
    """

    name: str
    range: tuple[float, float]
    mfs: tuple[SugenoOutputMf, ...]

    def __post_init__(self) -> None:
        _check_name(self.name, "output")
        object.__setattr__(self, "range", _check_range(self.range, f"output {self.name!r}"))
        object.__setattr__(self, "mfs", tuple(self.mfs))
        if not self.mfs or not all(isinstance(m, SugenoOutputMf) for m in self.mfs):
            raise InputError(
                f"output {self.name!r}: mfs must be a non-empty sequence of SugenoOutputMf"
            )


@dataclass(frozen=True)
class Rule:
    """One rule, in MATLAB's indexed form (a ``[Rules]`` line of a ``.fis`` file).

    Attributes
    ----------
    antecedent : tuple of int
        Per input, the 1-based index of its membership function; 0 = input not used;
        negative = NOT (``1 - mu``).
    consequent : tuple of int
        Per output, the 1-based index of its consequent; 0 = rule not used for it.
    weight : float
        In [0, 1]; multiplies the firing strength.
    connective : {"and", "or"}
        How the antecedent's terms combine.
    """

    antecedent: tuple[int, ...]
    consequent: tuple[int, ...]
    weight: float = 1.0
    connective: Literal["and", "or"] = "and"

    def __post_init__(self) -> None:
        for name in ("antecedent", "consequent"):
            values = getattr(self, name)
            try:
                ints = tuple(int(v) for v in values)
            except (TypeError, ValueError):
                raise InputError(f"rule {name} must be integers, got {values!r}") from None
            if any(i != v for i, v in zip(ints, values, strict=True)):
                raise InputError(f"rule {name} must be integers, got {list(values)}")
            object.__setattr__(self, name, ints)
        weight = float(self.weight)
        if not (math.isfinite(weight) and 0.0 <= weight <= 1.0):
            raise InputError(f"rule weight must be in [0, 1], got {self.weight}")
        object.__setattr__(self, "weight", weight)
        if self.connective not in ("and", "or"):
            raise InputError(f"rule connective must be 'and' or 'or', got {self.connective!r}")
        if not any(self.antecedent):
            raise InputError("rule antecedent uses no input (all indices are 0)")
        if not any(self.consequent):
            raise InputError("rule consequent sets no output (all indices are 0)")
        if any(c < 0 for c in self.consequent):
            raise InputError(
                f"rule consequent {list(self.consequent)}: negative (NOT) consequents have no "
                "meaning in a Sugeno system"
            )


@dataclass(frozen=True)
class SugenoSystem:
    """A Takagi-Sugeno fuzzy inference system (MATLAB's ``sugfis``).

    Attributes
    ----------
    name : str
        Its name.
    inputs, outputs : tuple
        The variables, in order (a rule's indices follow this order).
    rules : tuple of Rule
        The rule base.
    and_method : {"min", "prod"}
        AND of a rule's terms.
    or_method : {"max", "probor"}
        OR of a rule's terms (``probor``: ``a + b - a b``, applied left to right).
    defuzz : {"wtaver", "wtsum"}
        Weighted average or weighted sum of the rules' outputs.

    Notes
    -----
    Validated on construction (:class:`~firefleet.errors.InputError` naming the
    field): every rule has one index per input and per output, in range; linear
    consequents have ``n_inputs + 1`` parameters; variable names are unique.
    The compiled evaluation form is built on first use and cached on the object.
    """

    name: str
    inputs: tuple[FuzzyInput, ...]
    outputs: tuple[FuzzyOutput, ...]
    rules: tuple[Rule, ...]
    and_method: Literal["min", "prod"] = "prod"
    or_method: Literal["max", "probor"] = "probor"
    defuzz: Literal["wtaver", "wtsum"] = "wtaver"

    def __post_init__(self) -> None:
        _check_name(self.name, "system")
        for attr in ("inputs", "outputs", "rules"):
            object.__setattr__(self, attr, tuple(getattr(self, attr)))
        if not self.inputs or not all(isinstance(v, FuzzyInput) for v in self.inputs):
            raise InputError("system.inputs must be a non-empty sequence of FuzzyInput")
        if not self.outputs or not all(isinstance(v, FuzzyOutput) for v in self.outputs):
            raise InputError("system.outputs must be a non-empty sequence of FuzzyOutput")
        if not self.rules or not all(isinstance(r, Rule) for r in self.rules):
            raise InputError("system.rules must be a non-empty sequence of Rule")
        for field_name, allowed in (
            ("and_method", _AND_METHODS),
            ("or_method", _OR_METHODS),
            ("defuzz", _DEFUZZ_METHODS),
        ):
            value = getattr(self, field_name)
            if value not in allowed:
                raise InputError(
                    f"system.{field_name} must be one of {', '.join(allowed)}, got {value!r}"
                )
        for kind, variables in (("input", self.inputs), ("output", self.outputs)):
            names = [v.name for v in variables]
            dup = sorted({n for n in names if names.count(n) > 1})
            if dup:
                raise InputError(f"system: {kind} names must be unique, repeated: {dup}")
        n_in = len(self.inputs)
        for out in self.outputs:
            for mf in out.mfs:
                if mf.kind == "linear" and len(mf.params) != n_in + 1:
                    raise InputError(
                        f"output {out.name!r} membership function {mf.name!r}: linear takes "
                        f"{n_in + 1} parameters (one per input, then the constant), "
                        f"got {len(mf.params)}"
                    )
        for k, rule in enumerate(self.rules, start=1):
            _check_rule(rule, k, self.inputs, self.outputs)

    @functools.cached_property
    def _compiled(self) -> _Compiled:
        return _compile(self)


def _check_rule(
    rule: Rule, k: int, inputs: tuple[FuzzyInput, ...], outputs: tuple[FuzzyOutput, ...]
) -> None:
    if len(rule.antecedent) != len(inputs):
        raise InputError(
            f"rules[{k}].antecedent: {len(rule.antecedent)} indices for {len(inputs)} inputs"
        )
    if len(rule.consequent) != len(outputs):
        raise InputError(
            f"rules[{k}].consequent: {len(rule.consequent)} indices for {len(outputs)} outputs"
        )
    for idx, var in zip(rule.antecedent, inputs, strict=True):
        if abs(idx) > len(var.mfs):
            raise InputError(
                f"rules[{k}].antecedent: index {idx} out of range for input {var.name!r} "
                f"(1..{len(var.mfs)}, 0 = not used, negative = NOT)"
            )
    for idx, out in zip(rule.consequent, outputs, strict=True):
        if idx > len(out.mfs):
            raise InputError(
                f"rules[{k}].consequent: index {idx} out of range for output {out.name!r} "
                f"(1..{len(out.mfs)}, 0 = not used)"
            )


# ------------------------------------------------------------------ compiled form

_Scalar = Callable[[float], float]


def _scalar_mf(kind: str, p: tuple[float, ...]) -> _Scalar:
    """A float -> float closure with exactly the arithmetic of the vectorised form."""
    if kind in ("trimf", "trapmf"):
        a, b, c, d = _group_params(kind, p)

        def trap(x: float) -> float:
            up = (1.0 if x >= b else 0.0) if a == b else (x - a) / (b - a)
            down = (1.0 if x <= c else 0.0) if c == d else (d - x) / (d - c)
            m = up if up < down else down
            return 0.0 if m < 0.0 else (1.0 if m > 1.0 else m)

        return trap
    if kind == "gaussmf":
        sigma, c = p
        two_s2 = 2.0 * sigma * sigma
        return lambda x: math.exp(-((x - c) ** 2) / two_s2)
    if kind == "gbellmf":
        a, b, c = p

        def gbell(x: float) -> float:
            t = ((x - c) / a) ** 2
            if t == 0.0 and b < 0:
                return 0.0
            try:
                return 1.0 / (1.0 + float(t**b))
            except OverflowError:  # |(x - c)/a|^(2b) beyond 1e308: the degree is 0
                return 0.0

        return gbell
    if kind == "sigmf":
        a, c = p
        expit = scipy.special.expit
        return lambda x: float(expit(a * (x - c)))
    a, b = p
    mid = 0.5 * (a + b)
    s_shape = kind == "smf"
    if a >= b:
        if s_shape:
            return lambda x: 1.0 if x >= mid else 0.0
        return lambda x: 1.0 if x <= mid else 0.0
    w = b - a

    def sz(x: float) -> float:
        t = min(max((x - a) / w, 0.0), 1.0)
        u = min(max((b - x) / w, 0.0), 1.0)
        if s_shape:
            return 2.0 * t * t if x <= mid else 1.0 - 2.0 * u * u
        return 1.0 - 2.0 * t * t if x <= mid else 2.0 * u * u

    return sz


@dataclass(frozen=True)
class _Group:
    """Membership functions of one shape, evaluated together."""

    fn: _Vectorised
    cols: NDArray[np.intp]  # input column of each (M,)
    params: FloatArray  # (M, n_params)
    start: int  # first slot in the membership table


@dataclass(frozen=True)
class _Compiled:
    """Index and parameter arrays of a system, built once (see :func:`_compile`)."""

    lo: FloatArray  # (n_in,)
    hi: FloatArray
    lo_list: tuple[float, ...]
    hi_list: tuple[float, ...]
    n_in: int
    n_out: int
    n_slots: int  # used membership functions
    groups: tuple[_Group, ...]
    negated: NDArray[np.intp]  # slots used under NOT; complement at n_slots + 2 + k
    width: int  # table columns: slots, one, zero, complements
    # rules by connective: column indices into the table, (K, R_c), padded with the
    # neutral column (one for AND, zero for OR); and their positions in W
    and_idx: NDArray[np.intp]
    and_rules: NDArray[np.intp]
    or_idx: NDArray[np.intp]
    or_rules: NDArray[np.intp]
    weights: FloatArray  # (R,)
    n_rules: int
    const_mat: FloatArray  # (R, 2 n_out): constant parts then masks
    linear_mat: FloatArray | None  # (R, n_out * n_in) coefficients, None if all constant
    midpoints: FloatArray  # (n_out,)
    defuzz: str
    and_method: str
    or_method: str
    # scalar path
    scalar_mfs: tuple[tuple[int, _Scalar], ...]  # (input column, closure) per slot
    scalar_rules: tuple[tuple[float, bool, tuple[int, ...]], ...]  # weight, is_and, table cols
    scalar_outputs: tuple[tuple[tuple[int, float, tuple[float, ...] | None], ...], ...]
    midpoint_list: tuple[float, ...]
    table_has_complements: bool = field(default=False)


def _compile(system: SugenoSystem) -> _Compiled:
    """Flatten a validated system into arrays for :func:`evaluate`."""
    n_in, n_out = len(system.inputs), len(system.outputs)
    # slots: the (input, mf) pairs that some rule uses, grouped by shape
    used = sorted({(i, abs(a) - 1) for r in system.rules for i, a in enumerate(r.antecedent) if a})
    by_group: dict[str, list[tuple[int, int]]] = {}
    for i, m in used:
        by_group.setdefault(_GROUP[system.inputs[i].mfs[m].kind], []).append((i, m))
    slot: dict[tuple[int, int], int] = {}
    groups: list[_Group] = []
    scalar_mfs: list[tuple[int, _Scalar]] = []
    for gname, pairs in by_group.items():
        start = len(slot)
        rows = []
        for i, m in pairs:
            slot[(i, m)] = len(slot)
            mf = system.inputs[i].mfs[m]
            rows.append(_group_params(mf.kind, mf.params))
            scalar_mfs.append((i, _scalar_mf(mf.kind, mf.params)))
        groups.append(
            _Group(
                fn=_GROUP_FN[gname],
                cols=np.array([i for i, _ in pairs], dtype=np.intp),
                params=np.array(rows, dtype=np.float64),
                start=start,
            )
        )
    n_slots = len(slot)
    one_col, zero_col = n_slots, n_slots + 1
    neg_slots = sorted(
        {slot[(i, -a - 1)] for r in system.rules for i, a in enumerate(r.antecedent) if a < 0}
    )
    comp_col = {s: n_slots + 2 + k for k, s in enumerate(neg_slots)}

    def columns(rule: Rule) -> list[int]:
        cols = []
        for i, a in enumerate(rule.antecedent):
            if a > 0:
                cols.append(slot[(i, a - 1)])
            elif a < 0:
                cols.append(comp_col[slot[(i, -a - 1)]])
        return cols

    def index_block(rule_ids: list[int], neutral: int) -> NDArray[np.intp]:
        lists = [columns(system.rules[r]) for r in rule_ids]
        k = max((len(c) for c in lists), default=0)
        block = np.full((k, len(lists)), neutral, dtype=np.intp)
        for j, cols in enumerate(lists):
            block[: len(cols), j] = cols
        return block

    and_ids = [k for k, r in enumerate(system.rules) if r.connective == "and"]
    or_ids = [k for k, r in enumerate(system.rules) if r.connective == "or"]
    n_rules = len(system.rules)
    const_mat = np.zeros((n_rules, 2 * n_out))
    linear = np.zeros((n_rules, n_out, n_in))
    any_linear = False
    scalar_outputs: list[list[tuple[int, float, tuple[float, ...] | None]]] = [
        [] for _ in range(n_out)
    ]
    for r, rule in enumerate(system.rules):
        for j, c in enumerate(rule.consequent):
            if c == 0:
                continue
            omf = system.outputs[j].mfs[c - 1]
            const_mat[r, j] = omf.params[-1]
            const_mat[r, n_out + j] = 1.0
            coeffs: tuple[float, ...] | None = None
            if omf.kind == "linear":
                linear[r, j, :] = omf.params[:-1]
                any_linear = True
                coeffs = omf.params[:-1]
            scalar_outputs[j].append((r, omf.params[-1], coeffs))
    lo = np.array([v.range[0] for v in system.inputs])
    hi = np.array([v.range[1] for v in system.inputs])
    mids = np.array([0.5 * (o.range[0] + o.range[1]) for o in system.outputs])
    return _Compiled(
        lo=lo,
        hi=hi,
        lo_list=tuple(lo.tolist()),
        hi_list=tuple(hi.tolist()),
        n_in=n_in,
        n_out=n_out,
        n_slots=n_slots,
        groups=tuple(groups),
        negated=np.array(neg_slots, dtype=np.intp),
        width=n_slots + 2 + len(neg_slots),
        and_idx=index_block(and_ids, one_col),
        and_rules=np.array(and_ids, dtype=np.intp),
        or_idx=index_block(or_ids, zero_col),
        or_rules=np.array(or_ids, dtype=np.intp),
        weights=np.array([r.weight for r in system.rules]),
        n_rules=n_rules,
        const_mat=const_mat,
        linear_mat=linear.reshape(n_rules, n_out * n_in) if any_linear else None,
        midpoints=mids,
        defuzz=system.defuzz,
        and_method=system.and_method,
        or_method=system.or_method,
        scalar_mfs=tuple(scalar_mfs),
        scalar_rules=tuple(
            (r.weight, r.connective == "and", tuple(columns(r))) for r in system.rules
        ),
        scalar_outputs=tuple(tuple(o) for o in scalar_outputs),
        midpoint_list=tuple(mids.tolist()),
        table_has_complements=bool(neg_slots),
    )


# ------------------------------------------------------------------ evaluation


def _combine(table: FloatArray, idx: NDArray[np.intp], method: str, *, conj: bool) -> FloatArray:
    """Firing strengths (N, R_c) of rules whose term columns are ``idx`` (K, R_c)."""
    acc = table[:, idx[0]]
    for k in range(1, idx.shape[0]):
        term = table[:, idx[k]]
        if conj:
            acc = acc * term if method == "prod" else np.minimum(acc, term)
        elif method == "max":
            acc = np.maximum(acc, term)
        else:  # probor, left to right as MATLAB's probor
            acc = acc + term - acc * term
    return acc


def _evaluate_batch(c: _Compiled, x: FloatArray) -> FloatArray:
    n = x.shape[0]
    xc = np.minimum(np.maximum(x, c.lo), c.hi)
    table = np.empty((n, c.width))
    for g in c.groups:
        table[:, g.start : g.start + g.cols.size] = g.fn(xc[:, g.cols], g.params)
    table[:, c.n_slots] = 1.0
    table[:, c.n_slots + 1] = 0.0
    if c.table_has_complements:
        table[:, c.n_slots + 2 :] = 1.0 - table[:, c.negated]
    if c.or_rules.size == 0:
        w = _combine(table, c.and_idx, c.and_method, conj=True)
    elif c.and_rules.size == 0:
        w = _combine(table, c.or_idx, c.or_method, conj=False)
    else:
        w = np.empty((n, c.n_rules))
        w[:, c.and_rules] = _combine(table, c.and_idx, c.and_method, conj=True)
        w[:, c.or_rules] = _combine(table, c.or_idx, c.or_method, conj=False)
    w = w * c.weights
    sums = w @ c.const_mat  # (N, 2 n_out): sum w z_const, sum w
    num = sums[:, : c.n_out]
    den = sums[:, c.n_out :]
    if c.linear_mat is not None:
        coef = (w @ c.linear_mat).reshape(n, c.n_out, c.n_in)
        num = num + np.einsum("nok,nk->no", coef, xc)
    if c.defuzz == "wtsum":
        return np.ascontiguousarray(num)
    fired = den > 0.0
    return np.where(fired, num / np.where(fired, den, 1.0), c.midpoints)


def _evaluate_one(c: _Compiled, x: list[float]) -> list[float]:
    for v in x:
        if not math.isfinite(v):
            raise InputError("evaluate: x must be finite, got non-finite values")
    xs = [min(max(v, lo), hi) for v, lo, hi in zip(x, c.lo_list, c.hi_list, strict=True)]
    mu = [f(xs[i]) for i, f in c.scalar_mfs]
    mu.append(1.0)
    mu.append(0.0)
    if c.table_has_complements:
        mu.extend(1.0 - mu[s] for s in c.negated.tolist())
    strengths = []
    for weight, is_and, cols in c.scalar_rules:
        terms = [mu[k] for k in cols]
        if is_and:
            w = math.prod(terms) if c.and_method == "prod" else min(terms)
        elif c.or_method == "max":
            w = max(terms)
        else:
            w = terms[0]
            for t in terms[1:]:
                w = w + t - w * t
        strengths.append(w * weight)
    out = []
    for j, entries in enumerate(c.scalar_outputs):
        num = 0.0
        den = 0.0
        for r, q, coeffs in entries:
            w = strengths[r]
            z = (
                q
                if coeffs is None
                else q + math.fsum(p * v for p, v in zip(coeffs, xs, strict=True))
            )
            num += w * z
            den += w
        if c.defuzz == "wtsum":
            out.append(num)
        else:
            out.append(num / den if den > 0.0 else c.midpoint_list[j])
    return out


def evaluate(system: SugenoSystem, x: ArrayLike) -> FloatArray:
    """Outputs of a Sugeno system for one sample or a batch (a whole team).

    Parameters
    ----------
    system : SugenoSystem
        The controller.
    x : array_like, shape (n_inputs,) or (N, n_inputs)
        Crisp inputs, one column per input in ``system.inputs`` order, in the
        inputs' units. Values outside an input's range are clipped to it (as
        MATLAB's ``evalfis`` does); linear consequents see the clipped values.

    Returns
    -------
    ndarray of float64, shape (n_outputs,) or (N, n_outputs)
        One value per output. Under ``wtaver``, an output no rule fires for (all
        firing strengths 0) is the midpoint of its range, as in MATLAB; never NaN.

    Raises
    ------
    InputError
        Wrong shape or non-finite values.

    Notes
    -----
    A batch is one vectorised pass, no Python loop over N. A single sample
    (``(n_inputs,)`` or ``(1, n_inputs)``) takes an equivalent scalar path that
    skips numpy's per-call overhead (see the module notes). Section 2.6.2, eq. 12.
    """
    c = system._compiled
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == c.n_in:
        return np.array(_evaluate_one(c, arr.tolist()))
    if arr.ndim != 2 or arr.shape[1] != c.n_in:
        raise InputError(
            f"evaluate: x must have shape ({c.n_in},) or (N, {c.n_in}) for the inputs "
            f"{[v.name for v in system.inputs]}, got {arr.shape}"
        )
    if arr.shape[0] == 1:
        return np.array([_evaluate_one(c, arr[0].tolist())])
    if not np.all(np.isfinite(arr)):
        raise InputError("evaluate: x must be finite, got non-finite values")
    return _evaluate_batch(c, arr)


# ------------------------------------------------------------------ .fis text


def _num(v: float) -> str:
    """Shortest text that reads back to the same float (integers without '.0')."""
    if v.is_integer() and abs(v) < 1e15:
        return str(int(v))
    return repr(v)


def _nums(values: Sequence[float]) -> str:
    return "[" + " ".join(_num(v) for v in values) + "]"


def fis_text(system: SugenoSystem) -> str:
    """The system as MATLAB ``.fis`` text (``writefis``'s Version 2.0 layout).

    Numbers are written with the shortest representation that reads back to the
    same float, so :func:`parse_fis` of this text gives an equal system.
    """
    lines = [
        "[System]",
        f"Name='{system.name}'",
        "Type='sugeno'",
        "Version=2.0",
        f"NumInputs={len(system.inputs)}",
        f"NumOutputs={len(system.outputs)}",
        f"NumRules={len(system.rules)}",
        f"AndMethod='{system.and_method}'",
        f"OrMethod='{system.or_method}'",
        "ImpMethod='prod'",
        "AggMethod='sum'",
        f"DefuzzMethod='{system.defuzz}'",
    ]
    variables: list[tuple[str, FuzzyInput | FuzzyOutput]] = [
        *((f"Input{k}", v) for k, v in enumerate(system.inputs, start=1)),
        *((f"Output{k}", v) for k, v in enumerate(system.outputs, start=1)),
    ]
    for section, var in variables:
        mfs: Sequence[MembershipFunction | SugenoOutputMf] = var.mfs
        lines += [
            "",
            f"[{section}]",
            f"Name='{var.name}'",
            f"Range={_nums(var.range)}",
            f"NumMFs={len(var.mfs)}",
        ]
        lines += [
            f"MF{m}='{mf.name}':'{mf.kind}',{_nums(mf.params)}" for m, mf in enumerate(mfs, start=1)
        ]
    lines += ["", "[Rules]"]
    for r in system.rules:
        ante = " ".join(str(a) for a in r.antecedent)
        cons = " ".join(str(c) for c in r.consequent)
        lines.append(f"{ante}, {cons} ({_num(r.weight)}) : {1 if r.connective == 'and' else 2}")
    return "\n".join(lines) + "\n"


def write_fis(system: SugenoSystem, path: str | Path) -> None:
    """Write ``system`` as a MATLAB ``.fis`` file, atomically (temporary name + rename).

    Raises
    ------
    InputError
        If the folder does not exist or cannot be written.
    """
    write_text_atomic(path, fis_text(system))


def read_fis(path: str | Path) -> SugenoSystem:
    """Read a MATLAB ``.fis`` file (Sugeno type); see :func:`parse_fis`.

    Raises
    ------
    InputError
        Missing or unreadable file, or any error of :func:`parse_fis`.
    """
    p = Path(path)
    try:
        raw = p.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{p}: no such file") from None
    except OSError as exc:
        raise InputError(f"{p}: cannot read: {exc.strerror}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("latin-1")  # MATLAB on Windows writes the system code page
    return parse_fis(text, origin=str(p))


_SECTION_RE = re.compile(r"^\[(System|Input(\d+)|Output(\d+)|Rules)\]$", re.IGNORECASE)
_KEY_RE = re.compile(r"^([A-Za-z][A-Za-z0-9]*)\s*=\s*(.*)$")
_MF_RE = re.compile(r"^'([^']*)'\s*:\s*'([^']*)'\s*,\s*\[([^\]]*)\]$")
_RULE_RE = re.compile(r"^([^,(:]*?)(?:,([^(:]*?))?\s*(?:\(([^)]*)\))?\s*(?::\s*(\S+))?$")
_SYSTEM_KEYS = (
    "Name",
    "Type",
    "Version",
    "NumInputs",
    "NumOutputs",
    "NumRules",
    "AndMethod",
    "OrMethod",
    "ImpMethod",
    "AggMethod",
    "DefuzzMethod",
)


@dataclass
class _Section:
    kind: str  # "System", "Input", "Output", "Rules"
    number: int  # Input/Output number, else 0
    line: int
    entries: list[tuple[int, str]] = field(default_factory=list)  # (line number, text)


class _Parser:
    """One ``.fis`` text: sections, then a validated :class:`SugenoSystem`."""

    def __init__(self, text: str, origin: str) -> None:
        self.origin = origin
        self.sections: list[_Section] = []
        self.n_lines = 0
        for number, raw in enumerate(text.splitlines(), start=1):
            self.n_lines = number
            line = raw.strip()
            if not line or line[0] in "%#":
                continue
            head = _SECTION_RE.match(line)
            if head:
                name = head.group(1).lower()
                kind = "Input" if head.group(2) else "Output" if head.group(3) else name.title()
                num = int(head.group(2) or head.group(3) or 0)
                self.sections.append(_Section(kind, num, number))
            elif line.startswith("["):
                self.fail(number, f"unknown section {line}")
            elif not self.sections:
                self.fail(number, f"text before the first section: {line!r}")
            else:
                self.sections[-1].entries.append((number, line))

    def fail(self, line: int, what: str) -> NoReturn:
        raise InputError(f"{self.origin}:{line}: {what}")

    def keys(self, section: _Section, allowed: tuple[str, ...]) -> dict[str, tuple[int, str]]:
        """key -> (line, value) of a key=value section; MFk keys are returned as given."""
        found: dict[str, tuple[int, str]] = {}
        for line, text in section.entries:
            m = _KEY_RE.match(text)
            if not m:
                self.fail(line, f"expected key=value in [{self.label(section)}], got {text!r}")
            key, value = m.group(1), m.group(2).strip()
            canonical = next((k for k in allowed if k.lower() == key.lower()), None)
            if canonical is None and re.fullmatch(r"MF\d+", key, re.IGNORECASE) and "MF" in allowed:
                canonical = "MF" + str(int(key[2:]))
            if canonical is None:
                self.fail(line, f"unknown key {key!r} in [{self.label(section)}]")
            if canonical in found:
                self.fail(line, f"{canonical} given twice in [{self.label(section)}]")
            found[canonical] = (line, value)
        return found

    @staticmethod
    def label(section: _Section) -> str:
        return f"{section.kind}{section.number}" if section.number else section.kind

    def string(self, line: int, value: str) -> str:
        if len(value) >= 2 and value[0] == value[-1] == "'":
            return value[1:-1]
        if "'" in value:
            self.fail(line, f"unbalanced quotes in {value!r}")
        return value

    def integer(self, line: int, key: str, value: str) -> int:
        try:
            number = float(value)
        except ValueError:
            number = math.nan
        if not (number.is_integer() and number >= 0):
            self.fail(line, f"{key} must be a whole number >= 0, got {value!r}")
        return int(number)

    def numbers(self, line: int, what: str, text: str) -> list[float]:
        values = []
        for token in text.replace(",", " ").split():
            try:
                v = float(token)
            except ValueError:
                self.fail(line, f"{what}: bad number {token!r}")
            if not math.isfinite(v):
                self.fail(line, f"{what}: {token} is not a finite number")
            values.append(v)
        return values

    def required(
        self, found: dict[str, tuple[int, str]], key: str, section: _Section
    ) -> tuple[int, str]:
        if key not in found:
            self.fail(section.line, f"[{self.label(section)}] has no {key}")
        return found[key]

    def parse(self) -> SugenoSystem:
        systems = [s for s in self.sections if s.kind == "System"]
        if not systems:
            self.fail(1, "missing [System] section")
        if len(systems) > 1:
            self.fail(systems[1].line, "[System] given twice")
        sysec = systems[0]
        sysk = self.keys(sysec, _SYSTEM_KEYS)
        type_line, type_value = self.required(sysk, "Type", sysec)
        fis_type = self.string(type_line, type_value).lower()
        if fis_type == "mamdani":
            self.fail(
                type_line,
                "Type='mamdani': only Sugeno (Takagi-Sugeno) systems can be evaluated; "
                "convert it in MATLAB with convertToSugeno (or mam2sug) first",
            )
        if fis_type != "sugeno":
            self.fail(type_line, f"Type must be 'sugeno', got {type_value}")
        if "Version" in sysk:
            line, value = sysk["Version"]
            if self.string(line, value) not in ("1.0", "2.0", "1", "2"):
                self.fail(line, f"Version {value}: only .fis versions 1.0 and 2.0 are known")
        counts = {}
        for key in ("NumInputs", "NumOutputs", "NumRules"):
            line, value = self.required(sysk, key, sysec)
            counts[key] = (line, self.integer(line, key, value))
        methods = {}
        for key, allowed, default in (
            ("AndMethod", _AND_METHODS, "prod"),
            ("OrMethod", _OR_METHODS, "probor"),
            ("DefuzzMethod", _DEFUZZ_METHODS, "wtaver"),
            ("ImpMethod", ("prod", "min"), "prod"),
            ("AggMethod", ("sum", "max", "probor"), "sum"),
        ):
            if key not in sysk:
                methods[key] = default
                continue
            line, value = sysk[key]
            method = self.string(line, value)
            if method not in allowed:
                self.fail(
                    line, f"{key} {value} is not supported; expected one of {', '.join(allowed)}"
                )
            methods[key] = method
        if methods["ImpMethod"] != "prod" or methods["AggMethod"] != "sum":
            logger.info(
                "%s: ImpMethod=%s, AggMethod=%s play no part in a Sugeno output (MATLAB "
                "ignores them too)",
                self.origin,
                methods["ImpMethod"],
                methods["AggMethod"],
            )
        name_line, name_value = self.required(sysk, "Name", sysec)
        name = self.string(name_line, name_value)

        n_in_line, n_in = counts["NumInputs"]
        n_out_line, n_out = counts["NumOutputs"]
        inputs = [self.variable(s, "Input", n_in) for s in self.numbered("Input", n_in, n_in_line)]
        outputs_secs = self.numbered("Output", n_out, n_out_line)
        outputs = [self.output(s, n_in) for s in outputs_secs]
        rules = self.rules(inputs, outputs, counts["NumRules"])
        try:
            return SugenoSystem(
                name=name,
                inputs=tuple(inputs),
                outputs=tuple(outputs),
                rules=tuple(rules),
                and_method=methods["AndMethod"],  # type: ignore[arg-type]
                or_method=methods["OrMethod"],  # type: ignore[arg-type]
                defuzz=methods["DefuzzMethod"],  # type: ignore[arg-type]
            )
        except InputError as exc:
            self.fail(sysec.line, str(exc))

    def numbered(self, kind: str, count: int, count_line: int) -> list[_Section]:
        secs = [s for s in self.sections if s.kind == kind]
        by_number: dict[int, _Section] = {}
        for s in secs:
            if s.number in by_number:
                self.fail(s.line, f"[{kind}{s.number}] given twice")
            if not 1 <= s.number <= count:
                self.fail(s.line, f"[{kind}{s.number}] but Num{kind}s={count}")
            by_number[s.number] = s
        for k in range(1, count + 1):
            if k not in by_number:
                self.fail(count_line, f"Num{kind}s={count} but there is no [{kind}{k}] section")
        if count == 0:
            self.fail(count_line, f"Num{kind}s must be at least 1")
        return [by_number[k] for k in range(1, count + 1)]

    def mf_entries(
        self, sec: _Section, found: dict[str, tuple[int, str]]
    ) -> list[tuple[int, str, str, list[float]]]:
        line, value = self.required(found, "NumMFs", sec)
        n_mfs = self.integer(line, "NumMFs", value)
        mf_keys = sorted((int(k[2:]), k) for k in found if k.startswith("MF"))
        numbers = [n for n, _ in mf_keys]
        if numbers != list(range(1, n_mfs + 1)):
            missing = sorted(set(range(1, n_mfs + 1)) - set(numbers))
            extra = sorted(set(numbers) - set(range(1, n_mfs + 1)))
            what = f"missing MF{missing[0]}" if missing else f"MF{extra[0]} beyond NumMFs={n_mfs}"
            where = found[f"MF{extra[0]}"][0] if extra and not missing else line
            self.fail(where, f"[{self.label(sec)}] NumMFs={n_mfs}: {what}")
        out = []
        for _, key in mf_keys:
            mf_line, text = found[key]
            m = _MF_RE.match(text)
            if not m:
                self.fail(
                    mf_line,
                    f"{key}: expected 'name':'type',[params], got {text!r}",
                )
            params = self.numbers(mf_line, key, m.group(3))
            out.append((mf_line, m.group(1), m.group(2), params))
        return out

    def trim_padding(self, line: int, key: str, params: list[float], n: int) -> list[float]:
        """Old MATLAB files pad parameter rows with zeros to a common width."""
        if len(params) > n and all(p == 0.0 for p in params[n:]):
            return params[:n]
        return params

    def variable(self, sec: _Section, kind: str, n_in: int) -> FuzzyInput:
        found = self.keys(sec, ("Name", "Range", "NumMFs", "MF"))
        name = self.string(*self.required(found, "Name", sec))
        range_ = self.range(sec, found)
        mfs = []
        for k, (line, mf_name, mf_type, params) in enumerate(self.mf_entries(sec, found), 1):
            if mf_type not in _N_PARAMS:
                hint = (
                    " (an output type; inputs take trimf, trapmf, ...)"
                    if mf_type
                    in (
                        "constant",
                        "linear",
                    )
                    else ""
                )
                self.fail(
                    line,
                    f"MF{k}: unknown membership function type {mf_type!r}{hint}; "
                    f"expected one of {', '.join(_MF_KINDS)}",
                )
            params = self.trim_padding(line, f"MF{k}", params, _N_PARAMS[mf_type])
            try:
                mfs.append(MembershipFunction(mf_name, mf_type, tuple(params)))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"MF{k}: {exc}")
        try:
            return FuzzyInput(name, range_, tuple(mfs))
        except InputError as exc:
            self.fail(sec.line, str(exc))

    def range(self, sec: _Section, found: dict[str, tuple[int, str]]) -> tuple[float, float]:
        line, value = self.required(found, "Range", sec)
        m = re.fullmatch(r"\[([^\]]*)\]", value)
        if not m:
            self.fail(line, f"Range must be [min max], got {value!r}")
        values = self.numbers(line, "Range", m.group(1))
        if len(values) != 2 or values[0] > values[1]:
            self.fail(line, f"Range must be [min max] with min <= max, got {value}")
        return values[0], values[1]

    def output(self, sec: _Section, n_in: int) -> FuzzyOutput:
        found = self.keys(sec, ("Name", "Range", "NumMFs", "MF"))
        name = self.string(*self.required(found, "Name", sec))
        range_ = self.range(sec, found)
        mfs = []
        for k, (line, mf_name, mf_type, params) in enumerate(self.mf_entries(sec, found), 1):
            if mf_type not in ("constant", "linear"):
                self.fail(
                    line,
                    f"MF{k}: a Sugeno output takes 'constant' or 'linear', got {mf_type!r}",
                )
            n = 1 if mf_type == "constant" else n_in + 1
            params = self.trim_padding(line, f"MF{k}", params, n)
            if len(params) != n:
                self.fail(
                    line,
                    f"MF{k}: {mf_type} takes {n} parameter(s)"
                    + ("" if n == 1 else " (one per input, then the constant)")
                    + f", got {len(params)}",
                )
            try:
                mfs.append(SugenoOutputMf(mf_name, mf_type, tuple(params)))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"MF{k}: {exc}")
        try:
            return FuzzyOutput(name, range_, tuple(mfs))
        except InputError as exc:
            self.fail(sec.line, str(exc))

    def rules(
        self, inputs: list[FuzzyInput], outputs: list[FuzzyOutput], count: tuple[int, int]
    ) -> list[Rule]:
        secs = [s for s in self.sections if s.kind == "Rules"]
        count_line, n_rules = count
        if not secs:
            self.fail(count_line, f"NumRules={n_rules} but there is no [Rules] section")
        if len(secs) > 1:
            self.fail(secs[1].line, "[Rules] given twice")
        sec = secs[0]
        if len(sec.entries) != n_rules:
            self.fail(
                count_line,
                f"NumRules={n_rules} but [Rules] (line {sec.line}) has {len(sec.entries)} rule(s)",
            )
        n_in, n_out = len(inputs), len(outputs)
        rules = []
        for k, (line, text) in enumerate(sec.entries, start=1):
            m = _RULE_RE.match(text)
            if not m:
                self.fail(
                    line,
                    f"rule {k}: expected 'in1 .. inN, out1 .. outM (weight) : 1|2', got {text!r}",
                )
            first = self.indices(line, k, m.group(1))
            if m.group(2) is not None:  # with the comma: antecedent, consequent
                ante, cons = first, self.indices(line, k, m.group(2))
                if len(ante) != n_in:
                    self.fail(line, f"rule {k}: {len(ante)} antecedent indices for {n_in} inputs")
                if len(cons) != n_out:
                    self.fail(line, f"rule {k}: {len(cons)} consequent indices for {n_out} outputs")
            else:  # without the comma: the first n_in numbers are the antecedent
                if len(first) != n_in + n_out:
                    self.fail(
                        line,
                        f"rule {k}: {len(first)} indices for {n_in} inputs and {n_out} outputs",
                    )
                ante, cons = first[:n_in], first[n_in:]
            weight = 1.0
            if m.group(3) is not None:
                values = self.numbers(line, f"rule {k} weight", m.group(3))
                if len(values) != 1 or not 0.0 <= values[0] <= 1.0:
                    self.fail(
                        line, f"rule {k}: weight must be one number in [0, 1], got ({m.group(3)})"
                    )
                weight = values[0]
            connective = "and"
            if m.group(4) is not None:
                if m.group(4) not in ("1", "2"):
                    self.fail(
                        line, f"rule {k}: connective must be 1 (AND) or 2 (OR), got {m.group(4)!r}"
                    )
                connective = "and" if m.group(4) == "1" else "or"
            for i, (a, var) in enumerate(zip(ante, inputs, strict=True), start=1):
                if abs(a) > len(var.mfs):
                    self.fail(
                        line,
                        f"rule {k}: input {i} ({var.name!r}) has no membership function {abs(a)} "
                        f"(it has {len(var.mfs)})",
                    )
            for j, (c, out) in enumerate(zip(cons, outputs, strict=True), start=1):
                if c < 0:
                    self.fail(
                        line,
                        f"rule {k}: output {j}: negative (NOT) consequents have no meaning "
                        "in a Sugeno system",
                    )
                if c > len(out.mfs):
                    self.fail(
                        line,
                        f"rule {k}: output {j} ({out.name!r}) has no membership function {c} "
                        f"(it has {len(out.mfs)})",
                    )
            try:
                rules.append(Rule(tuple(ante), tuple(cons), weight, connective))  # type: ignore[arg-type]
            except InputError as exc:
                self.fail(line, f"rule {k}: {exc}")
        return rules

    def indices(self, line: int, k: int, text: str) -> list[int]:
        values = self.numbers(line, f"rule {k}", text)
        for v in values:
            if not v.is_integer():
                self.fail(
                    line, f"rule {k}: index {v:g} is not a whole number (hedges are not supported)"
                )
        return [int(v) for v in values]


def parse_fis(text: str, *, origin: str = "<string>") -> SugenoSystem:
    """Parse MATLAB ``.fis`` text into a :class:`SugenoSystem`.

    Reads what MATLAB's ``writefis`` writes (Version 2.0: quoted values,
    ``Range=[a b]``, ``MF1='name':'trimf',[a b c]``, rule lines
    ``1 0 2 0, 1 3 (1) : 1``) and the older files shipped with the toolbox:
    ``%`` comment lines, spaces around ``=``, no ``Version`` line, parameter rows
    padded with trailing zeros, ``ImpMethod``/``AggMethod`` other than
    ``prod``/``sum`` (they do not affect a Sugeno output), rule lines without the
    comma, the weight or the connective (defaults 1 and AND).

    Parameters
    ----------
    text : str
        The file's text.
    origin : str
        Its name in error messages.

    Returns
    -------
    SugenoSystem

    Raises
    ------
    InputError
        ``"origin:LINE: what"`` for the first problem: a Mamdani system (only Sugeno
        systems are evaluated), a missing section or key, a bad number, a membership
        function index out of range, a wrong parameter count, an unknown
        membership function type or method, counts that disagree with the sections.
    """
    return _Parser(text, origin).parse()


def evaluate_csv(system: SugenoSystem, text: str, *, origin: str = "<csv>") -> str:
    """Evaluate a system on a CSV table of inputs; returns the CSV table of outputs.

    Parameters
    ----------
    system : SugenoSystem
        The controller.
    text : str
        CSV with a header row naming every input of ``system`` exactly once (any
        order), then one row of numbers per sample.
    origin : str
        Its name in error messages.

    Returns
    -------
    str
        CSV with a header of the output names and one row per input row, numbers
        written so they read back to the same floats.

    Raises
    ------
    InputError
        ``"origin:LINE: what"``: no header, a missing or extra column (named), a row
        with the wrong number of fields, a bad or non-finite number, no data rows.
    """
    rows = list(csv.reader(io.StringIO(text)))
    numbered = [(k, r) for k, r in enumerate(rows, start=1) if any(f.strip() for f in r)]
    if not numbered:
        raise InputError(f"{origin}:1: empty file; expected a header naming the inputs")
    head_line, header = numbered[0]
    names = [h.strip() for h in header]
    wanted = [v.name for v in system.inputs]
    for name in names:
        if name not in wanted:
            raise InputError(
                f"{origin}:{head_line}: column {name!r} is not an input of {system.name!r} "
                f"(inputs: {wanted})"
            )
        if names.count(name) > 1:
            raise InputError(f"{origin}:{head_line}: column {name!r} given twice")
    for name in wanted:
        if name not in names:
            raise InputError(f"{origin}:{head_line}: missing column {name!r}")
    order = [names.index(name) for name in wanted]
    data = numbered[1:]
    if not data:
        raise InputError(f"{origin}:{head_line}: no data rows after the header")
    x = np.empty((len(data), len(wanted)))
    for row_index, (line, row) in enumerate(data):
        if len(row) != len(names):
            raise InputError(f"{origin}:{line}: {len(row)} fields, the header has {len(names)}")
        for k, col in enumerate(order):
            field_text = row[col].strip()
            try:
                value = float(field_text)
            except ValueError:
                raise InputError(
                    f"{origin}:{line}: column {wanted[k]!r}: bad number {field_text!r}"
                ) from None
            if not math.isfinite(value):
                raise InputError(
                    f"{origin}:{line}: column {wanted[k]!r}: {field_text} is not finite"
                )
            x[row_index, k] = value
    y = evaluate(system, x).reshape(len(data), len(system.outputs))
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow([o.name for o in system.outputs])
    writer.writerows([repr(v) for v in row] for row in y.tolist())
    return out.getvalue()


def evaluate_csv_file(system: SugenoSystem, in_path: str | Path, out_path: str | Path) -> int:
    """:func:`evaluate_csv` from file to file; the output is written atomically.

    Returns
    -------
    int
        The number of rows evaluated.

    Raises
    ------
    InputError
        A missing or unreadable input file, a folder that cannot be written, or any
        error of :func:`evaluate_csv` (nothing is written then).
    """
    src = Path(in_path)
    try:
        text = src.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"{src}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise InputError(f"{src}: cannot read: {exc}") from None
    table = evaluate_csv(system, text, origin=str(src))
    write_text_atomic(out_path, table)
    return table.count("\n") - 1

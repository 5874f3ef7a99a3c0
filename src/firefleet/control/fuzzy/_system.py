"""The description of a Takagi-Sugeno system: variables, membership functions, rules.

Frozen dataclasses validated on construction (:class:`~firefleet.errors.InputError`
naming the field). MATLAB semantics throughout (Fuzzy Logic Toolbox, ``sugfis``).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Literal

from firefleet.control.fuzzy._kernel import FisTables, PackedTables, compile_system, pack
from firefleet.control.fuzzy._membership import MfKind, check_mf_params
from firefleet.errors import InputError

__all__ = [
    "FuzzyInput",
    "FuzzyOutput",
    "MembershipFunction",
    "Rule",
    "SugenoOutputMf",
    "SugenoSystem",
]

AND_METHODS = ("min", "prod")
OR_METHODS = ("max", "probor")
DEFUZZ_METHODS = ("wtaver", "wtsum")
RANGE_LIMIT = 1e15
"""Largest magnitude of a variable's range end: beyond it a float64 no longer resolves
a unit step (2**53 = 9.0e15) and the plots' axes overflow."""


def _check_name(name: object, where: str) -> None:
    if not isinstance(name, str) or not name.strip():
        raise InputError(f"{where}: name must be a non-empty string, got {name!r}")
    if any(c in name for c in "'\n\r"):
        raise InputError(f"{where}: name {name!r} must not contain quotes or line breaks")


def range_problem(lo: float, hi: float) -> str | None:
    """What is wrong with a variable's range [lo, hi], or None."""
    if not (math.isfinite(lo) and math.isfinite(hi) and lo <= hi):
        return f"must be finite with min <= max, got [{lo:g} {hi:g}]"
    if max(abs(lo), abs(hi)) > RANGE_LIMIT:
        return (
            f"ends must lie within +-{RANGE_LIMIT:g} (float64 resolves a unit step only "
            f"up to 9e15), got [{lo:g} {hi:g}]"
        )
    return None


def _check_range(rng: object, where: str) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in rng)  # type: ignore[attr-defined]
    except (TypeError, ValueError):
        raise InputError(f"{where}: range must be two numbers (min, max), got {rng!r}") from None
    problem = range_problem(lo, hi)
    if problem is not None:
        raise InputError(f"{where}: range {problem}")
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
        object.__setattr__(self, "params", check_mf_params(self.kind, self.params, where))


@dataclass(frozen=True)
class FuzzyInput:
    """An input variable.

    Attributes
    ----------
    name : str
        Its name (a column name in ``firefleet fis --eval``); a unit may follow in
        brackets, ``"D_rp [m]"``, and is shown on plots.
    range : tuple of float
        (min, max) of the variable; inputs outside are clipped to it. Both ends
        within +-1e15 (``RANGE_LIMIT``).
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
        Both ends within +-1e15.
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
            ("and_method", AND_METHODS),
            ("or_method", OR_METHODS),
            ("defuzz", DEFUZZ_METHODS),
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
    def _tables(self) -> FisTables:
        """The system flattened for compiled evaluation (built once, cached)."""
        return compile_system(self)

    @functools.cached_property
    def _packed(self) -> PackedTables:
        """:attr:`_tables` in two buffers, for the one-sample call (fewest arguments)."""
        return pack(self._tables)


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

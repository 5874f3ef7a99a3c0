"""A Sugeno system as flat arrays, and its evaluation inside compiled (numba) loops.

:func:`firefleet.control.fuzzy.evaluate` is the reference: vectorised NumPy over a
batch. The simulator's compiled team loop cannot call NumPy functions on objects, so
:func:`compile_system` flattens a system into arrays and :func:`eval_one` evaluates one
sample with scalar arithmetic, the same definitions (MATLAB Fuzzy Logic Toolbox) in the
same order. Tests check that the two agree to rounding.

:func:`eval_one` is inlined into its callers: passing its fourteen arrays through a call
costs more (reference counting) than evaluating the system. Numba's on-disk cache keys a
compiled function on its own file only: after editing this module, remove the caches
(``make clean``) so the simulator's kernel is compiled again.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError

__all__ = ["FisTables", "compile_system", "eval_one"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

MF_CODES = {"trimf": 0, "trapmf": 1, "gaussmf": 2, "gbellmf": 3, "sigmf": 4, "smf": 5, "zmf": 6}
"""Integer code of each membership-function kind in :class:`FisTables`."""


class FisTables(NamedTuple):
    """A Sugeno system flattened for :func:`eval_one` (M input MFs, R rules, K output MFs).

    Attributes
    ----------
    mf_kind : ndarray of int, shape (M,)
        Kind of each input membership function (``MF_CODES``).
    mf_params : ndarray, shape (M, 4)
        Its parameters, padded with zeros.
    mf_input : ndarray of int, shape (M,)
        The input it belongs to.
    in_range : ndarray, shape (n_in, 2)
        Input ranges (inputs are clipped to them).
    rule_mf : ndarray of int, shape (R, n_in)
        Global MF index per rule and input, -1 where the input is not used.
    rule_not : ndarray of bool, shape (R, n_in)
        Whether the antecedent is negated.
    rule_weight : ndarray, shape (R,)
    rule_or : ndarray of bool, shape (R,)
        True for an OR rule.
    rule_out : ndarray of int, shape (R, n_out)
        Global output-MF index per rule and output, -1 where unused.
    out_coef : ndarray, shape (K, n_in + 1)
        Output MFs as linear functions (input coefficients, then the constant).
    out_mid : ndarray, shape (n_out,)
        Middle of each output's range: the output when no rule fires (MATLAB's choice).
    flags : ndarray of int, shape (3,)
        AND is product (1) or min (0); OR is probor (1) or max (0); defuzzification is
        weighted sum (1) or weighted average (0).
    """

    mf_kind: IntArray
    mf_params: FloatArray
    mf_input: IntArray
    in_range: FloatArray
    rule_mf: IntArray
    rule_not: NDArray[np.bool_]
    rule_weight: FloatArray
    rule_or: NDArray[np.bool_]
    rule_out: IntArray
    out_coef: FloatArray
    out_mid: FloatArray
    flags: IntArray


def compile_system(system: Any) -> FisTables:
    """Flatten a :class:`firefleet.control.fuzzy.SugenoSystem` into :class:`FisTables`."""
    n_in = len(system.inputs)
    kinds: list[int] = []
    params: list[list[float]] = []
    owner: list[int] = []
    first: list[int] = []
    for i, var in enumerate(system.inputs):
        first.append(len(kinds))
        for mf in var.mfs:
            if mf.kind not in MF_CODES:
                raise InputError(f"input {var.name}: membership function kind {mf.kind!r}")
            kinds.append(MF_CODES[mf.kind])
            params.append([*mf.params, 0.0, 0.0, 0.0, 0.0][:4])
            owner.append(i)
    out_first: list[int] = []
    coef: list[list[float]] = []
    for var in system.outputs:
        out_first.append(len(coef))
        for mf in var.mfs:
            if mf.kind == "constant":
                coef.append([0.0] * n_in + [float(mf.params[0])])
            else:
                coef.append([float(p) for p in mf.params])
    n_rules = len(system.rules)
    rule_mf = np.full((n_rules, n_in), -1, dtype=np.int64)
    rule_not = np.zeros((n_rules, n_in), dtype=np.bool_)
    rule_out = np.full((n_rules, len(system.outputs)), -1, dtype=np.int64)
    for r, rule in enumerate(system.rules):
        for i, a in enumerate(rule.antecedent):
            if a != 0:
                rule_mf[r, i] = first[i] + abs(a) - 1
                rule_not[r, i] = a < 0
        for o, c in enumerate(rule.consequent):
            if c != 0:
                rule_out[r, o] = out_first[o] + abs(c) - 1
    return FisTables(
        mf_kind=np.array(kinds, dtype=np.int64),
        mf_params=np.array(params, dtype=np.float64).reshape(-1, 4),
        mf_input=np.array(owner, dtype=np.int64),
        in_range=np.array([v.range for v in system.inputs], dtype=np.float64),
        rule_mf=rule_mf,
        rule_not=rule_not,
        rule_weight=np.array([r.weight for r in system.rules], dtype=np.float64),
        rule_or=np.array([r.connective == "or" for r in system.rules], dtype=np.bool_),
        rule_out=rule_out,
        out_coef=np.array(coef, dtype=np.float64).reshape(-1, n_in + 1),
        out_mid=np.array([0.5 * (v.range[0] + v.range[1]) for v in system.outputs]),
        flags=np.array(
            [
                system.and_method == "prod",
                system.or_method == "probor",
                system.defuzz == "wtsum",
            ],
            dtype=np.int64,
        ),
    )


@numba.njit(cache=True)
def membership_one(kind: int, p: FloatArray, m: int, x: float) -> float:  # pragma: no cover
    """Degree of ``x`` in membership function ``m`` (row ``m`` of ``p``, (M, 4)), MATLAB's
    definitions (see ``firefleet.control.fuzzy``)."""
    a, b, c, d = float(p[m, 0]), float(p[m, 1]), float(p[m, 2]), float(p[m, 3])
    if kind == 0:  # trimf [a b c]
        if x == b:
            return 1.0
        if a < x < b:
            return (x - a) / (b - a)
        if b < x < c:
            return (c - x) / (c - b)
        return 0.0
    if kind == 1:  # trapmf [a b c d]
        y1 = 1.0 if x >= b else ((x - a) / (b - a) if x >= a and a != b else 0.0)
        y2 = 1.0 if x <= c else ((d - x) / (d - c) if x <= d and c != d else 0.0)
        return min(y1, y2)
    if kind == 2:  # gaussmf [sigma c]
        return math.exp(-((x - b) ** 2) / (2.0 * a**2))
    if kind == 3:  # gbellmf [a b c]
        ratio: float = abs((x - c) / a)
        return 1.0 / (1.0 + math.pow(ratio, 2.0 * b))
    if kind == 4:  # sigmf [a c]
        return 1.0 / (1.0 + math.exp(-a * (x - b)))
    if kind == 5:  # smf [a b]
        if a >= b:
            return 1.0 if x >= 0.5 * (a + b) else 0.0
        if x <= a:
            return 0.0
        if x <= 0.5 * (a + b):
            return 2.0 * ((x - a) / (b - a)) ** 2
        if x <= b:
            return 1.0 - 2.0 * ((x - b) / (b - a)) ** 2
        return 1.0
    # zmf [a b]
    if a >= b:
        return 1.0 if x <= 0.5 * (a + b) else 0.0
    if x <= a:
        return 1.0
    if x <= 0.5 * (a + b):
        return 1.0 - 2.0 * ((x - a) / (b - a)) ** 2
    if x <= b:
        return 2.0 * ((x - b) / (b - a)) ** 2
    return 0.0


@numba.njit(cache=True, inline="always")
def eval_one(
    x: FloatArray,
    mf_kind: IntArray,
    mf_params: FloatArray,
    mf_input: IntArray,
    in_range: FloatArray,
    rule_mf: IntArray,
    rule_not: NDArray[np.bool_],
    rule_weight: FloatArray,
    rule_or: NDArray[np.bool_],
    rule_out: IntArray,
    out_coef: FloatArray,
    out_mid: FloatArray,
    flags: IntArray,
    out: FloatArray,
    work: FloatArray,
) -> None:  # pragma: no cover - jit
    """Evaluate one sample ``x`` (n_in,) into ``out`` (n_out,); the tables' fields in order.

    ``work`` is scratch space of at least ``n_in + M + 2 n_out`` floats (no allocation
    inside the hot loop).
    """
    n_in = x.shape[0]
    n_mf = mf_kind.shape[0]
    n_out = out.shape[0]
    # work holds, one after the other: clipped inputs, memberships, numerators, weights
    mu0 = n_in
    num0 = n_in + n_mf
    den0 = num0 + n_out
    for i in range(n_in):
        work[i] = min(max(x[i], in_range[i, 0]), in_range[i, 1])
    for m in range(n_mf):
        work[mu0 + m] = membership_one(mf_kind[m], mf_params, m, work[mf_input[m]])
    for o in range(n_out):
        work[num0 + o] = 0.0
        work[den0 + o] = 0.0
    for r in range(rule_mf.shape[0]):
        is_or = rule_or[r]
        w = 0.0 if is_or else 1.0
        if not is_or and flags[0] == 0:
            w = 1.0
        started = False
        for i in range(n_in):
            m = rule_mf[r, i]
            if m < 0:
                continue
            d = 1.0 - work[mu0 + m] if rule_not[r, i] else work[mu0 + m]
            if not started:
                w = d
                started = True
            elif is_or:
                w = w + d - w * d if flags[1] == 1 else max(w, d)
            else:
                w = w * d if flags[0] == 1 else min(w, d)
        if not started:
            w = 0.0
        w *= rule_weight[r]
        for o in range(n_out):
            k = rule_out[r, o]
            if k < 0:
                continue
            z = out_coef[k, n_in]
            for i in range(n_in):
                z += out_coef[k, i] * work[i]
            work[num0 + o] += w * z
            work[den0 + o] += w
    for o in range(n_out):
        if flags[2] == 1:
            out[o] = work[num0 + o]
        elif work[den0 + o] > 0.0:
            out[o] = work[num0 + o] / work[den0 + o]
        else:
            out[o] = out_mid[o]

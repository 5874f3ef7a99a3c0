"""A Sugeno system as flat arrays, and its evaluation in compiled (numba) code.

:func:`compile_system` flattens a :class:`~firefleet.control.fuzzy.SugenoSystem` into
:class:`FisTables`; :func:`eval_one` evaluates one sample with scalar arithmetic on
those tables, calling :func:`~firefleet.control.fuzzy._membership.membership_one` (the
one definition of the membership functions). It is the only evaluation of a system:
the public :func:`~firefleet.control.fuzzy.evaluate` runs it for one sample
(:func:`eval_packed`) or loops it over a batch (:func:`eval_rows`), and the
simulator's compiled team loop inlines it per robot and tick.

:func:`eval_one` is inlined into its callers: passing its fourteen arrays through a call
costs more (reference counting) than evaluating the system. For the same reason the
public one-sample call passes the tables packed into two buffers (:func:`pack`), which
the compiled side slices back into views. Numba's on-disk cache keys a compiled
function on its own file only: after editing this module or ``_membership.py``, remove
the caches (``make clean``) so the simulator's kernel is compiled again.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from firefleet._typing import FloatArray, IntArray
from firefleet.control.fuzzy._membership import MF_CODES, membership_one, mf_value
from firefleet.errors import InputError

if TYPE_CHECKING:
    from firefleet.control.fuzzy._system import SugenoSystem

__all__ = [
    "MF_CODES",
    "FisTables",
    "PackedTables",
    "compile_system",
    "eval_one",
    "eval_packed",
    "eval_rows",
    "membership_one",
    "pack",
]


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


def compile_system(system: SugenoSystem) -> FisTables:
    """Flatten a :class:`~firefleet.control.fuzzy.SugenoSystem` into :class:`FisTables`."""
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
    for out_var in system.outputs:
        out_first.append(len(coef))
        for omf in out_var.mfs:
            if omf.kind == "constant":
                coef.append([0.0] * n_in + [float(omf.params[0])])
            else:
                coef.append([float(p) for p in omf.params])
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


@numba.njit(cache=True, inline="always")
def eval_one(
    x: FloatArray,
    mf_kind: IntArray,
    mf_params: FloatArray,
    mf_input: IntArray,
    in_range: FloatArray,
    rule_mf: IntArray,
    rule_not: NDArray[np.bool_] | IntArray,
    rule_weight: FloatArray,
    rule_or: NDArray[np.bool_] | IntArray,
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
    and_prod = flags[0] == 1
    or_probor = flags[1] == 1
    for i in range(n_in):
        work[i] = min(max(x[i], in_range[i, 0]), in_range[i, 1])
    for m in range(n_mf):
        work[mu0 + m] = mf_value(
            mf_kind[m],
            mf_params[m, 0],
            mf_params[m, 1],
            mf_params[m, 2],
            mf_params[m, 3],
            work[mf_input[m]],
        )
    for o in range(n_out):
        work[num0 + o] = 0.0
        work[den0 + o] = 0.0
    for r in range(rule_mf.shape[0]):
        is_or = rule_or[r]
        w = 0.0
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
                w = w + d - w * d if or_probor else max(w, d)
            else:
                w = w * d if and_prod else min(w, d)
        w *= rule_weight[r]
        if w == 0.0:  # w z = +-0 (z finite) added to sums that are never -0: no bit changes
            continue
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


class PackedTables(NamedTuple):
    """:class:`FisTables` in two 2-D buffers (see :func:`pack`), tables as row blocks.

    Attributes
    ----------
    floats : ndarray, shape (2 + M + n_in + K, W)
        Row 0 ``rule_weight``, row 1 ``out_mid``, then the rows of ``mf_params``,
        ``in_range`` and ``out_coef``, each from column 0, padded with zeros.
    ints : ndarray of int, shape (5 + 3 R, W)
        Row 0 ``n_in, M, R, n_out, K, work size``; rows 1-4 ``mf_kind``,
        ``mf_input``, ``rule_or``, ``flags``; then the rows of ``rule_mf``,
        ``rule_not`` and ``rule_out``.
    n_in, n_out : int
        Inputs and outputs.

    Notes
    -----
    Row blocks make every table a basic slice of its buffer (``ints[5:5 + R, :n_in]``),
    which the compiled side takes almost for free; a ``reshape`` per table cost more
    than the evaluation itself.
    """

    floats: FloatArray
    ints: IntArray
    n_in: int
    n_out: int


def pack(t: FisTables) -> PackedTables:
    """Pack :class:`FisTables` into two buffers (the compiled side takes views).

    Membership functions no rule uses are left out (their degrees would never be
    read), so the packed evaluation gives the same bits with less work.
    """
    used = np.unique(t.rule_mf[t.rule_mf >= 0])
    remap = np.full(t.mf_kind.shape[0], -1, dtype=np.int64)
    remap[used] = np.arange(used.size)
    t = t._replace(
        mf_kind=t.mf_kind[used],
        mf_params=t.mf_params[used],
        mf_input=t.mf_input[used],
        rule_mf=np.where(t.rule_mf >= 0, remap[np.maximum(t.rule_mf, 0)], -1),
    )
    n_in = t.in_range.shape[0]
    n_out = t.out_mid.shape[0]
    n_mf = t.mf_kind.shape[0]
    n_r = t.rule_mf.shape[0]
    n_k = t.out_coef.shape[0]
    width = max(6, 4, n_in + 1, n_out, n_mf, n_r)
    ints = np.zeros((5 + 3 * n_r, width), dtype=np.int64)
    ints[0, :6] = [n_in, n_mf, n_r, n_out, n_k, n_in + n_mf + 2 * n_out]
    ints[1, :n_mf] = t.mf_kind
    ints[2, :n_mf] = t.mf_input
    ints[3, :n_r] = t.rule_or
    ints[4, :3] = t.flags
    ints[5 : 5 + n_r, :n_in] = t.rule_mf
    ints[5 + n_r : 5 + 2 * n_r, :n_in] = t.rule_not
    ints[5 + 2 * n_r : 5 + 3 * n_r, :n_out] = t.rule_out
    floats = np.zeros((2 + n_mf + n_in + n_k, width))
    floats[0, :n_r] = t.rule_weight
    floats[1, :n_out] = t.out_mid
    floats[2 : 2 + n_mf, :4] = t.mf_params
    floats[2 + n_mf : 2 + n_mf + n_in, :2] = t.in_range
    floats[2 + n_mf + n_in :, : n_in + 1] = t.out_coef
    return PackedTables(floats, ints, n_in, n_out)


@numba.njit(cache=True, inline="always")
def _unpack(fb: FloatArray, ib: IntArray) -> tuple[Any, ...]:  # pragma: no cover - jit
    """The :class:`FisTables` fields as views of the packed buffers (basic slices)."""
    n_in, n_mf, n_r, n_out = ib[0, 0], ib[0, 1], ib[0, 2], ib[0, 3]
    m0 = 2 + n_mf
    return (
        ib[1, :n_mf],  # mf_kind
        fb[2:m0, :4],  # mf_params
        ib[2, :n_mf],  # mf_input
        fb[m0 : m0 + n_in, :2],  # in_range
        ib[5 : 5 + n_r, :n_in],  # rule_mf
        ib[5 + n_r : 5 + 2 * n_r, :n_in],  # rule_not
        fb[0, :n_r],  # rule_weight
        ib[3, :n_r],  # rule_or
        ib[5 + 2 * n_r : 5 + 3 * n_r, :n_out],  # rule_out
        fb[m0 + n_in :, : n_in + 1],  # out_coef
        fb[1, :n_out],  # out_mid
        ib[4, :3],  # flags
    )


@numba.njit(cache=True, error_model="numpy")
def eval_packed(x: FloatArray, fb: FloatArray, ib: IntArray, out: FloatArray) -> bool:
    """One sample ``x`` (n_in,) into ``out`` (n_out,); False (nothing written) if ``x``
    holds a non-finite value. ``fb``, ``ib``: :class:`PackedTables` buffers."""
    for i in range(x.shape[0]):  # pragma: no cover - jit
        if not math.isfinite(x[i]):
            return False
    work = np.empty(ib[0, 5])
    kind, par, inp, rng, rmf, rnot, rw, ror, rout, coef, mid, flags = _unpack(fb, ib)
    eval_one(x, kind, par, inp, rng, rmf, rnot, rw, ror, rout, coef, mid, flags, out, work)
    return True


@numba.njit(cache=True, error_model="numpy")
def eval_rows(x: FloatArray, fb: FloatArray, ib: IntArray, out: FloatArray) -> int:
    """A batch ``x`` (N, n_in) into ``out`` (N, n_out), row after row with :func:`eval_one`.

    Returns -1, or the first row holding a non-finite value (nothing evaluated then).
    """
    n = x.shape[0]  # pragma: no cover - jit
    for k in range(n):
        for i in range(x.shape[1]):
            if not math.isfinite(x[k, i]):
                return k
    work = np.empty(ib[0, 5])
    row = np.empty(x.shape[1])
    y = np.empty(out.shape[1])
    kind, par, inp, rng, rmf, rnot, rw, ror, rout, coef, mid, flags = _unpack(fb, ib)
    for k in range(n):  # the tables unpacked once; plain buffers per row (no views)
        for i in range(x.shape[1]):
            row[i] = x[k, i]
        eval_one(row, kind, par, inp, rng, rmf, rnot, rw, ror, rout, coef, mid, flags, y, work)
        for j in range(y.shape[0]):
            out[k, j] = y[j]
    return -1

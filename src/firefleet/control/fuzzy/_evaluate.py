"""Evaluation of a Sugeno system: one sample, a batch (a whole team), a CSV table.

Per sample and per output ``j`` (MATLAB's ``evalfis`` for a Sugeno system)::

    x      <- clip(x, input ranges)                              (MATLAB clips too)
    w_r    =  weight_r * AND/OR over used inputs of mu(x_i) (or 1 - mu for NOT)
    z_rj   =  c_rj  (constant)   or   p_rj . x + q_rj  (linear, MATLAB order)
    y_j    =  sum_r w_r z_rj / sum_r w_r     (wtaver; rules with consequent 0 skipped)
           =  sum_r w_r z_rj                  (wtsum)

Both the one-sample call and the batch run the same compiled function
(:func:`firefleet.control.fuzzy._kernel.eval_one`) on tables flattened once and
cached on the frozen system, so a single robot's call costs about a microsecond (the
bench controller: 11 rules, 4 inputs) and a batch is one compiled loop (about 0.3 us a
sample); the simulator's team loop inlines the same function.
"""

from __future__ import annotations

import csv
import io
import math

import numpy as np
from numpy.typing import ArrayLike

from firefleet._typing import FloatArray
from firefleet.control.fuzzy._kernel import eval_packed, eval_rows
from firefleet.control.fuzzy._system import SugenoSystem
from firefleet.errors import InputError

__all__ = ["evaluate", "evaluate_csv"]


_NOT_FINITE = "evaluate: x must be finite, got non-finite values"


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
    Compiled: one sample is one call of the compiled evaluation, a batch one
    compiled loop over its rows (no Python loop over N). Section 2.6.2, eq. 12.

    Examples
    --------
    >>> from firefleet.control.fuzzy import (
    ...     FuzzyInput, FuzzyOutput, MembershipFunction, Rule, SugenoOutputMf,
    ...     SugenoSystem, evaluate)
    >>> near = MembershipFunction("near", "trimf", (0, 0, 2))
    >>> far = MembershipFunction("far", "trimf", (0, 2, 2))
    >>> speed = FuzzyOutput("v", (0, 1), (SugenoOutputMf("slow", "constant", (0.1,)),
    ...                                   SugenoOutputMf("fast", "constant", (0.5,))))
    >>> fis = SugenoSystem("s", (FuzzyInput("d", (0, 2), (near, far)),), (speed,),
    ...                    (Rule((1,), (1,)), Rule((2,), (2,))))
    >>> evaluate(fis, [0.5]).tolist()           # 0.75 * 0.1 + 0.25 * 0.5
    [0.2]
    >>> evaluate(fis, [[0.0], [2.0]]).tolist()  # a batch (N, 1) -> (N, 1)
    [[0.1], [0.5]]
    """
    packed = system._packed
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim == 1 and arr.shape[0] == packed.n_in:
        out = np.empty(packed.n_out)
        if not eval_packed(np.ascontiguousarray(arr), packed.floats, packed.ints, out):
            raise InputError(_NOT_FINITE)
        return out
    if arr.ndim != 2 or arr.shape[1] != packed.n_in:
        raise InputError(
            f"evaluate: x must have shape ({packed.n_in},) or (N, {packed.n_in}) for the "
            f"inputs {[v.name for v in system.inputs]}, got {arr.shape}"
        )
    result = np.empty((arr.shape[0], packed.n_out))
    if eval_rows(np.ascontiguousarray(arr), packed.floats, packed.ints, result) >= 0:
        raise InputError(_NOT_FINITE)
    return result


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

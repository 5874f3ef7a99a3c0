"""Takagi-Sugeno fuzzy inference, for one robot or a whole team, with MATLAB ``.fis`` files.

The deliverable's high-level controller is a Takagi-Sugeno system designed in MATLAB's
Fuzzy Logic Toolbox (section 2.5.1; eq. 12; rule base of Table 1, section 2.6.2.7).
This package evaluates such systems exactly as the toolbox does, for one robot or a
whole team in one call, and reads and writes the toolbox's ``.fis`` text so a
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

When no rule fires for an output under ``wtaver`` the output is the midpoint of its
range, as MATLAB's ``evalfis`` does. The implication (``ImpMethod``) and aggregation
(``AggMethod``) methods of a ``.fis`` file play no part in a Sugeno system's output;
MATLAB ignores them and so do we (they are read, and written as ``prod`` and ``sum``).

Layout: ``_membership`` (the one compiled definition of each membership function),
``_system`` (the frozen description), ``_kernel`` (the system as flat tables and its
compiled evaluation, also inlined by the simulator), ``_evaluate`` (the public
evaluation), ``_fis_format`` (the ``.fis`` reader and writer). The library returns
text; the command line (``firefleet fis``) writes files.

References
----------
MathWorks, Fuzzy Logic Toolbox User's Guide: ``trimf``, ``trapmf``, ``gaussmf``,
``gbellmf``, ``sigmf``, ``smf``, ``zmf``, ``evalfis``, ``readfis``, ``writefis``.
T. Takagi and M. Sugeno, "Fuzzy identification of systems and its applications to
modeling and control", IEEE Trans. SMC 15(1), 1985.
"""

from firefleet.control.fuzzy._evaluate import evaluate, evaluate_csv
from firefleet.control.fuzzy._fis_format import fis_text, parse_fis, read_fis
from firefleet.control.fuzzy._membership import MfKind, membership
from firefleet.control.fuzzy._system import (
    FuzzyInput,
    FuzzyOutput,
    MembershipFunction,
    Rule,
    SugenoOutputMf,
    SugenoSystem,
)

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
    "fis_text",
    "membership",
    "parse_fis",
    "read_fis",
]

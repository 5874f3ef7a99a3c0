"""Former home of the compiled fuzzy evaluation, now ``firefleet.control.fuzzy._kernel``."""

from firefleet.control.fuzzy._kernel import MF_CODES, FisTables, compile_system, eval_one
from firefleet.control.fuzzy._membership import membership_one

__all__ = ["MF_CODES", "FisTables", "compile_system", "eval_one", "membership_one"]

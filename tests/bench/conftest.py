"""Load the bench's helper modules (bench/_harness.py, bench/_topics.py) for the tests.

They are loaded by file under their own names, without putting ``bench/`` on
``sys.path`` (its topic modules are named ``fuzzy``, ``stereo``, ... and must not shadow
anything for the rest of the suite).
"""

import importlib.util
import sys
from pathlib import Path

BENCH = Path(__file__).resolve().parents[2] / "bench"

for _name in ("_harness", "_topics"):  # _topics imports _harness: this order
    if _name not in sys.modules:
        _spec = importlib.util.spec_from_file_location(_name, BENCH / f"{_name}.py")
        assert _spec is not None
        assert _spec.loader is not None
        _module = importlib.util.module_from_spec(_spec)
        sys.modules[_name] = _module
        _spec.loader.exec_module(_module)

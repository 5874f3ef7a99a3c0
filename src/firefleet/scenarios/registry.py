"""Registry of the built-in scenarios (``scenarios/builtin/*.yaml``)."""

from __future__ import annotations

import difflib
from importlib import resources
from pathlib import Path

from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario, read_scenario_file

__all__ = ["builtin_names", "load_scenario"]

_BUILTIN = resources.files("firefleet.scenarios") / "builtin"


def builtin_names() -> list[str]:
    """Names of the built-in scenarios, sorted.

    Examples
    --------
    >>> from firefleet.scenarios import builtin_names
    >>> names = builtin_names()
    >>> "motor-pid" in names, names == sorted(names)
    (True, True)
    """
    return sorted(
        p.name.removesuffix(".yaml") for p in _BUILTIN.iterdir() if p.name.endswith(".yaml")
    )


def load_scenario(name_or_path: str | Path) -> Scenario:
    """A built-in scenario by name, or a scenario YAML file by path.

    A string ending in ``.yaml`` / ``.yml`` or containing a path separator is a path.

    Raises
    ------
    InputError
        For an unknown name (with the closest built-in names) or a bad file.

    Examples
    --------
    >>> from firefleet.scenarios import load_scenario
    >>> load_scenario("motor-pid").command.kind
    'wheel-speed-step'
    >>> try:
    ...     load_scenario("motor-pdi")
    ... except ValueError as error:
    ...     print(str(error).split(";")[0], "motor-pid" in str(error))
    unknown scenario 'motor-pdi' True
    """
    text = str(name_or_path)
    if isinstance(name_or_path, Path) or text.endswith((".yaml", ".yml")) or "/" in text:
        return read_scenario_file(name_or_path)
    names = builtin_names()
    if text not in names:
        close = difflib.get_close_matches(text, names, n=3, cutoff=0.5)
        hint = f"; did you mean {', '.join(close)}?" if close else ""
        raise InputError(
            f"unknown scenario {text!r}{hint} (built-in: {', '.join(names)}; or give a .yaml path)"
        )
    with resources.as_file(_BUILTIN / f"{text}.yaml") as path:
        scenario = read_scenario_file(path)
    if scenario.name != text:
        raise InputError(f"built-in file {text}.yaml names itself {scenario.name!r}")
    return scenario

"""The sweep's points: ``--set KEY=V1,V2,...`` and ``--seeds A:B`` parsed and checked.

A key is any scenario key by its dotted path (``command.speed_rad_s``, ``link.loss``,
``poses``, ``paths[0].x_end_m``); each point's scenario is the base scenario's plain data
with the point's values put in and validated by the scenario schema
(:func:`firefleet.scenarios.parse_scenario`), so a misspelt key gets the schema's own
did-you-mean and a new key of the schema works without any change here.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pydantic
import yaml

from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario, parse_scenario

__all__ = [
    "Point",
    "SweepAxis",
    "parse_seeds",
    "parse_set",
    "points_of",
    "scenario_data",
]

_DUMP = pydantic.TypeAdapter(Scenario)
_EXPONENT = re.compile(r"[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9]+)[eE][-+]?[0-9]+")


@dataclass(frozen=True)
class SweepAxis:
    """One swept key and its values.

    Attributes
    ----------
    key : str
        The dotted scenario key as typed (``command.speed_rad_s``).
    values : tuple
        Plain data (numbers, strings, lists, maps), one per point along the axis.
    labels : tuple of str
        How each value is shown in tables and plots (the text typed, ``@team20.yaml``).
    """

    key: str
    values: tuple[Any, ...]
    labels: tuple[str, ...]


@dataclass(frozen=True)
class Point:
    """One parameter point of a sweep: its values and its validated scenario.

    Attributes
    ----------
    index : int
        Position in the sweep (rows sort by it, then by seed).
    values : mapping of str to object
        Swept key -> value (plain data) at this point.
    labels : mapping of str to str
        Swept key -> the value as shown.
    scenario : Scenario
        The base scenario with this point's values.
    digest : str
        A hash of the point's whole validated scenario: a finished run is reused
        on resume only when its point's digest and seed match.
    """

    index: int
    values: Mapping[str, Any]
    labels: Mapping[str, str]
    scenario: Scenario
    digest: str


def _split_top(text: str) -> list[str]:
    """Split at commas outside brackets, braces and quotes (``[1, 2],[3, 4]`` is two)."""
    parts: list[str] = []
    depth, quote, start = 0, "", 0
    for i, ch in enumerate(text):
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append(text[start:i])
            start = i + 1
    parts.append(text[start:])
    return [p.strip() for p in parts]


def _value(text: str, flag: str, base: Path) -> Any:
    """A typed value: YAML (``2``, ``0.1``, ``1e3``, ``[0, 1, 90]``) or ``@file.yaml``."""
    if text.startswith("@"):
        path = Path(text[1:])
        path = path if path.is_absolute() else base / path
        try:
            return yaml.safe_load(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise InputError(f"{flag}: {text}: no such file") from None
        except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
            detail = str(exc).replace("\n", " ")
            raise InputError(f"{flag}: {text}: cannot read as YAML: {detail}") from None
    try:
        value = yaml.safe_load(text)
    except yaml.YAMLError:
        raise InputError(f"{flag}: {text!r} is not a value (a number, a word, a [list])") from None
    if isinstance(value, str) and _EXPONENT.fullmatch(value):
        return float(value)  # YAML 1.1 reads 1e3 as a string; a person means a number
    return value


def parse_set(text: str, *, base: Path | None = None) -> SweepAxis:
    """Parse one ``--set KEY=V1,V2,...`` into an axis (the key is checked later, on points).

    Parameters
    ----------
    text : str
        As typed after ``--set``.
    base : Path, optional
        Folder ``@file`` values are read relative to (default: the current one).

    Raises
    ------
    InputError
        Naming ``--set`` and the text when there is no ``=``, no key or no value.

    Examples
    --------
    >>> from firefleet.sweep import parse_set
    >>> axis = parse_set("command.speed_rad_s=1,2.5,1e1,0e0")
    >>> axis.key, axis.values, axis.labels
    ('command.speed_rad_s', (1, 2.5, 10.0, 0.0), ('1', '2.5', '1e1', '0e0'))
    >>> parse_set("poses=[[0, 0, 0]],[[0, 0, 0], [1, 0, 0]]").values[1]
    [[0, 0, 0], [1, 0, 0]]
    """
    flag = f"--set {text}"
    key, eq, values = text.partition("=")
    key = key.strip()
    if not eq or not key:
        raise InputError(f"{flag}: expected KEY=V1,V2,... (e.g. command.speed_rad_s=1,2)")
    labels = _split_top(values)
    if not values.strip() or any(not label for label in labels):
        raise InputError(f"{flag}: an empty value; expected KEY=V1,V2,...")
    here = base if base is not None else Path.cwd()
    return SweepAxis(key, tuple(_value(v, flag, here) for v in labels), tuple(labels))


def parse_seeds(text: str, flag: str = "--seeds") -> tuple[int, ...]:
    """Seeds from ``A:B`` (``A`` to ``B - 1``, as Python's range), ``N`` or ``N,M,...``.

    Raises
    ------
    InputError
        For a malformed, negative or empty range, naming the flag.

    Examples
    --------
    >>> from firefleet.sweep import parse_seeds
    >>> parse_seeds("0:4"), parse_seeds("7"), parse_seeds("3,1")
    ((0, 1, 2, 3), (7,), (1, 3))
    """
    try:
        if ":" in text:
            low, _, high = text.partition(":")
            seeds = tuple(range(int(low), int(high)))
        else:
            seeds = tuple(sorted({int(part) for part in text.split(",")}))
    except ValueError:
        raise InputError(f"{flag} {text}: expected A:B (seeds A to B-1), N or N,M,...") from None
    if not seeds:
        raise InputError(f"{flag} {text}: an empty range of seeds; expected A:B with A < B")
    if seeds[0] < 0:
        raise InputError(f"{flag} {text}: seeds must be >= 0")
    return seeds


def scenario_data(scenario: Scenario) -> dict[str, Any]:
    """A scenario as plain data (what its YAML would load to), headings in degrees."""
    data: dict[str, Any] = _DUMP.dump_python(scenario, mode="json")
    return data


def _path(key: str) -> list[str | int]:
    """``paths[0].x_end_m`` -> ``["paths", 0, "x_end_m"]``."""
    parts: list[str | int] = []
    for piece in key.replace("[", ".[").split("."):
        if piece.startswith("[") and piece.endswith("]") and piece[1:-1].isdigit():
            parts.append(int(piece[1:-1]))
        elif piece.isdigit():
            parts.append(int(piece))
        elif piece:
            parts.append(piece)
        else:
            raise InputError(f"--set {key}: not a dotted key (such as command.speed_rad_s)")
    return parts


def _put(data: Any, key: str, value: Any) -> None:
    """Put ``value`` at the dotted ``key`` in ``data``, making missing maps on the way."""
    parts = _path(key)
    node = data
    for depth, part in enumerate(parts[:-1]):
        nxt = parts[depth + 1]
        if isinstance(part, int):
            if not isinstance(node, list) or not -len(node) <= part < len(node):
                where = key.split("[")[0] if depth == 0 else key
                raise InputError(f"--set {key}: no item [{part}] in {where}")
            if node[part] is None:
                node[part] = [] if isinstance(nxt, int) else {}
            node = node[part]
        else:
            if not isinstance(node, dict):
                raise InputError(f"--set {key}: {part!r} is not a key of a map here")
            if node.get(part) is None:  # an optional block (link: {...}) made on the way
                node[part] = [] if isinstance(nxt, int) else {}
            node = node[part]
    last = parts[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or not -len(node) <= last < len(node):
            raise InputError(f"--set {key}: no item [{last}] there")
        node[last] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise InputError(f"--set {key}: {last!r} is not a key of a map here")


def _digest(data: Mapping[str, Any]) -> str:
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def points_of(
    base: Scenario, axes: Sequence[SweepAxis], *, zipped: bool = False
) -> tuple[Point, ...]:
    """Every point of the sweep, each scenario validated before anything runs.

    Parameters
    ----------
    base : Scenario
        The scenario swept.
    axes : sequence of SweepAxis
        The ``--set`` axes; none gives the one point of the base scenario.
    zipped : bool
        Pair the axes' values (all the same length) instead of their grid (product).

    Raises
    ------
    InputError
        For an unknown key (with the schema's did-you-mean) or a bad value, naming the
        ``--set`` it came from; for zipped axes of different lengths; for a key set twice.

    Examples
    --------
    >>> from firefleet import load_scenario
    >>> from firefleet.sweep import parse_set, points_of
    >>> axes = [parse_set("command.speed_rad_s=1,2"), parse_set("load.torque_n_m=0,0.5")]
    >>> points = points_of(load_scenario("motor-pid"), axes)
    >>> [(p.index, p.scenario.command.speed_rad_s, p.scenario.load.torque_n_m) for p in points]
    [(0, 1.0, 0.0), (1, 1.0, 0.5), (2, 2.0, 0.0), (3, 2.0, 0.5)]
    >>> len(points_of(load_scenario("motor-pid"), axes, zipped=True))
    2
    """
    keys = [axis.key for axis in axes]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise InputError(f"--set {twice[0]}: set twice; give all its values in one --set")
    if zipped and axes:
        lengths = {axis.key: len(axis.values) for axis in axes}
        if len(set(lengths.values())) > 1:
            shown = ", ".join(f"{k} ({n})" for k, n in lengths.items())
            raise InputError(f"--zip: every --set needs as many values; got {shown}")
        combos: list[tuple[int, ...]] = [(i,) * len(axes) for i in range(len(axes[0].values))]
    else:
        combos = list(itertools.product(*(range(len(axis.values)) for axis in axes)))
    data = scenario_data(base)
    points = []
    for index, combo in enumerate(combos):
        point_data = json.loads(json.dumps(data))
        for axis, k in zip(axes, combo, strict=True):
            _put(point_data, axis.key, axis.values[k])
        try:
            scenario = parse_scenario(point_data, origin="--set")
        except InputError as exc:
            shown = ", ".join(f"{a.key}={a.labels[k]}" for a, k in zip(axes, combo, strict=True))
            first = str(exc).splitlines()[0].removeprefix("--set: ")
            raise InputError(f"--set {shown}: {first}") from None
        points.append(
            Point(
                index=index,
                values={a.key: a.values[k] for a, k in zip(axes, combo, strict=True)},
                labels={a.key: a.labels[k] for a, k in zip(axes, combo, strict=True)},
                scenario=scenario,
                digest=_digest(scenario_data(scenario)),  # 1 and 1.0 alike
            )
        )
    return tuple(points)

"""``dataclasses.replace`` for the tactics' frozen states, without their constructors.

The team's tactics and navigation replace fields of their frozen states (``TacticsState``
has 40 fields, ``NavigationState`` 20) some 60,000 times in 300 simulated seconds of
mission-office; ``dataclasses.replace`` walks the fields and runs the generated
``__init__``, which sets each field through ``object.__setattr__``. :func:`replace` makes
the same object (the same field values, the untouched ones shared, as
``dataclasses.replace`` shares them) by copying the instance's dict.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, TypeVar

__all__ = ["replace"]

_T = TypeVar("_T")


@functools.cache
def _plain_fields(cls: type) -> frozenset[str]:
    """The field names of ``cls`` when its instances are just their fields (every field
    set by the constructor, no ``__post_init__``, no ``InitVar``, no slots); else empty
    (``dataclasses.replace`` then)."""
    if not dataclasses.is_dataclass(cls) or hasattr(cls, "__post_init__"):
        return frozenset()
    if "__slots__" in cls.__dict__ or not hasattr(cls, "__dict__"):
        return frozenset()
    names = []
    for f in dataclasses.fields(cls):  # InitVar and ClassVar are not in fields()
        if not f.init:
            return frozenset()
        names.append(f.name)
    if len(getattr(cls, dataclasses._FIELDS)) != len(names):  # type: ignore[attr-defined]
        return frozenset()  # an InitVar: the constructor does more than set fields
    return frozenset(names)


def replace(obj: _T, /, **changes: Any) -> _T:
    """``dataclasses.replace(obj, **changes)``: a new instance with the fields in
    ``changes`` set and the others ``obj``'s.

    For a dataclass whose instances are just their fields (module notes) the new
    instance is made by copying ``obj``'s dict, without the constructor; any other
    object, a name that is no field, or an instance holding more than its fields goes
    to ``dataclasses.replace``.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class P:
    ...     x: float
    ...     y: float = 0.0
    >>> p = replace(P(1.0, 2.0), y=3.0)
    >>> p, p == P(1.0, 3.0)
    (P(x=1.0, y=3.0), True)
    """
    cls: type = type(obj)
    names = _plain_fields(cls)
    old = getattr(obj, "__dict__", None)
    if not names or old is None or len(old) != len(names) or not changes.keys() <= names:
        return dataclasses.replace(obj, **changes)  # type: ignore[type-var]
    new: _T = object.__new__(cls)
    new.__dict__.update(old)
    new.__dict__.update(changes)
    return new

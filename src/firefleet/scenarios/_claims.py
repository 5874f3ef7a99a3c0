"""A claim about one metric of a run, checked after the run (every scenario's claims)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import pydantic

from firefleet.errors import InputError

_STRICT = pydantic.ConfigDict(extra="forbid")
_CLAIM_OPS = ("<", "<=", ">", ">=", "~")


@pydantic.dataclasses.dataclass(frozen=True, config=_STRICT)
class Claim:
    """A claim about one metric, checked after the run.

    Attributes
    ----------
    metric : str
        Metric name (a key of ``metrics.json``).
    op : {"<", "<=", ">", ">=", "~"}
        Comparison; ``"~"`` means within ``rel_tol`` (relative) of ``value``.
    value : float
        The bound or the target.
    rel_tol : float
        Relative tolerance of ``"~"``.
    source : str
        Where the claim comes from (the deliverable's section or the issue).
    robot : int, optional
        For a per-robot metric (a list in ``metrics.json``): the robot it is about,
        numbered from 1 as the deliverable numbers them. Without it, a claim on a
        per-robot metric must hold for every robot.

    Examples
    --------
    >>> from firefleet.scenarios import Claim
    >>> claim = Claim(metric="steady_speed_rad_s", op="~", value=1.3955, rel_tol=0.005)
    >>> claim.expected, claim.holds(1.40), claim.holds(1.45)
    ('1.3955 ± 0.00698', True, False)
    >>> per_robot = Claim(metric="wait_time_s", op="<", value=1.0, robot=2)
    >>> per_robot.label, per_robot.holds([5.0, 0.5])
    ('wait_time_s[robot 2]', True)
    """

    metric: str
    op: Literal["<", "<=", ">", ">=", "~"]
    value: float
    rel_tol: float = 0.0
    source: str = ""
    robot: int | None = None

    def __post_init__(self) -> None:
        if self.robot is not None and self.robot < 1:
            raise InputError(f"claim on {self.metric}: robot is numbered from 1, got {self.robot}")
        if self.op == "~" and not self.rel_tol > 0:
            raise InputError(f"claim on {self.metric}: op '~' needs rel_tol > 0")
        if self.op != "~" and self.rel_tol != 0:
            raise InputError(f"claim on {self.metric}: rel_tol is only for op '~'")

    @property
    def label(self) -> str:
        """The metric as claimed, e.g. ``"wait_time_s"`` or ``"wait_time_s[robot 2]"``."""
        return self.metric if self.robot is None else f"{self.metric}[robot {self.robot}]"

    def select(self, measured: float | Sequence[float] | None) -> float | list[float] | None:
        """The part of a metric's value this claim is about (the robot's entry, if any)."""
        if self.robot is None or measured is None:
            return None if measured is None else _plain(measured)
        if isinstance(measured, int | float):
            return None
        return float(measured[self.robot - 1]) if self.robot <= len(measured) else None

    @property
    def expected(self) -> str:
        """The claim as a person reads it, in the metric's own unit, e.g. ``"< 0.2"`` or
        ``"1.3955 +- 0.00698"`` (the tolerance ``rel_tol |value|``, in the value's unit)."""
        if self.op == "~":
            return f"{self.value:g} \u00b1 {self.rel_tol * abs(self.value):.3g}"
        return f"{self.op} {self.value:g}"

    def holds(self, measured: float | Sequence[float] | None) -> bool:
        """Whether the metric's value satisfies the claim.

        ``measured`` is the whole metric (a number, or one number per robot); a missing
        or NaN value does not satisfy any claim, and a per-robot list satisfies it only
        if every robot's entry does (or the claimed robot's, with ``robot``).
        """
        value = self.select(measured)
        if isinstance(value, list):
            return bool(value) and all(self._holds_one(v) for v in value)
        return self._holds_one(value)

    def _holds_one(self, measured: float | None) -> bool:
        if measured is None or math.isnan(measured):
            return False
        if self.op == "~":
            return abs(measured - self.value) <= self.rel_tol * abs(self.value)
        compare = {
            "<": measured < self.value,
            "<=": measured <= self.value,
            ">": measured > self.value,
            ">=": measured >= self.value,
        }
        return bool(compare[self.op])


def _plain(value: float | Sequence[float]) -> float | list[float]:
    return float(value) if isinstance(value, int | float) else [float(v) for v in value]

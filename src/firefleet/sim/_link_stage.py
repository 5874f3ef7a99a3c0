"""The world loop's link stage: its protocol and the ideal link (:mod:`firefleet.sim.loop`);
:mod:`firefleet.sim.link` models a real radio."""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Protocol

from firefleet._typing import FloatArray
from firefleet.scenarios.schema import Scenario

__all__ = ["IdealLink", "Link", "link_impaired"]

Messages = Mapping[str, FloatArray]


@dataclass(frozen=True)
class IdealLink:
    """Every message arrives, unchanged, at the next tick."""

    def init(self, n_robots: int, dt_s: float) -> None:
        """Nothing to hold."""

    def exchange(
        self, state: None, sent: Messages, t_s: float, pose: FloatArray
    ) -> tuple[Messages, None]:
        """The messages delivered this tick: all those sent last tick."""
        return sent, None

    def counters(self, state: None) -> dict[str, float]:
        """No counters: the ideal link loses nothing."""
        return {}


class Link(Protocol):
    """The link stage: the messages sent last tick, as the receivers hold them now
    (:mod:`firefleet.sim.link` models a real radio)."""

    def init(self, n_robots: int, dt_s: float) -> Any: ...

    def exchange(
        self, state: Any, sent: Messages, t_s: float, pose: FloatArray
    ) -> tuple[Messages, Any]: ...

    def counters(self, state: Any) -> dict[str, float]: ...


def link_impaired(scenario: Scenario) -> bool:
    """Whether the scenario's link is anything but the ideal one (then the staged loop
    runs it; the compiled loops know only the ideal link).

    Examples
    --------
    >>> import dataclasses
    >>> from firefleet import load_scenario
    >>> from firefleet.scenarios.schema import LinkSpec
    >>> scenario = load_scenario("coop-different-paths")
    >>> link_impaired(scenario), link_impaired(dataclasses.replace(scenario, link=LinkSpec()))
    (False, False)
    >>> link_impaired(dataclasses.replace(scenario, link=LinkSpec(loss=0.1)))
    True
    """
    spec = scenario.link
    if spec is None:
        return False
    given = dataclasses.asdict(spec)
    given.pop("preset")
    given.pop("timeout_s")
    return spec.preset != "ideal" or any(v is not None for v in given.values())

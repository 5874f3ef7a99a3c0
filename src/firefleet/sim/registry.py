"""The registry of task kinds: what a scenario's ``command.kind`` runs, measures and draws.

A task kind (a motor step, path following, formation; later navigation, a mission) is
one :class:`TaskKind`: the ``kind`` string of its scenario command, its decision step
on the world loop (:mod:`firefleet.sim.loop`), the metrics it declares and computes,
and the figures it draws. The simulator, the metrics, the report and the scenario
schema look a kind up here by its ``kind`` string; nothing else dispatches on the kind
of a command.

The built-in kinds live in :mod:`firefleet.sim.kinds`, one module each; every module
there lists its kinds in a module-level ``KINDS`` tuple and is found when a kind is
first looked up, so adding a kind touches its module and its scenarios only. A kind
from elsewhere joins with :func:`register` (as in Gymnasium's ``register``).

Examples
--------
>>> from firefleet.sim.registry import task_kind
>>> kind = task_kind("wheel-speed-step")
>>> kind.metric_names[:3]
('rise_time_s', 'settling_time_s', 'overshoot_pct')
"""

from __future__ import annotations

import functools
import importlib
import pkgutil
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from firefleet.errors import InputError

if TYPE_CHECKING:
    from firefleet.scenarios.schema import Scenario
    from firefleet.sim.loop import Decider, FusedRun, ProgressCallback, StagesFactory
    from firefleet.sim.result import SimResult

__all__ = ["Metrics", "TaskKind", "kind_names", "register", "task_kind"]

Metrics = dict[str, float | list[float]]
"""Named numbers of a run: a float, or one float per robot (a list, robot 1 first)."""

Runner = Callable[["Scenario", NDArray[np.int64], "ProgressCallback | None"], "SimResult"]
"""``result = runner(scenario, rec_steps, progress)``: a kind's own loop."""


@dataclass(frozen=True)
class TaskKind:
    """A kind of task: how a scenario with this ``command.kind`` runs and is judged.

    Attributes
    ----------
    name : str
        The scenario command's ``kind`` string (``"path-following"``).
    metric_names : tuple of str
        The metrics ``metrics`` returns, the names claims may use.
    metrics : callable
        ``metrics(result) -> dict``: the named numbers of a run.
    figures : callable
        ``figures(result, metrics) -> {file name: PNG bytes}``; imports matplotlib
        (from :mod:`firefleet.report`) only when called.
    decider : Decider, optional
        The kind's decision on the world loop (:class:`firefleet.sim.loop.Decider`).
    fused : callable, optional
        A compiled loop for the default stages (:data:`firefleet.sim.loop.FusedRun`).
    runner : callable, optional
        For a kind that runs its own loop instead of a ``decider`` (exactly one of the
        two): ``runner(scenario, rec_steps, progress) -> SimResult``.
    stages : callable, optional
        The kind's own stages (:data:`firefleet.sim.loop.StagesFactory`:
        ``stages(scenario, decider, rng) -> Stages``), instead of
        :func:`~firefleet.sim.loop.default_stages`; such a kind has no fused loop.
    list_items : tuple of (str, str), optional
        The list metrics whose values are not one per robot, with what one value is
        about: ``(("victims_found_s", "victim"),)``. Other lists are per robot.

    Examples
    --------
    >>> from firefleet.sim.registry import task_kind
    >>> kind = task_kind("path-following")
    >>> kind.name, kind.decider is not None, kind.runner is None
    ('path-following', True, True)
    """

    name: str
    metric_names: tuple[str, ...]
    metrics: Callable[[SimResult], Metrics]
    figures: Callable[[SimResult, Metrics], dict[str, bytes]]
    decider: Decider | None = None
    fused: FusedRun | None = None
    runner: Runner | None = None
    stages: StagesFactory | None = None
    list_items: tuple[tuple[str, str], ...] = ()

    def __post_init__(self) -> None:
        if (self.decider is None) == (self.runner is None):
            raise InputError(f"task kind {self.name!r}: give a decider or a runner, not both")
        if self.fused is not None and self.decider is None:
            raise InputError(f"task kind {self.name!r}: a fused loop needs a decider")
        if self.stages is not None and (self.decider is None or self.fused is not None):
            raise InputError(f"task kind {self.name!r}: own stages need a decider, no fused loop")

    def run(
        self,
        scenario: Scenario,
        rec_steps: NDArray[np.int64],
        progress: ProgressCallback | None = None,
        *,
        staged: bool = False,
    ) -> SimResult:
        """Run ``scenario`` (whose command is of this kind), recording ``rec_steps``.

        ``staged``: run the world loop stage by stage even where the kind has a fused
        loop (a kind with its own ``runner`` ignores it).
        """
        if self.runner is not None:
            return self.runner(scenario, rec_steps, progress)
        from firefleet.sim.loop import default_stages, run_loop

        assert self.decider is not None  # __post_init__
        if self.stages is not None:
            return run_loop(
                scenario, self.decider, rec_steps, make_stages=self.stages, progress=progress
            )
        stages = default_stages(scenario, self.decider) if staged else None
        return run_loop(
            scenario, self.decider, rec_steps, fused=self.fused, stages=stages, progress=progress
        )


@functools.cache
def _builtin() -> dict[str, TaskKind]:
    """The kinds of :mod:`firefleet.sim.kinds`, by name (imported on first use)."""
    from firefleet.sim import kinds

    found: dict[str, TaskKind] = {}
    for info in pkgutil.iter_modules(kinds.__path__):
        if info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{kinds.__name__}.{info.name}")
        for kind in getattr(module, "KINDS", ()):
            if kind.name in found:
                raise InputError(f"task kind {kind.name!r} is defined twice")
            found[kind.name] = kind
    return found


_REGISTERED: dict[str, TaskKind] = {}
"""Kinds added with :func:`register` (the built-in ones are found in their package)."""


def register(kind: TaskKind) -> None:
    """Add a task kind, for scenarios whose ``command.kind`` is ``kind.name``.

    Raises
    ------
    InputError
        If a kind of that name exists already.

    Examples
    --------
    >>> from firefleet.errors import InputError
    >>> from firefleet.sim.registry import register, task_kind
    >>> try:
    ...     register(task_kind("wheel-speed-step"))
    ... except InputError as error:
    ...     print(error)
    task kind 'wheel-speed-step' is registered already
    """
    if kind.name in _builtin() or kind.name in _REGISTERED:
        raise InputError(f"task kind {kind.name!r} is registered already")
    _REGISTERED[kind.name] = kind


def kind_names() -> tuple[str, ...]:
    """Names of every known task kind, sorted.

    Examples
    --------
    >>> from firefleet.sim.registry import kind_names
    >>> "wheel-speed-step" in kind_names(), kind_names() == tuple(sorted(kind_names()))
    (True, True)
    """
    return tuple(sorted({*_builtin(), *_REGISTERED}))


def task_kind(name: str) -> TaskKind:
    """The task kind of a scenario command's ``kind`` string.

    Raises
    ------
    InputError
        For an unknown kind, listing the known ones.

    Examples
    --------
    >>> from firefleet.sim.registry import task_kind
    >>> task_kind("formation").name
    'formation'
    """
    kind = _builtin().get(name) or _REGISTERED.get(name)
    if kind is None:
        raise InputError(f"command.kind: unknown kind {name!r}; known: {', '.join(kind_names())}")
    return kind

"""The simulator's entry point: run a scenario on its task kind.

The scenario's ``command.kind`` names a task kind (:mod:`firefleet.sim.registry`); the
kind runs on the world loop (:mod:`firefleet.sim.loop`): each tick world, sensors,
link, estimation, the kind's decision, the wheel stack (:mod:`firefleet.sim.drive`),
the recorder, for the whole team at once.

Randomness (the encoders' unknown initial phase) comes from one
``numpy.random.Generator`` seeded with the scenario's ``seed``: same seed, same arrays,
bit for bit.
"""

from __future__ import annotations

import dataclasses
from typing import Literal

import numpy as np

from firefleet.errors import InputError
from firefleet.scenarios.schema import Scenario
from firefleet.sim.loop import ProgressCallback
from firefleet.sim.registry import task_kind
from firefleet.sim.result import SimResult

__all__ = ["ProgressCallback", "simulate"]


def simulate(
    scenario: Scenario,
    *,
    seed: int | None = None,
    record_every: int = 1,
    progress: ProgressCallback | None = None,
    backend: Literal["auto", "array"] = "auto",
) -> SimResult:
    """Run a scenario.

    Parameters
    ----------
    scenario : Scenario
        The experiment.
    seed : int, optional
        Overrides ``scenario.seed``.
    record_every : int
        Record every k-th step (and the last); 1 records them all.
    progress : callable, optional
        ``progress(done, total)``, for a progress bar.
    backend : {"auto", "array"}
        ``"auto"``: the kind's compiled loop where it has one (for the default stages);
        ``"array"``: the staged loop, each stage a NumPy function on the team's arrays
        (the reference the compiled loops are tested against).

    Returns
    -------
    SimResult
        The recorded run; its ``scenario`` carries the seed used.

    Examples
    --------
    >>> import firefleet
    >>> result = firefleet.simulate(firefleet.load_scenario("motor-open-loop"), record_every=100)
    >>> result.pose.shape  # 10 s at 10 ms, every 100th step and the last; one robot
    (11, 1, 3)
    """
    if seed is not None:
        if seed < 0:
            raise InputError(f"seed must be >= 0, got {seed}")
        scenario = dataclasses.replace(scenario, seed=seed)
    if record_every < 1:
        raise InputError(f"record_every must be >= 1, got {record_every}")
    if backend not in ("auto", "array"):
        raise InputError(f"backend must be 'auto' or 'array', got {backend!r}")
    n_steps = scenario.n_steps
    rec_steps = np.arange(0, n_steps + 1, record_every)
    if rec_steps[-1] != n_steps:  # the last step is always recorded
        rec_steps = np.r_[rec_steps, n_steps]
    kind = task_kind(scenario.command.kind)
    return kind.run(scenario, rec_steps, progress, staged=backend == "array")

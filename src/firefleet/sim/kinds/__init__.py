"""The built-in task kinds, one module each (see :mod:`firefleet.sim.registry`).

Each module lists its kinds in a module-level ``KINDS`` tuple of
:class:`~firefleet.sim.registry.TaskKind`; the registry finds them on first lookup.

To add a kind (say ``navigate``):

1. its command, a frozen pydantic dataclass with ``kind: Literal["navigate"]``, joins
   the ``Command`` union in ``scenarios/_commands.py`` (for now the one line
   outside the kind's module);
2. ``kinds/navigate.py`` holds the decision, ``new_state, command = decide(state,
   inputs, params, dt_s)`` on the world loop (:class:`firefleet.sim.loop.Decider`; it
   sees the time, the pose estimate, the sensors' readings and the link's messages, and
   returns wheel references and the series to record), the metric names and the metrics
   function, and a figures function that imports its matplotlib code from
   :mod:`firefleet.report` when called; optionally a compiled chunk for the default
   stages (:data:`firefleet.sim.loop.FusedRun`), shown equal to the staged loop by
   ``tests/sim/test_loop.py``;
3. ``KINDS = (TaskKind(name="navigate", ...),)`` at the end of the module;
4. its scenarios in ``scenarios/builtin/``.
"""

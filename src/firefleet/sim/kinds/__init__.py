"""The built-in task kinds, one module each (see :mod:`firefleet.sim.registry`).

Each module lists its kinds in a module-level ``KINDS`` tuple of
:class:`~firefleet.sim.registry.TaskKind`; the registry finds them on first lookup.
"""

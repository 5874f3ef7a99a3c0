"""When a team kernel spreads its robots over every core."""

PARALLEL_MIN_ROBOTS = 64
"""Teams at least this large run their robots on every core (they are independent, so
the result is the same bit for bit); smaller ones on one, where starting the threads for
each piece of a run costs more than they bring (on a busy machine a sleeping thread can
take milliseconds to wake)."""

PARALLEL_MIN_ROBOTS_ONE_PIECE = 2
"""The same for a path-following run in one piece (no progress callback), where the
threads start once for the whole run: from two robots, robots run on every core
(coop-different-paths, 3 robots on 2 cores: kernel 5.6 ms against 9.9 ms serial).

Processes: numba's default threading layer here is GNU OpenMP, and a process that has
run a parallel kernel and then forks (a ``multiprocessing`` pool with the "fork" start
method) has its children killed when they run one ("fork() called from a process
already using GNU OpenMP"). Start worker processes with "spawn" or "forkserver" (Dask
does; Python 3.14 makes "forkserver" the default), or set
``NUMBA_THREADING_LAYER=workqueue`` (fork-safe; 6.5 ms for the same run)."""

"""The ``firefleet`` command line: one module per command group.

``_main`` holds the parser and :func:`main` (bad input -> one line on stderr, exit 2);
``_console`` the exit statuses, the progress bar and the claims table every command
shares; ``_run`` (list, run, validate, reproduce), ``_fis``, ``_thermal``, ``_stereo``
(stereo, capture) and ``_slam`` one command group each, with its ``add_parsers``.
"""

from firefleet.cli._main import main

__all__ = ["main"]

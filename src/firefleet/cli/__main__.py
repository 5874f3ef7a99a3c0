"""``python -m firefleet.cli``: the ``firefleet`` command."""

import sys

from firefleet.cli._main import main

sys.exit(main())

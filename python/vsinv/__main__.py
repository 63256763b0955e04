"""``python -m vsinv``: the command-line interface (see :mod:`vsinv.cli`)."""

import sys

from .cli import main

sys.exit(main())

"""``python -m jaxdamp``: the command line (same as the ``jaxdamp`` script)."""

import sys

from .cli import main

sys.exit(main())

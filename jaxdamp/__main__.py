"""``python -m jaxdamp``: the command line (same as the ``jaxdamp`` script)."""

import sys

from jaxdamp.cli import main

sys.exit(main())

"""``python -m experiments.scoreboard``: see :mod:`experiments.scoreboard`."""

import sys

from experiments.scoreboard import main

sys.exit(main())

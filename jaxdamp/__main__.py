"""``python -m jaxdamp``: the command line (same as the ``jaxdamp`` script)."""

from jaxdamp.cli import entry

entry()

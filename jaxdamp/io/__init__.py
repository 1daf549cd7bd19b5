"""Every file jaxdamp writes, one module per kind (schemas in ``docs/output.md``).

* :mod:`~jaxdamp.io.common` — what all files share: root attributes (:func:`stamp`), datasets
  with units (:func:`put`), appendable datasets, the checkpoint form of a state, and the
  steady-state estimates group (:func:`write_steady`).
* :mod:`~jaxdamp.io.runfile` — run files (``jaxdamp run``): one system, resumable.
* :mod:`~jaxdamp.io.sweepfile` — sweep files (``jaxdamp run --replicates``, ``frf``,
  ``efficiency``, :func:`jaxdamp.sweep.sweep`, S3 sweeps): a grid × replicates, resumable.
* :mod:`~jaxdamp.io.efficiency` — the ``/efficiency`` analysis inside a sweep file.
* :mod:`~jaxdamp.io.optimisation` — optimiser and search logs (``jaxdamp optimize``).
"""

from .common import arrays_to_state, put, stamp, state_to_arrays, write_steady
from .runfile import RunFile, describe, read_config

__all__ = ["RunFile", "arrays_to_state", "describe", "put", "read_config", "stamp",
           "state_to_arrays", "write_steady"]

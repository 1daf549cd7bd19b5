"""Every file jaxdamp writes, one module per kind (schemas in ``docs/output.md``).

* :mod:`~jaxdamp.io.common` — what all files share: root attributes (:func:`stamp`), datasets
  with units (:func:`put`), appendable datasets and the steady-state estimates group
  (:func:`write_steady`).
* :mod:`~jaxdamp.io.runfile` — run files (``jaxdamp run``): one system, resumable.
* :mod:`~jaxdamp.io.sweepfile` — sweep files (``jaxdamp run --replicates``, ``frf``,
  ``efficiency``, :func:`jaxdamp.studies.sweep.sweep`, S3 sweeps): a grid × replicates, resumable.
* :mod:`~jaxdamp.io.efficiency` — the ``/efficiency`` analysis inside a sweep file.
* :mod:`~jaxdamp.io.optimisation` — optimiser and search logs (``jaxdamp optimize``).
* :mod:`~jaxdamp.io.export` — reading any output file for figures, and XYZ/VTK/GIF export.
* :mod:`~jaxdamp.io.describe` — ``jaxdamp info``: any file above, by its ``format``.
"""

from jaxdamp.io.common import put, stamp, write_steady
from jaxdamp.io.describe import describe
from jaxdamp.io.runfile import RunFile, read_config

__all__ = ["RunFile", "describe", "put", "read_config", "stamp", "write_steady"]

"""Studies of a damper built on the driver: a single run, batched sweeps, efficiency.

* :mod:`~jaxdamp.studies.runner` — one run end to end with a resumable run file.
* :mod:`~jaxdamp.studies.grid` — what a sweep is: the grid × replicates and its result.
* :mod:`~jaxdamp.studies.sweep` — every grid point and replicate in one batch, resumable.
* :mod:`~jaxdamp.studies.efficiency` — the dissipation efficiency of a driven box (S2).
* :mod:`~jaxdamp.studies.scaffold` — what every study script shares (``experiments/``): the
  command line, provenance, the result file, figures, tables.
"""

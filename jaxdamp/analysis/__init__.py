"""Analysis of simulated responses.

* :mod:`~jaxdamp.analysis.response` — the analytic FRF and its fit, steady-state summaries of a
  run's fixed window, resonance and optimum helpers.
* :mod:`~jaxdamp.analysis.stats` — per-period series, MSER detection of the steady state,
  replicate statistics.
* :mod:`~jaxdamp.analysis.dynamics` — nonlinear dynamics of the bed (Poincaré sections,
  spectra, embeddings, Kantz exponents, classification).
"""

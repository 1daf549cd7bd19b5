"""Figures (matplotlib, headless: Agg canvases, no pyplot state).

Every figure function returns a :class:`matplotlib.figure.Figure`; :func:`save` writes it.
The ``*_from_file`` functions take an output file (an open :class:`h5py.File` or a path),
check that it holds what the figure needs (:class:`jaxdamp.io.export.OutputFileError` naming the
file and the missing part otherwise) and return a ``Figure`` too; :func:`animate` writes a
GIF/MP4 directly.

Project rule: every axis is labelled, with its unit in brackets (``"time t [s]"``);
dimensionless quantities say what they are a ratio of (``"amplitude ratio Z / U"``).

- :mod:`jaxdamp.figures.style` — the style (:data:`DPI`, :data:`FIGSIZE`,
  :data:`SPECIES_COLOURS`), :func:`figure` and :func:`save`.
- :mod:`jaxdamp.figures.response` — the FRF (:func:`frf_figure`, :func:`frf_from_file`), the
  bed-band plot (:func:`band_figure`, :func:`band_from_file`; :func:`draw_band` into given axes), the energy channels
  (:func:`energy_figure`, :func:`energy_from_file`), free-decay curves (:func:`decay_figure`), random-excitation FRFs with coherence
  (:func:`random_figure`).
- :mod:`jaxdamp.figures.dynamics` — Poincaré sections (:func:`poincare_figure`,
  :func:`poincare_from_file`), spectra (:func:`spectrum_figure`), Kantz's divergence
  (:func:`kantz_figure`).
- :mod:`jaxdamp.figures.bed` — bed snapshots: one panel (:func:`draw_snapshot`), one snapshot
  in 3-D (:func:`snapshot_figure`, :func:`snapshot_from_file`), side views of several beds at
  several instants (:func:`snapshot_grid_figure`), and :func:`animate`.
- :mod:`jaxdamp.figures.efficiency` — dissipation efficiency versus drive amplitude
  (:func:`efficiency_figure`) and phase-resolved panels (:func:`phase_figure`).
- :mod:`jaxdamp.figures.maps` — the damper's effective-field maps with their uncertainty
  (:func:`map_figure`) and the response they predict by harmonic balance
  (:func:`prediction_figure`).
"""

from __future__ import annotations

# -- the public figure functions -------------------------------------------------------------
from jaxdamp.figures.bed import (
    animate,
    draw_snapshot,
    snapshot_figure,
    snapshot_from_file,
    snapshot_grid_figure,
)
from jaxdamp.figures.dynamics import (
    kantz_figure,
    poincare_figure,
    poincare_from_file,
    spectrum_figure,
)
from jaxdamp.figures.efficiency import efficiency_figure, phase_figure
from jaxdamp.figures.maps import map_figure, prediction_figure
from jaxdamp.figures.response import (
    BAND_PERIODS,
    band_figure,
    band_from_file,
    decay_figure,
    draw_band,
    energy_figure,
    energy_from_file,
    frf_figure,
    frf_from_file,
    random_figure,
)
from jaxdamp.figures.style import DPI, FIGSIZE, SPECIES_COLOURS, figure, save  # noqa: F401

__all__ = ["DPI", "FIGSIZE", "SPECIES_COLOURS", "figure", "save",
           "frf_figure", "frf_from_file", "band_figure", "band_from_file", "draw_band", "BAND_PERIODS",
           "energy_figure", "energy_from_file", "decay_figure", "random_figure",
           "poincare_figure", "poincare_from_file", "spectrum_figure", "kantz_figure",
           "draw_snapshot", "snapshot_figure", "snapshot_from_file", "snapshot_grid_figure",
           "animate", "efficiency_figure", "phase_figure", "map_figure",
           "prediction_figure"]

"""Figures (matplotlib, headless: Agg canvases, no pyplot state).

Every figure function returns a :class:`matplotlib.figure.Figure`; :func:`save` writes it.
The ``*_from_file`` functions take an output file (an open :class:`h5py.File` or a path),
check that it holds what the figure needs (:class:`jaxdamp.export.OutputFileError` naming the
file and the missing part otherwise) and return a ``Figure`` too; :func:`animate` writes a
GIF/MP4 directly.

Project rule: every axis is labelled, with its unit in brackets (``"time t [s]"``);
dimensionless quantities say what they are a ratio of (``"amplitude ratio Z / U"``).

- :mod:`jaxdamp.figures.response` — the FRF (:func:`frf_figure`, :func:`frf_from_file`), the
  bed-band plot (:func:`band_figure`, :func:`band_from_file`), the energy channels
  (:func:`energy_figure`, :func:`energy_from_file`).
- :mod:`jaxdamp.figures.dynamics` — Poincaré sections (:func:`poincare_figure`,
  :func:`poincare_from_file`), spectra (:func:`spectrum_figure`), Kantz's divergence
  (:func:`kantz_figure`).
- :mod:`jaxdamp.figures.bed` — bed snapshots: one panel (:func:`draw_snapshot`), one snapshot
  in 3-D (:func:`snapshot_figure`, :func:`snapshot_from_file`), side views of several beds at
  several instants (:func:`snapshot_grid_figure`), and :func:`animate`.
- :mod:`jaxdamp.figures.efficiency` — dissipation efficiency versus drive amplitude
  (:func:`efficiency_figure`) and phase-resolved panels (:func:`phase_figure`).
"""

from __future__ import annotations

import os
import sys

# -- style -------------------------------------------------------------------------------------
#: resolution of every figure [dots per inch]; pixel size = figure size [inch] × DPI
DPI = 120
#: figure sizes [inch] per kind (the snapshot grid grows with its panels)
FIGSIZE = {"frf": (7.0, 4.5), "band": (9.0, 6.0), "energy": (8.0, 7.5),
           "poincare": (6.5, 5.5), "spectrum": (7.0, 4.0), "kantz": (6.0, 4.0),
           "efficiency": (6.5, 4.3), "phase": (13.0, 4.0), "snapshot": (6.0, 8.0),
           "snapshot_panel": (2.6, 2.9), "animation": (5.0, 6.5)}
#: colours of grain species 0, 1, 2, ... (the 2023 paper: red large, green small)
SPECIES_COLOURS = ("tab:red", "tab:green", "tab:blue", "tab:orange", "tab:purple", "tab:brown",
                   "tab:pink", "tab:olive", "tab:cyan", "tab:gray")


def figure(figsize, dpi=DPI, **kwargs):
    """A new :class:`matplotlib.figure.Figure` of ``figsize`` [inch] on an Agg canvas (no
    pyplot, no display); the one place that imports matplotlib's figure machinery. Extra
    keywords go to ``Figure`` (e.g. ``layout="tight"``)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, dpi=dpi, **kwargs)
    FigureCanvasAgg(fig)
    return fig


def save(fig, path, dpi=DPI):
    """Write ``fig`` to ``path`` (PNG unless the extension says otherwise) at exactly
    ``figsize × dpi`` pixels (default :data:`DPI`, whatever the figure's own dpi), creating
    the directory; a pyplot figure is closed afterwards. Returns ``path``.

    Figures must have labelled axes with units (the project rule; the figure functions of
    this package lay themselves out, so ``save`` does not re-arrange anything)."""
    os.makedirs(os.path.dirname(os.path.abspath(path)) or ".", exist_ok=True)
    fig.savefig(path, dpi=dpi)
    if getattr(fig.canvas, "manager", None) is not None and "matplotlib.pyplot" in sys.modules:
        sys.modules["matplotlib.pyplot"].close(fig)
    return path


# -- the public figure functions (imported after the style, which they use) ----------------
from .bed import animate, draw_snapshot, snapshot_figure, snapshot_from_file, snapshot_grid_figure  # noqa: E402
from .dynamics import kantz_figure, poincare_figure, poincare_from_file, spectrum_figure  # noqa: E402
from .efficiency import efficiency_figure, phase_figure  # noqa: E402
from .response import (BAND_PERIODS, band_figure, band_from_file, energy_figure,  # noqa: E402
                       energy_from_file, frf_figure, frf_from_file)

__all__ = ["DPI", "FIGSIZE", "SPECIES_COLOURS", "figure", "save",
           "frf_figure", "frf_from_file", "band_figure", "band_from_file", "BAND_PERIODS",
           "energy_figure", "energy_from_file",
           "poincare_figure", "poincare_from_file", "spectrum_figure", "kantz_figure",
           "draw_snapshot", "snapshot_figure", "snapshot_from_file", "snapshot_grid_figure",
           "animate", "efficiency_figure", "phase_figure"]

"""The figures' style, the one matplotlib entry point (:func:`figure`) and :func:`save`."""

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
           "snapshot_panel": (2.6, 2.9), "animation": (5.0, 6.5),
           "decay": (10.0, 4.0), "random": (7.0, 6.0), "map": (11.0, 8.0)}
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

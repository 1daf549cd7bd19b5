"""The ``/random`` group of a random-excitation sweep file (``jaxdamp random``;
``docs/output.md``)."""

from __future__ import annotations

import h5py
import numpy as np

#: Per-level datasets ``(P, F)`` on the band's lines and their units.
SPECTRA = {"f": "Hz", "H_re": "1", "H_im": "1", "mag": "1", "mag_se": "1", "coherence": "1",
           "Gxx": "m^2/Hz", "Gyy": "m^2/Hz"}
#: Per-level, per-realisation datasets ``(P, R)``.
PER_REALISATION = {"y_rms": "m", "z_rms": "m", "start": "s", "stationary": "1"}


def write(path: str, result) -> None:
    """Store ``result`` (:class:`jaxdamp.studies.random.RandomResult`) in ``/random`` of the
    sweep file ``path``: ``scale`` (P,); ``a_rms`` (P,) base RMS acceleration [m/s²];
    spectra (P, F) on the band's lines (:data:`SPECTRA`: pooled H1 ``z/u`` as real and
    imaginary parts, ``|H1|`` and its SE between realisations, coherence γ², one-sided densities
    of ``u`` and ``z``); per realisation (P, R) (:data:`PER_REALISATION`); ``H_each_re``,
    ``H_each_im`` (P, R, F); attrs ``period``, ``replicates``, ``method``, ``dof`` (the
    degree of freedom whose response ``z`` is, the structure's numbering)."""
    P, R = len(result.scales), result.replicates
    F = max(len(lev["f"]) for lev in result.levels)
    with h5py.File(path, "a") as h5:
        if "random" in h5:
            del h5["random"]
        g = h5.create_group("random")
        g.attrs["method"] = ("H1 = G_xy / G_xx, coherence = |G_xy|^2 / (G_xx G_yy), x = base "
                             "displacement u, y = primary displacement z; Welch over whole "
                             "excitation periods (rectangular window, one period per segment) "
                             "after the stationary start detected by MSER, pooled over "
                             "realisations; z is the displacement of degree of freedom dof")
        g.attrs["period"] = result.period
        g.attrs["replicates"] = R
        g.attrs["dof"] = result.dof
        g.create_dataset("scale", data=result.scales).attrs["units"] = "1"
        g.create_dataset("a_rms", data=[lev["a_rms"] for lev in result.levels]
                         ).attrs["units"] = "m/s^2"
        for name, unit in SPECTRA.items():
            a = np.full((P, F), np.nan)
            for i, lev in enumerate(result.levels):
                v = {"H_re": lev["H"].real, "H_im": lev["H"].imag,
                     "mag": np.abs(lev["H"])}.get(name, lev.get(name))
                a[i, :len(v)] = v
            g.create_dataset(name, data=a).attrs["units"] = unit
        for name, unit in PER_REALISATION.items():
            a = np.array([np.asarray(lev[name], float) for lev in result.levels])
            g.create_dataset(name, data=a).attrs["units"] = unit
        for part, fn in (("re", np.real), ("im", np.imag)):
            a = np.full((P, R, F), np.nan)
            for i, lev in enumerate(result.levels):
                a[i, :, :lev["H_each"].shape[-1]] = fn(lev["H_each"])
            g.create_dataset(f"H_each_{part}", data=a).attrs["units"] = "1"


def read(path: str) -> dict:
    """``{name: array, attrs...}`` of :func:`write` (``H`` complex, rebuilt)."""
    with h5py.File(path, "r") as h5:
        g = h5["random"]
        out = {k: g[k][()] for k in g}
        out.update(dict(g.attrs))
    out["H"] = out["H_re"] + 1j * out["H_im"]
    return out

"""Figures (matplotlib, headless). Each function writes one PNG and returns its path."""

from __future__ import annotations

import numpy as np

from .analysis import frf_amplitude


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def frf_figure(path, f, Z, lz_values, primary, grain_mass, fits=None, title=""):
    """Amplitude ratio Z/U versus f for each Lz, with the analytic FRFs of the primary alone
    (mass M) and with the grains as a rigid mass (M + m_p).

    Args:
      f: frequencies [Hz], ``(F,)``; Z: amplitudes [m], ``(F, L)``; lz_values: ``(L,)`` [m] or
      ``[None]``; primary: :class:`jaxdamp.config.Primary`; grain_mass [kg];
      fits: optional ``[(M_ef, C_ef), ...]`` per Lz, drawn dashed.
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4.5))
    ff = np.linspace(min(f) * 0.9, max(f) * 1.05, 400)
    U = primary.U
    ax.plot(ff, frf_amplitude(ff, primary.M, primary.K, primary.C, U) / U, "k-", lw=0.8,
            label=f"analytic, mass M = {primary.M:g} kg")
    ax.plot(ff, frf_amplitude(ff, primary.M + grain_mass, primary.K, primary.C, U) / U, "k--",
            lw=0.8, label=f"analytic, mass M + m_p = {primary.M + grain_mass:.3g} kg")
    for j, lz in enumerate(lz_values):
        lab = f"DEM, Lz = {lz:g} m" if lz is not None else "DEM"
        line, = ax.plot(f, Z[:, j] / U, "o-", label=lab)
        if fits is not None and fits[j] is not None:
            M, C = fits[j]
            ax.plot(ff, frf_amplitude(ff, M, primary.K, C, U) / U, ":", color=line.get_color(),
                    label=f"fit: M_ef = {M:.3g} kg, C_ef = {C:.3g} N s/m")
    ax.set_yscale("log")
    ax.set_xlabel("excitation frequency f [Hz]")
    ax.set_ylabel("amplitude ratio Z / U")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

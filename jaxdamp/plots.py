"""Figures (matplotlib, headless). Each function writes one PNG and returns its path."""

from __future__ import annotations

import numpy as np

from .analysis import frf_amplitude


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def frf_figure(path, f, Z, lz_values, primary, grain_mass, fits=None, title="", model="DEM"):
    """Amplitude ratio Z/U versus f for each Lz, with the analytic FRFs of the primary alone
    (mass M) and with the grains as a rigid mass (M + m_p).

    Args:
      f: frequencies [Hz], ``(F,)``; Z: amplitudes [m], ``(F, L)``; lz_values: ``(L,)`` [m] or
      ``[None]``; primary: :class:`jaxdamp.config.Primary`; grain_mass [kg];
      fits: optional ``[(M_ef, C_ef), ...]`` per Lz, drawn dashed.
      model: legend label of the simulated points (``"DEM"``, ``"S3"``).
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
        lab = f"{model}, Lz = {lz:g} m" if lz is not None else model
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


def poincare_figure(path, section, kind="velocity", title=""):
    """Scatter of a stroboscopic Poincaré section (:func:`jaxdamp.dynamics.poincare_section`):
    ``(x_k, x'_k)`` for ``kind="velocity"``, the return map ``(x_k, x_{k+1})`` for
    ``kind="return"``. A period-k response shows k dots; quasi-periodic, a closed curve;
    chaotic, a structured cloud."""
    plt = _plt()
    P = section.points(kind)
    fig, ax = plt.subplots(figsize=(4.5, 4.2))
    ax.plot(P[:, 0], P[:, 1], ".", ms=3)
    ax.set_xlabel("x(t_k)")
    ax.set_ylabel("dx/dt(t_k)" if kind == "velocity" else "x(t_{k+1})")
    ax.set_title(title or f"Poincaré section, f = {section.frequency:g} Hz, "
                 f"phase = {section.phase:.2f} rad, {len(P)} points", fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def spectrum_figure(path, spectrum, fmax=None, title=""):
    """PSD (log scale) of :func:`jaxdamp.dynamics.power_spectrum` with the drive's harmonics
    (dashed) and subharmonics (dotted) marked and labelled."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(7, 4))
    m = spectrum.f > 0
    ax.semilogy(spectrum.f[m], spectrum.psd[m], "k-", lw=0.7)
    top = spectrum.f[-1] if fmax is None else fmax
    for label, fl, _ in spectrum.lines:
        if fl > top:
            continue
        sub = "/" in label
        ax.axvline(fl, color="tab:blue" if sub else "tab:red", ls=":" if sub else "--", lw=0.7)
        ax.annotate(label, (fl, 1.0), xycoords=("data", "axes fraction"), fontsize=7,
                    ha="center", va="bottom")
    ax.set_xlim(0, top)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("PSD [x²/Hz]")
    ax.set_title(title or spectrum.method, fontsize=9, pad=12)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


def kantz_figure(path, result, title=""):
    """Kantz's ``S(Δn)`` (:func:`jaxdamp.dynamics.lyapunov_kantz`) against ``Δn·dt`` with the
    fitted line over its fit range; the slope is the largest Lyapunov exponent."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6, 4))
    tt = result.time
    ax.plot(tt, result.S, "k.-", ms=2, lw=0.6, label="S(Δn)")
    i0, i1 = result.fit_range
    seg = tt[i0: i1 + 1]
    ax.plot(seg, result.intercept + result.exponent * seg, "r-", lw=1.5,
            label=f"slope λ = {result.exponent:.4g} (fit Δn = {i0}..{i1})")
    ax.set_xlabel("Δn · dt")
    ax.set_ylabel("S = <ln distance>")
    ax.set_title(title or f"Kantz, m = {result.dim}, τ = {result.delay}, "
                 f"ε = {result.epsilon:.3g}, Theiler = {result.theiler}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path

"""Effective-field figures (:mod:`jaxdamp.studies.maps`): the maps with their uncertainty
(:func:`map_figure`) and the structure's response they predict beside a coupled simulation's
(:func:`prediction_figure`)."""

from __future__ import annotations

import numpy as np

from jaxdamp.figures.style import FIGSIZE, figure

#: The panels of :func:`map_figure`: quantity, label with unit, scale.
PANELS = (("E_diss", "dissipated energy per cycle E_diss [J]", 1.0),
          ("m_eff", "effective mass m_eff [kg]", 1.0),
          ("c_eff", "effective damping c_eff [N s/m]", 1.0),
          ("psi", "specific damping capacity ψ = E_diss / (½ m_p Ω² A²) [-]", 1.0))


def map_figure(field, title=""):
    """The four maps of ``field`` (:class:`jaxdamp.studies.maps.EffectiveField`) over drive
    amplitude × frequency: colour the mean over beds, every cell labelled ``mean`` and, below
    it, ``± SE`` (with one bed: the value alone)."""
    A, f = np.asarray(field.amplitudes) * 1e3, np.asarray(field.frequencies)
    fig = figure(FIGSIZE["map"], layout="constrained")
    axes = fig.subplots(2, 2).ravel()
    for ax, (q, label, scale) in zip(axes, PANELS):
        mean, se = field.mean(q) * scale, field.se(q) * scale
        mesh = ax.pcolormesh(np.arange(len(f) + 1) - 0.5, np.arange(len(A) + 1) - 0.5, mean,
                             cmap="viridis", shading="flat")
        fig.colorbar(mesh, ax=ax, label=label)
        lo, hi = np.nanmin(mean), np.nanmax(mean)
        for i, j in np.ndindex(mean.shape):
            dark = mean[i, j] < lo + 0.5 * (hi - lo)
            text = f"{mean[i, j]:.3g}" + (f"\n±{se[i, j]:.2g}" if np.isfinite(se[i, j]) else "")
            ax.text(j, i, text, ha="center", va="center", fontsize=6,
                    color="white" if dark else "black")
        ax.set_xticks(range(len(f)), [f"{x:g}" for x in f], fontsize=7)
        ax.set_yticks(range(len(A)), [f"{x:.3g}" for x in A], fontsize=7)
        ax.set_xlabel("drive frequency f [Hz]")
        ax.set_ylabel("drive amplitude A [mm]")
    fig.suptitle(title or f"effective fields, mean ± SE over {field.replicates} bed(s)",
                 fontsize=9)
    return fig


def draw_prediction(ax, prediction, unit_amplitude: float, dem=None, title=""):
    """Draw into ``ax`` the response amplitude the maps predict
    (:func:`jaxdamp.analysis.harmonic_balance.predict`) over frequency: every bed's roots
    (several where the response is multi-valued) and the mean ± 2 SE where each bed has one;
    ``dem``: ``(f [Hz] (F,), Z [m] (F, R))`` of a coupled simulation to set beside it (mean ± 2
    SE over its beds). Amplitudes over ``unit_amplitude`` (the base amplitude ``U``)."""
    from jaxdamp.analysis.uncertainty import standard_error

    f = np.asarray(prediction["frequency"])
    for r, row in enumerate(prediction["balances"]):
        for k, b in enumerate(row):
            ax.plot([f[k]] * len(b.roots), np.asarray(b.roots) / unit_amplitude, "x",
                    color="C0", ms=4, alpha=0.6, label="map: every bed's roots"
                    if r == 0 and k == 0 else None)
    ok = np.isfinite(prediction["mean"])
    ax.errorbar(f[ok], prediction["mean"][ok] / unit_amplitude,
                yerr=2 * np.nan_to_num(prediction["se"][ok]) / unit_amplitude, fmt="o-",
                color="C0", capsize=3, ms=4, label="map by harmonic balance (± 2 SE)")
    if dem is not None:
        fd, Z = np.asarray(dem[0]), np.asarray(dem[1])
        ax.errorbar(fd, Z.mean(axis=-1) / unit_amplitude,
                    yerr=2 * np.nan_to_num(standard_error(Z, axis=-1)) / unit_amplitude,
                    fmt="s--", color="C1", capsize=3, ms=4, label="coupled DEM (± 2 SE)")
    ax.set_xlabel("excitation frequency f [Hz]")
    ax.set_ylabel("amplitude ratio Z / U [-]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)


def prediction_figure(prediction, unit_amplitude: float, dem=None, title=""):
    """:func:`draw_prediction` as a figure of its own."""
    fig = figure(FIGSIZE["frf"], layout="constrained")
    draw_prediction(fig.subplots(), prediction, unit_amplitude, dem, title)
    return fig

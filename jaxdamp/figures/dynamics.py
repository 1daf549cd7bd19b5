"""Figures of :mod:`jaxdamp.analysis.dynamics`: stroboscopic Poincaré sections
(:func:`poincare_figure`; :func:`poincare_from_file` for a run file's centre of mass), power
spectra with the drive's lines (:func:`spectrum_figure`) and Kantz's divergence curve with its
Lyapunov fit (:func:`kantz_figure`)."""

from __future__ import annotations

import json

import numpy as np

from jaxdamp.figures._files import open_file, run_title, time_window
from jaxdamp.figures.style import FIGSIZE, figure
from jaxdamp.io.export import require

POINCARE_PATHS = ("series/t", "series/z_cm", "series/vz_cm")


def poincare_figure(section, kind="velocity", *, velocity=None, trajectory=None, x_scale=1.0,
                    unit="x", xlabel=None, ylabel=None, title=""):
    """Scatter of a stroboscopic Poincaré section (:class:`jaxdamp.analysis.dynamics.PoincareSection`,
    from :func:`jaxdamp.analysis.dynamics.poincare_section`), the points coloured by their time.

    ``kind="velocity"``: ``(x_k, v_k)`` with ``v_k`` = ``velocity`` (values at ``section.t``,
    e.g. a recorded velocity sampled by a second section) or else the section's spline
    derivative ``section.dxdt``; ``kind="return"``: the first-return map ``(x_k, x_{k+1})``.
    A period-k response shows k dots; quasi-periodic, a closed curve; chaotic, a structured
    cloud.

    Args:
      trajectory: optional ``(x(t), v(t))`` drawn thinly in the same plane (``"velocity"``).
      x_scale: display factor on x (``1e3``: m → mm); v is drawn as given.
      unit: the unit of x for the default axis labels ``x(t_k) [unit]``,
        ``dx/dt(t_k) [unit/s]``; ``xlabel``/``ylabel`` replace them.
    """
    if kind == "velocity" and velocity is not None:
        v = np.asarray(velocity, float)
        P = np.stack([section.x, v], axis=1)
    else:
        P = section.points(kind)
    tk = section.t if kind == "velocity" else section.t[:-1]
    P = P * np.array([x_scale, 1.0 if kind == "velocity" else x_scale])
    fig = figure(FIGSIZE["poincare"])
    ax = fig.subplots()
    if trajectory is not None and kind == "velocity":
        ax.plot(np.asarray(trajectory[0]) * x_scale, trajectory[1], "-", color="0.8", lw=0.5,
                label="trajectory")
    if len(P):
        sc = ax.scatter(P[:, 0], P[:, 1], c=tk, cmap="viridis", s=22 if len(P) <= 200 else 5,
                        zorder=3, label=f"once per period ({len(P)} point"
                        f"{'s' if len(P) != 1 else ''})")
        fig.colorbar(sc, ax=ax, label="time t [s]")
        ax.legend(fontsize=8, loc="best")
    else:
        ax.text(0.5, 0.5, "no full drive period in the window", transform=ax.transAxes,
                ha="center", va="center")
    ax.set_xlabel(xlabel or f"x(t_k) [{unit}]")
    ax.set_ylabel(ylabel or (f"dx/dt(t_k) [{unit}/s]" if kind == "velocity"
                             else f"x(t_{{k+1}}) [{unit}]"))
    f = section.frequency
    ax.set_title((title + "\n" if title else "") +
                 f"{'Poincaré section' if kind == 'velocity' else 'return map'} at "
                 f"T = 1/f = {1e3 / f:.4g} ms (f = {f:g} Hz), phase {section.phase:.3g} rad",
                 fontsize=9)
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def poincare_from_file(h5_or_path, t0=None, t1=None, phase=0.0):
    """:func:`poincare_figure` of a run file's centre of mass: ``(z_cm, vz_cm)`` sampled once
    per drive period (at phase ``phase`` [rad] of ``cos 2πft``) by
    :func:`jaxdamp.analysis.dynamics.poincare_section` in the window ``[t0, t1]`` [s], over the thin
    trajectory in the same plane."""
    from jaxdamp.analysis.dynamics import poincare_section

    h5, close = open_file(h5_or_path)
    try:
        require(h5, "the Poincaré section", "run", POINCARE_PATHS)
        g = h5["series"]
        cfg = json.loads(h5.attrs["config"])
        t, z, v = g["t"][()], g["z_cm"][()], g["vz_cm"][()]
        title, path = run_title(h5, cfg), h5.filename
    finally:
        if close:
            h5.close()
    f = float(cfg["frequency"])
    m = time_window(t, t0, t1, what="Poincaré section", path=path)
    t, z, v = t[m], z[m], v[m]
    sec = poincare_section(t, z, f, phase)
    # the recorded velocity at the same instants (not the spline's derivative of z_cm, which
    # smooths over collisions)
    vk = poincare_section(t, v, f, phase).x
    return poincare_figure(sec, velocity=vk, trajectory=(z, v), x_scale=1e3,
                           xlabel="centre of mass $z_{cm}$ [mm] (lab frame)",
                           ylabel="centre-of-mass velocity $v_{z,cm}$ [m/s]", title=title)


def spectrum_figure(spectrum, fmax=None, unit="x", title=""):
    """PSD (log scale) of :func:`jaxdamp.analysis.dynamics.power_spectrum` with the drive's harmonics
    (dashed) and subharmonics (dotted) marked and labelled; ``unit`` is the series' unit."""
    fig = figure(FIGSIZE["spectrum"])
    ax = fig.subplots()
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
    ax.set_ylabel(f"PSD [{unit}²/Hz]")
    ax.set_title(title or spectrum.method, fontsize=9, pad=12)
    fig.tight_layout()
    return fig


def kantz_figure(result, title=""):
    """Kantz's ``S(Δn)`` (:func:`jaxdamp.analysis.dynamics.lyapunov_kantz`) against ``Δn·dt`` with the
    fitted line over its fit range; the slope is the largest Lyapunov exponent."""
    fig = figure(FIGSIZE["kantz"])
    ax = fig.subplots()
    tt = result.time
    ax.plot(tt, result.S, "k.-", ms=2, lw=0.6, label="S(Δn)")
    i0, i1 = result.fit_range
    seg = tt[i0: i1 + 1]
    ax.plot(seg, result.intercept + result.exponent * seg, "r-", lw=1.5,
            label=f"slope λ = {result.exponent:.4g} (fit Δn = {i0}..{i1})")
    ax.set_xlabel("Δn · dt [s] (dt = 1 for a map: iterations)")
    ax.set_ylabel("S = ⟨ln distance⟩ [ln of the units of x]")
    ax.set_title(title or f"Kantz, m = {result.dim}, τ = {result.delay}, "
                 f"ε = {result.epsilon:.3g}, Theiler = {result.theiler}", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig

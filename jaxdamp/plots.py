"""Figures (matplotlib, headless). Each function writes one PNG and returns its path."""

from __future__ import annotations

import numpy as np

from .analysis import frf_amplitude


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figure(fig, path, dpi=120):
    """Lay out ``fig``, write it to ``path`` (PNG), close it and return ``path``."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def frf_figure(path, f, Z, lz_values, primary, grain_mass, fits=None, title="", model="DEM",
               Z_se=None):
    """Amplitude ratio Z/U versus f for each Lz, with the analytic FRFs of the primary alone
    (mass M) and with the grains as a rigid mass (M + m_p).

    Args:
      f: frequencies [Hz], ``(F,)``; Z: amplitudes [m], ``(F, L)``; lz_values: ``(L,)`` [m] or
      ``[None]``; primary: :class:`jaxdamp.config.Primary`; grain_mass [kg];
      fits: optional ``[(M_ef, C_ef), ...]`` per Lz, drawn dashed.
      model: legend label of the simulated points (``"DEM"``, ``"S3"``).
      Z_se: optional standard errors of ``Z`` across replicates [m], ``(F, L)``: error bars
        of ± 2 SE.
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
        if Z_se is not None and np.isfinite(Z_se[:, j]).any():
            ax.errorbar(f, Z[:, j] / U, yerr=2 * np.nan_to_num(Z_se[:, j]) / U, fmt="none",
                        ecolor=line.get_color(), capsize=2, lw=0.8)
        if fits is not None and fits[j] is not None:
            M, C = fits[j]
            ax.plot(ff, frf_amplitude(ff, M, primary.K, C, U) / U, ":", color=line.get_color(),
                    label=f"fit: M_ef = {M:.3g} kg, C_ef = {C:.3g} N s/m")
    ax.set_yscale("log")
    ax.set_xlabel("excitation frequency f [Hz]")
    ax.set_ylabel("amplitude ratio Z / U")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return save_figure(fig, path)


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
    return save_figure(fig, path)


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
    return save_figure(fig, path)


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
    return save_figure(fig, path)


def efficiency_figure(path, curves, title=""):
    """``⟨E_d⟩ / m`` versus drive amplitude (the 2023 paper's figs. 2, 6, 9).

    Args:
      curves: ``[(label, amplitudes [m] (P,), E_d/m [1/kg] (P,), spread [1/kg] (P,)), ...]``;
        the spread is drawn as error bars (the paper: standard deviation over periods).
    """
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.5, 4.3))
    for label, amp, y, err in curves:
        ax.errorbar(np.asarray(amp) * 100, y, yerr=err, fmt="o-", ms=4, capsize=2, label=label)
    ax.set_xlabel("drive amplitude A_d [cm]")
    ax.set_ylabel("⟨E_d⟩ / m  [1/kg]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return save_figure(fig, path)


def phase_figure(path, cases, title=""):
    """Phase-resolved diagnostics over one drive period (the paper's figs. 4, 5, 7, 8, 10–12).

    Args:
      cases: ``[(label, phase dict, species names), ...]`` with the arrays of one point of
        :attr:`jaxdamp.efficiency.EfficiencyResult.phase` (``phase``, ``contacts``,
        ``force_floor_lid``, ``z_cm_species``, ``vz_cm_species``, ``z_box``).
    Panels: grains touching floor or lid; vertical force of the grains on floor + lid; the
    centre of mass' phase plot ``v_z(z)`` per species, ``z`` measured from the box's mid-plane
    position at rest (lab frame).
    """
    plt = _plt()
    fig, axes = plt.subplots(1, 3, figsize=(13, 4))
    styles = ["-", "--", ":", "-."]
    for k, (label, ph, names) in enumerate(cases):
        x = np.asarray(ph["phase"])
        line, = axes[0].plot(x, ph["contacts"], label=label)
        axes[1].plot(x, ph["force_floor_lid"], color=line.get_color(), label=label)
        zc, vc = np.asarray(ph["z_cm_species"]), np.asarray(ph["vz_cm_species"])
        for s, name in enumerate(names):
            close = lambda a: np.append(a, a[:1])  # noqa: E731  (a closed orbit)
            axes[2].plot(close(zc[:, s]) * 100, close(vc[:, s]), styles[s % 4],
                         color=line.get_color(), label=f"{label}: {name}")
    axes[0].set_ylabel("grains touching floor or lid")
    axes[1].set_ylabel("vertical force on floor + lid [N]")
    for ax in axes[:2]:
        ax.set_xlabel("phase t/T (box at its top at 0, z_box = A_d cos 2πft)")
    axes[2].set_xlabel("centre of mass z [cm] (lab frame)")
    axes[2].set_ylabel("centre of mass v_z [m/s]")
    for ax in axes:
        ax.legend(fontsize=6)
    fig.suptitle(title, fontsize=9)
    return save_figure(fig, path)


def snapshot_figure(path, rows, title=""):
    """Side views (x–z) of beds at chosen instants, grains drawn to scale, coloured by species
    (the paper's fig. 3).

    Args:
      rows: ``[(label, [(caption, r (N, 3), z_box), ...], radii (N,), species (N,), box
        (Lx, Lz)), ...]``; one row per system, one panel per instant.
    """
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Rectangle

    plt = _plt()
    ncol = max(len(r[1]) for r in rows)
    fig, axes = plt.subplots(len(rows), ncol, figsize=(2.6 * ncol, 2.9 * len(rows)),
                             squeeze=False)
    colours = ["tab:red", "tab:green", "tab:blue", "tab:orange"]
    for i, (label, frames, radii, species, (Lx, Lz)) in enumerate(rows):
        order = np.argsort(-np.asarray(radii))  # small grains drawn last, on top
        for j, (caption, r, z_box) in enumerate(frames):
            ax = axes[i, j]
            circles = [Circle((r[k, 0] * 100, (r[k, 2] - z_box) * 100), radii[k] * 100)
                       for k in order]
            ax.add_collection(PatchCollection(
                circles, facecolor=[colours[species[k] % 4] for k in order], edgecolor="none",
                alpha=0.8))
            ax.add_patch(Rectangle((0, 0), Lx * 100, Lz * 100, fill=False, lw=1))
            ax.set_xlim(-0.2, Lx * 100 + 0.2)
            ax.set_ylim(-0.2, Lz * 100 + 0.2)
            ax.set_aspect("equal")
            ax.set_title(f"{label}\n{caption}", fontsize=7)
            ax.tick_params(labelsize=6)
        for j in range(len(frames), ncol):
            axes[i, j].axis("off")
    fig.suptitle(title + "  (x–z side view, box frame [cm]; red: large, green: small)",
                 fontsize=8)
    return save_figure(fig, path)

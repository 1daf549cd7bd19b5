"""Response figures: the FRF (amplitude ratio versus frequency), the bed-band plot and the
energy channels of a run.

- :func:`frf_figure` — Z/U versus f per ``Lz`` with the analytic FRFs; :func:`frf_from_file`
  draws it from a sweep file.
- :func:`band_figure` — the thesis' bed-band plot: floor and lid of the box, the band between
  the lowest and highest grain centre, the centre of mass, and the force of the grains on the
  box, versus time; :func:`band_from_file` from a run file.
- :func:`energy_figure` — cumulative work channels and the energy-balance residual;
  :func:`energy_from_file` from a run file.
- :func:`decay_figure` — a free decay's damping ratio and frequency versus amplitude, ζ(Z)
  and f(Z), per initial displacement, with the replicates' ± 2 SE band.
"""

from __future__ import annotations

import json
import os
import textwrap

import numpy as np

from jaxdamp.analysis.response import frf_amplitude
from jaxdamp.figures._files import open_file, run_title, time_window
from jaxdamp.figures.style import FIGSIZE, figure
from jaxdamp.io.export import OutputFileError, require

#: default time window of the band plot, in drive periods before the end of the run
BAND_PERIODS = 4

BAND_PATHS = ("series/t", "series/z_box", "series/z_cm", "series/z_lowest", "series/z_highest",
              "series/force_box")
ENERGY_PATHS = ("series/t", "series/work", "series/balance_residual")


# -- FRF -----------------------------------------------------------------------------------------
def frf_figure(f, Z, lz_values, primary, grain_mass, fits=None, title="", model="DEM",
               Z_se=None, failures=None):
    """Amplitude ratio Z/U versus f for each Lz, with the analytic FRFs of the primary alone
    (mass M) and with the grains as a rigid mass (M + m_p).

    Args:
      f: frequencies [Hz], ``(F,)``; Z: amplitudes [m], ``(F, L)``; lz_values: ``(L,)`` [m] or
      ``[None]``; primary: :class:`jaxdamp.config.Primary`; grain_mass [kg];
      fits: optional ``[(M_ef, C_ef), ...]`` per Lz, drawn dotted (``None`` entries: none).
      failures: optional reasons per Lz why its fit failed (``""``: it did not;
        :func:`jaxdamp.analysis.response.fit_failure`): a failed fit is not drawn, the legend
        says "fit failed" instead.
      model: legend label of the simulated points (``"DEM"``, ``"S3"``).
      Z_se: optional standard errors of ``Z`` across replicates [m], ``(F, L)``: error bars
        of ± 2 SE.
    """
    fig = figure(FIGSIZE["frf"])
    ax = fig.subplots()
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
        failed = failures is not None and bool(failures[j])
        if failed:
            ax.plot([], [], ":", color=line.get_color(), label="fit failed (not a result): "
                    + textwrap.shorten(str(failures[j]), 60))
        elif fits is not None and fits[j] is not None:
            M, C = fits[j]
            ax.plot(ff, frf_amplitude(ff, M, primary.K, C, U) / U, ":", color=line.get_color(),
                    label=f"fit: M_ef = {M:.3g} kg, C_ef = {C:.3g} N s/m")
    ax.set_yscale("log")
    ax.set_xlabel("excitation frequency f [Hz]")
    ax.set_ylabel("amplitude ratio Z / U")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def frf_from_file(h5_or_path):
    """:func:`frf_figure` of a sweep file: amplitude ratio Z/U versus frequency, one curve per
    ``box.Lz``, with the fitted FRFs when ``/fit`` is present (those flagged as failed in
    ``/fit/failure`` are not drawn). The amplitudes are those ``jaxdamp frf`` fitted: per
    replicate the steady mean where the run became stationary, else its fixed window
    (:func:`jaxdamp.studies.grid.steady_or_window`); with replicates, their mean ± 2 SE."""
    from types import SimpleNamespace

    from jaxdamp.analysis.response import replicate_mean
    from jaxdamp.config import from_json
    from jaxdamp.physics.model import grain_mass
    from jaxdamp.studies.grid import steady_or_window

    h5, close = open_file(h5_or_path)
    try:
        require(h5, "the FRF figure", "sweep", ("summary/amplitude",))
        axes = json.loads(h5.attrs["axes"])
        R = int(axes.pop("replicates", h5.attrs.get("replicates", 1)))
        layout = axes.pop("layout", "grid")
        keys = list(axes)
        if "frequency" not in keys:
            raise OutputFileError(f"{h5.filename}: the FRF figure needs a sweep over 'frequency'; "
                                  f"this one sweeps {', '.join(keys)}")
        if layout != "grid":
            raise OutputFileError(f"{h5.filename}: the FRF figure needs a grid sweep; this one "
                                  f"is a list of {layout}")
        cfg = from_json(h5.attrs["base_config"])
        if cfg.system != "primary":
            raise OutputFileError(f"{h5.filename}: the FRF figure needs an S1 sweep (system "
                                  f"'primary'); this one is {cfg.system!r}")
        other = [k for k in keys if k != "frequency"]
        if other and other[0] != "box.Lz":
            raise OutputFileError(f"{h5.filename}: the FRF figure draws one curve per box.Lz; "
                                  f"this sweep's second axis is {other[0]!r}")
        f = np.asarray(axes["frequency"], float)
        shape = [len(axes[k]) for k in keys]
        if "steady/amplitude/values" in h5 and "replicate_summary/amplitude" in h5:
            stored = SimpleNamespace(
                steady={"amplitude": {k: h5[f"steady/amplitude/{k}"][()]
                                      for k in ("values", "stationary")}},
                replicate_summary={"amplitude": h5["replicate_summary/amplitude"][()]})
            Zr = np.asarray(steady_or_window(stored, "amplitude")[0], float)
        else:  # no per-replicate data: the fixed-window mean
            Zr = np.asarray(h5["summary/amplitude"][()], float)
        Zr = Zr.reshape(shape + [-1])
        if keys[0] != "frequency":
            Zr = np.swapaxes(Zr, 0, 1)
        Zr = Zr.reshape(len(f), -1, Zr.shape[-1])
        Z, Z_se = replicate_mean(Zr)
        lz = [float(x) for x in axes["box.Lz"]] if other else [None]
        fits = failures = None
        if "fit/M_ef" in h5 and "fit/C_ef" in h5:
            fits = list(zip(h5["fit/M_ef"][()], h5["fit/C_ef"][()]))
            if "fit/failure" in h5:  # files before the flag: every fit drawn
                failures = [w.decode() if isinstance(w, bytes) else str(w)
                            for w in h5["fit/failure"][()]]
        order = np.argsort(f)
        title = (f"{cfg.name}: {os.path.basename(h5.filename)}, N = {cfg.n_grains} grains"
                 + (f", mean of R = {R} beds ± 2 SE" if R > 1 else ""))
        return frf_figure(f[order], Z[order], lz, cfg.primary, grain_mass(cfg), fits,
                          title=title, failures=failures,
                          Z_se=None if Z_se is None else Z_se[order])
    finally:
        if close:
            h5.close()


# -- bed band ------------------------------------------------------------------------------------
def draw_band(ax, t, z_box, z_lowest, z_highest, z_cm, Lz, *, fontsize=None):
    """Draw the bed band into ``ax`` (heights in mm, lab frame, against time ``t`` [s]): the
    floor ``z_box`` and the lid ``z_box + Lz`` [m], the band between the lowest and highest
    grain centre filled, and the centre of mass ``z_cm`` (``None``: not drawn). The one
    drawing of the band, used by :func:`band_figure` and by the experiments' panels."""
    mm = 1e3
    zb, zl, zh = (np.asarray(x) * mm for x in (z_box, z_lowest, z_highest))
    ax.fill_between(t, zl, zh, color="tab:orange", alpha=0.45, lw=0,
                    label="grains (lowest … highest centre)")
    ax.plot(t, zb, "k-", lw=1.4, label="floor $z_{box}$")
    ax.plot(t, zb + Lz * mm, "k--", lw=1.4, label=f"lid $z_{{box}} + L_z$ ($L_z$ = {Lz * mm:g} mm)")
    if z_cm is not None:
        ax.plot(t, np.asarray(z_cm) * mm, "-", color="tab:red", lw=1.0,
                label="centre of mass $z_{cm}$")
    ax.set_ylabel("height z [mm] (lab frame)", fontsize=fontsize)
    ax.set_xlabel("time t [s]", fontsize=fontsize)
    ax.grid(alpha=0.3)


def draw_run_band(ax, run: dict, Lz, frequency, periods=3, *, centre=True, fontsize=None):
    """:func:`draw_band` of the last ``periods`` drive periods of ``frequency`` [Hz] of one
    recorded run: ``run`` holds its samples ``t``, ``z_box``, ``z_lowest``, ``z_highest`` and,
    with ``centre``, ``z_cm`` (a row of a sweep's records, say). Returns the boolean mask of
    the samples drawn, ``t ≥ t_end − periods/frequency``, for more curves on the same window.

    Example: ``m = draw_run_band(ax, {k: v[row] for k, v in res.records.items()}, 0.11, 15.5)``
    draws the band of the run's last 3 periods (0.194 s).
    """
    m = time_window(run["t"], None, None, frequency, periods, "band")
    z = [np.asarray(run[k])[m] for k in ("z_box", "z_lowest", "z_highest")]
    draw_band(ax, np.asarray(run["t"])[m], *z, np.asarray(run["z_cm"])[m] if centre else None,
              Lz, fontsize=fontsize)
    return m


def draw_replicates(ax, x, Y, **kwargs):
    """The mean over the last axis (the replicates) of ``Y`` ``(L, R)`` against ``x`` ``(L,)``
    with error bars of ± 2 standard errors across the replicates, ``2 s/√R``
    (:func:`jaxdamp.analysis.uncertainty.standard_error`; no bar where ``R = 1``), by
    ``Axes.errorbar`` (``kwargs``; defaults ``fmt="o-"``, ``capsize=3``). Returns its container.

    Example: ``draw_replicates(ax, [1, 2], [[1.0, 3.0], [2.0, 2.0]])`` draws 2 ± 2 and 2 ± 0.
    """
    from jaxdamp.analysis.uncertainty import standard_error

    Y = np.asarray(Y, float)
    return ax.errorbar(x, Y.mean(axis=-1), yerr=2 * standard_error(Y),
                       **{"fmt": "o-", "capsize": 3, **kwargs})


def draw_interval(ax, mean, half_width, **kwargs):
    """Shade ``mean ± half_width`` along the x axis (an optimum's 95 % interval, say), with
    ``kwargs`` to ``Axes.axvspan``; nothing where the half-width is not finite (one replicate).
    Returns the patch, or ``None``.

    Example: ``draw_interval(ax, 0.12, 0.01, alpha=0.15)`` shades 0.11 … 0.13.
    """
    if not np.isfinite(half_width):
        return None
    return ax.axvspan(mean - half_width, mean + half_width, **kwargs)


def band_figure(t, z_box, Lz, z_lowest, z_highest, z_cm, force_box, *, weight=None,
                frequency=None, t0=None, t1=None, periods=BAND_PERIODS, title="", path=""):
    """The bed-band plot of the thesis versus time ``t`` [s].

    Top panel (heights in mm, lab frame): the floor ``z_box`` and the lid ``z_box + Lz`` of the
    box, the band between the lowest and highest grain centre filled, and the bed's centre of
    mass ``z_cm``. Bottom panel: the vertical force of the grains on the box ``force_box`` [N]
    (interval average, positive upwards; with ``weight`` = ``m_p g`` [N], the level ``−m_p g``
    of a bed resting on the floor is drawn as a reference). Default window:
    the last ``periods`` drive periods of ``frequency`` [Hz] (the whole run without it).
    """
    m = time_window(t, t0, t1, frequency, periods, "band plot", path)
    t = np.asarray(t)[m]
    F = np.asarray(force_box)[m]
    fig = figure(FIGSIZE["band"])
    ax, axf = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    draw_band(ax, t, *(np.asarray(x)[m] for x in (z_box, z_lowest, z_highest, z_cm)), Lz)
    ax.set_xlabel("")  # the force panel below carries the time axis
    ax.legend(fontsize=8, loc="upper left", ncol=2, framealpha=0.85)
    axf.plot(t, F, "-", color="tab:blue", lw=0.9, label="grains on box $F_{gz}$")
    if weight is not None:
        axf.axhline(-weight, color="0.4", ls=":", lw=1.0,
                    label=f"bed resting on the floor: $-m_p g$ = {-weight:.3g} N")
    axf.axhline(0.0, color="0.7", lw=0.6)
    axf.set_ylabel("force on box [N]")
    axf.set_xlabel("time t [s]")
    axf.legend(fontsize=8, loc="upper left")
    axf.grid(alpha=0.3)
    if frequency:
        title = (title + "\n" if title else "") + (
            f"f = {frequency:g} Hz, t = {t[0]:.4g} … {t[-1]:.4g} s "
            f"({(t[-1] - t[0]) * frequency:.2g} periods)")
    ax.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def band_from_file(h5_or_path, t0=None, t1=None, periods=BAND_PERIODS):
    """:func:`band_figure` of a run file."""
    h5, close = open_file(h5_or_path)
    try:
        require(h5, "the band plot", "run", BAND_PATHS)
        s = {k: h5["series"][k][()] for k in ("t", "z_box", "z_lowest", "z_highest", "z_cm",
                                                  "force_box")}
        cfg = json.loads(h5.attrs["config"])
        weight = (float(h5["grains/mass"][()].sum()) * float(cfg["gravity"])
                  if "grains/mass" in h5 else None)
        lid = float((cfg.get("box") or cfg.get("container"))["Lz"])
        return band_figure(s["t"], s["z_box"], lid, s["z_lowest"],
                           s["z_highest"], s["z_cm"], s["force_box"], weight=weight,
                           frequency=float(cfg["frequency"]), t0=t0, t1=t1, periods=periods,
                           title=run_title(h5, cfg), path=h5.filename)
    finally:
        if close:
            h5.close()


# -- energy --------------------------------------------------------------------------------------
GRANULAR = ("pp_normal", "pp_friction", "pw_normal", "pw_friction")
_LABELS = {"input": "input work", "primary_damping": "primary damper C",
           "pp_normal": "grain–grain, normal", "pp_friction": "grain–grain, friction",
           "pw_normal": "grain–wall, normal", "pw_friction": "grain–wall, friction",
           "drag": "settling drag"}


def energy_figure(t, work, channels, residual, *, t0=None, t1=None, title="", path=""):
    """Cumulative work channels [J] since t = 0 and the energy-balance residual [J] versus time.

    Panels: input work, loss in the primary's damper and the total granular loss; the four
    granular channels (grain–grain / grain–wall, normal / friction); the residual
    ``E(t) − E(0) + losses − input`` with its size relative to the energy turned over.
    """
    m = time_window(t, t0, t1, what="energy figure", path=path)
    t = np.asarray(t)[m]
    W = np.asarray(work)[m]
    res = np.asarray(residual)[m]
    col = {name: W[:, i] for i, name in enumerate(channels)}
    gran = sum(col[c] for c in GRANULAR if c in col)
    fig = figure(FIGSIZE["energy"])
    a1, a2, a3 = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [1.3, 1.3, 1]})
    for name, style in (("input", "k-"), ("primary_damping", "-")):
        if name in col:
            a1.plot(t, col[name], style, lw=1.1, label=_LABELS[name])
    a1.plot(t, gran, "-", lw=1.1, color="tab:red", label="granular loss (sum of 4 channels)")
    if "drag" in col and np.any(col["drag"] != 0):
        a1.plot(t, col["drag"], ":", label=_LABELS["drag"])
    a1.set_ylabel("cumulative work [J]")
    a1.legend(fontsize=8, loc="upper left")
    for name in GRANULAR:
        if name in col:
            a2.plot(t, col[name], lw=1.0, label=_LABELS[name])
    a2.plot(t, gran, "k--", lw=0.8, label="sum")
    a2.set_ylabel("granular loss [J]")
    a2.legend(fontsize=8, loc="upper left", ncol=2)
    a3.plot(t, res, "-", color="tab:purple", lw=0.9)
    from jaxdamp.physics.model import CHANNELS, LOSSES  # the physics: on use

    turnover = np.abs(col.get("input", np.zeros_like(t))) + sum(
        np.abs(col[CHANNELS[i]]) for i in LOSSES if CHANNELS[i] in col)  # not the breakdowns
    rel = float(np.max(np.abs(res)) / max(np.max(turnover), 1e-300))
    a3.set_ylabel("balance residual [J]")
    a3.set_xlabel("time t [s]")
    a3.set_title(f"residual E(t) − E(0) + losses − input; max |residual| / max(|input| + losses) "
                 f"= {rel:.2g}", fontsize=8)
    for a in (a1, a2, a3):
        a.grid(alpha=0.3)
    a1.set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def energy_from_file(h5_or_path, t0=None, t1=None):
    """:func:`energy_figure` of a run file."""
    h5, close = open_file(h5_or_path)
    try:
        require(h5, "the energy figure", "run", ENERGY_PATHS)
        g = h5["series"]
        channels = json.loads(g["work"].attrs["channels"])
        cfg = json.loads(h5.attrs["config"])
        return energy_figure(g["t"][()], g["work"][()], channels, g["balance_residual"][()],
                             t0=t0, t1=t1, title=run_title(h5, cfg), path=h5.filename)
    finally:
        if close:
            h5.close()


# -- free decay ----------------------------------------------------------------------------------
def decay_figure(curves, labels, zeta_struct=None, title=""):
    """The damper's characteristic curves from free decays: damping ratio ζ [%] (total, from
    the decrement; dashed: the grains' share from their dissipated energy) and damped
    frequency f [Hz] versus the cycle's amplitude Z [mm] (log axis), one line per curve
    (:func:`jaxdamp.analysis.decay.on_amplitudes`: mean over replicates, band ± 2 SE where
    two or more replicates cover the amplitude); ``zeta_struct``: the empty box's ratio,
    drawn as a horizontal line."""
    fig = figure(FIGSIZE["decay"], layout="constrained")
    ax_z, ax_f = fig.subplots(1, 2)
    for c, lab in zip(curves, labels):
        Z = np.asarray(c["Z"]) * 1e3
        line, = ax_z.plot(Z, 100 * np.asarray(c["zeta"]), lw=1.2, label=f"{lab}: total")
        if "zeta_g" in c:
            ax_z.plot(Z, 100 * np.asarray(c["zeta_g"]), lw=1.0, ls="--", color=line.get_color(),
                      label=f"{lab}: grains, ΔW/(2πKZ²)")
        ax_f.plot(Z, c["f"], lw=1.2, color=line.get_color(), label=lab)
        for ax, m, se, k in ((ax_z, c["zeta"], c["zeta_se"], 100.0), (ax_f, c["f"], c["f_se"], 1.0)):
            se = np.asarray(se)
            ok = np.isfinite(se)
            if ok.any():
                ax.fill_between(Z[ok], k * (np.asarray(m)[ok] - 2 * se[ok]),
                                k * (np.asarray(m)[ok] + 2 * se[ok]), color=line.get_color(),
                                alpha=0.25, lw=0)
    if zeta_struct is not None:
        ax_z.axhline(100 * zeta_struct, color="k", ls="--", lw=0.8,
                     label=f"empty box (grains as dead mass): {100 * zeta_struct:.2f} %")
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    for ax in (ax_z, ax_f):
        ax.set_xscale("log")
        ax.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.set_xlabel("amplitude of the cycle Z [mm]")
        ax.grid(alpha=0.3, which="both")
    ax_z.set_ylabel("equivalent damping ratio ζ [%]")
    ax_f.set_ylabel("damped frequency f [Hz]")
    ax_z.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=9)
    return fig


def random_figure(levels, labels, reference=None, title="", log=True):
    """FRFs from random excitation (:func:`jaxdamp.studies.random.measure`): the H1
    transmissibility ``|z/u|`` (log axis unless ``log=False``; band ± 2 SE between
    realisations where there are two or more, on the log axis no lower than a tenth of |H1|)
    over the coherence γ², one line per level.
    ``reference``: optional ``(f [Hz], |H|, label)`` drawn dashed (e.g. the empty box's
    analytic FRF). More curves go into ``fig.axes[0]`` (then call its ``legend`` again)."""
    fig = figure(FIGSIZE["random"], layout="constrained")
    ax_h, ax_c = fig.subplots(2, 1, sharex=True, height_ratios=(2.2, 1.0))
    for lev, lab in zip(levels, labels):
        f = np.asarray(lev["f"])
        mag = np.abs(np.asarray(lev["H"]))
        line, = ax_h.plot(f, mag, lw=1.2, marker=".", ms=3, label=lab)
        se = np.asarray(lev["mag_se"])
        ok = np.isfinite(se)
        if ok.any():
            low = mag[ok] - 2 * se[ok]  # on a log axis the band stops at a tenth of |H1|
            ax_h.fill_between(f[ok], np.maximum(low, 0.1 * mag[ok]) if log else low,
                              mag[ok] + 2 * se[ok], color=line.get_color(), alpha=0.25, lw=0)
        ax_c.plot(f, lev["coherence"], lw=1.0, color=line.get_color())
    if reference is not None:
        ax_h.plot(reference[0], reference[1], "k--", lw=0.8, label=reference[2])
    if log:
        ax_h.set_yscale("log")
    ax_h.set_ylabel("transmissibility |H1| = |z / u| [-]")
    ax_c.set_ylabel("coherence γ² [-]")
    ax_c.set_xlabel("frequency f [Hz]")
    ax_c.set_ylim(0.0, 1.05)
    for ax in (ax_h, ax_c):
        ax.grid(alpha=0.3, which="both")
    ax_h.legend(fontsize=7)
    if title:
        fig.suptitle(title, fontsize=9)
    return fig

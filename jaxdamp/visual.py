"""Figures from output files (matplotlib, Agg; no pyplot state).

Pure functions take arrays and return a :class:`matplotlib.figure.Figure`; the ``*_from_file``
helpers take an open :class:`h5py.File` (or a path), check that it holds what the figure needs
(:class:`jaxdamp.export.OutputFileError` naming the file and the missing part otherwise) and
return a ``Figure`` too. :func:`save` writes one at a fixed pixel size (``figsize × dpi``).

- :func:`band_figure` — the thesis' bed-band plot: floor and lid of the box, the band between
  the lowest and highest grain centre, the centre of mass, and the force of the grains on the
  box, versus time (run files).
- :func:`energy_figure` — cumulative work channels and the energy-balance residual (run files).
- :func:`frf_from_file` — the FRF of a sweep file, drawn by :func:`jaxdamp.plots.frf_figure`.
- :func:`snapshot_figure` — 3-D view of the grains at one snapshot (run files).
- :func:`poincare_figure` — stroboscopic (Poincaré) section of the bed's centre of mass at the
  drive period (run files).
- :func:`animate` — GIF (Pillow) or MP4 (ffmpeg) of the snapshots (run files).
"""

from __future__ import annotations

import json
import os
import shutil

import numpy as np

from .export import OutputFileError, load_snapshots, open_output, require

#: default figure sizes [inch] per kind; pixel size = size × DPI
FIGSIZE = {"band": (9.0, 6.0), "energy": (8.0, 7.5), "snapshot": (6.0, 8.0),
           "poincare": (6.5, 5.5), "animation": (5.0, 6.5)}
DPI = 110
#: default time window of the band plot, in drive periods before the end of the run
BAND_PERIODS = 4

BAND_PATHS = ("series/t", "series/z_box", "series/z_cm", "series/z_lowest", "series/z_highest",
              "series/force_box")
ENERGY_PATHS = ("series/t", "series/work", "series/balance_residual")
POINCARE_PATHS = ("series/t", "series/z_cm", "series/vz_cm")


def _figure(size, dpi=DPI):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=size, dpi=dpi)
    FigureCanvasAgg(fig)
    return fig


def save(fig, out, dpi=None) -> str:
    """Write ``fig`` to ``out`` (format from the extension) at exactly ``figsize × dpi``
    pixels; returns the path."""
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    fig.savefig(out, dpi=dpi or fig.dpi)
    return os.fspath(out)


def _window(t, t0, t1, frequency=None, periods=None, what="figure", path=""):
    """Boolean mask of samples in ``[t0, t1]``; defaults: the whole run, or with ``periods``
    the last ``periods`` drive periods."""
    t = np.asarray(t)
    lo, hi = float(t[0]), float(t[-1])
    if t1 is None:
        t1 = hi
    if t0 is None:
        t0 = max(lo, t1 - periods / frequency) if periods and frequency else lo
    if not t0 < t1:
        raise OutputFileError(f"{path}: {what}: empty time window t0 = {t0:g} s ≥ t1 = {t1:g} s")
    mask = (t >= t0) & (t <= t1)
    if mask.sum() < 2:
        raise OutputFileError(f"{path}: {what}: fewer than 2 samples in t = {t0:g} … {t1:g} s; "
                              f"the run's samples span {lo:.6g} … {hi:.6g} s")
    return mask


# -- bed band --------------------------------------------------------------------------------
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
    m = _window(t, t0, t1, frequency, periods, "band plot", path)
    t = np.asarray(t)[m]
    mm = 1e3
    zb, zl, zh, zc = (np.asarray(x)[m] * mm for x in (z_box, z_lowest, z_highest, z_cm))
    F = np.asarray(force_box)[m]
    fig = _figure(FIGSIZE["band"])
    ax, axf = fig.subplots(2, 1, sharex=True, gridspec_kw={"height_ratios": [2.2, 1]})
    ax.fill_between(t, zl, zh, color="tab:orange", alpha=0.45, lw=0,
                    label="grains (lowest … highest centre)")
    ax.plot(t, zb, "k-", lw=1.4, label="floor $z_{box}$")
    ax.plot(t, zb + Lz * mm, "k--", lw=1.4, label=f"lid $z_{{box}} + L_z$ ($L_z$ = {Lz * mm:g} mm)")
    ax.plot(t, zc, "-", color="tab:red", lw=1.0, label="centre of mass $z_{cm}$")
    ax.set_ylabel("height z [mm] (lab frame)")
    ax.legend(fontsize=8, loc="upper left", ncol=2, framealpha=0.85)
    ax.grid(alpha=0.3)
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


def _run_title(h5, cfg) -> str:
    n = sum(s["count"] for s in cfg["grains"])
    return f"{cfg.get('name', '')}: {os.path.basename(h5.filename)}, N = {n} grains"


def _open(h5_or_path):
    """``(h5, close)``: an open file and whether we opened it."""
    if isinstance(h5_or_path, (str, os.PathLike)):
        return open_output(h5_or_path), True
    return h5_or_path, False


def band_from_file(h5_or_path, t0=None, t1=None, periods=BAND_PERIODS):
    """:func:`band_figure` of a run file."""
    h5, close = _open(h5_or_path)
    try:
        require(h5, "the band plot", "run", BAND_PATHS)
        s = {k: h5["series"][k][()] for k in ("t", "z_box", "z_lowest", "z_highest", "z_cm",
                                                  "force_box")}
        cfg = json.loads(h5.attrs["config"])
        weight = float(h5["grains/mass"][()].sum()) * float(cfg["gravity"]) if "grains/mass" in h5 else None
        return band_figure(s["t"], s["z_box"], float(cfg["box"]["Lz"]), s["z_lowest"],
                           s["z_highest"], s["z_cm"], s["force_box"], weight=weight,
                           frequency=float(cfg["frequency"]), t0=t0, t1=t1, periods=periods,
                           title=_run_title(h5, cfg), path=h5.filename)
    finally:
        if close:
            h5.close()


# -- energy ----------------------------------------------------------------------------------
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
    m = _window(t, t0, t1, what="energy figure", path=path)
    t = np.asarray(t)[m]
    W = np.asarray(work)[m]
    res = np.asarray(residual)[m]
    col = {name: W[:, i] for i, name in enumerate(channels)}
    gran = sum(col[c] for c in GRANULAR if c in col)
    fig = _figure(FIGSIZE["energy"])
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
    turnover = np.abs(col.get("input", np.zeros_like(t))) + sum(
        np.abs(v) for k, v in col.items() if k != "input")
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
    h5, close = _open(h5_or_path)
    try:
        require(h5, "the energy figure", "run", ENERGY_PATHS)
        g = h5["series"]
        channels = json.loads(g["work"].attrs["channels"])
        cfg = json.loads(h5.attrs["config"])
        return energy_figure(g["t"][()], g["work"][()], channels, g["balance_residual"][()],
                             t0=t0, t1=t1, title=_run_title(h5, cfg), path=h5.filename)
    finally:
        if close:
            h5.close()


# -- FRF (sweep files) -------------------------------------------------------------------------
def frf_from_file(h5_or_path, out) -> str:
    """Amplitude ratio Z/U versus frequency from a sweep file (one curve per ``box.Lz``, with
    the fitted FRFs when ``/fit`` is present), written to ``out`` by
    :func:`jaxdamp.plots.frf_figure`. Returns ``out``."""
    from .config import from_json
    from .model import grain_mass
    from .plots import frf_figure

    h5, close = _open(h5_or_path)
    try:
        require(h5, "the FRF figure", "sweep", ("summary/amplitude",))
        axes = json.loads(h5.attrs["axes"])
        keys = list(axes)
        if "frequency" not in keys:
            raise OutputFileError(f"{h5.filename}: the FRF figure needs a sweep over 'frequency'; "
                                  f"this one sweeps {', '.join(keys)}")
        cfg = from_json(h5.attrs["base_config"])
        if cfg.system != "primary":
            raise OutputFileError(f"{h5.filename}: the FRF figure needs an S1 sweep (system "
                                  f"'primary'); this one is {cfg.system!r}")
        f = np.asarray(axes["frequency"], float)
        Z = np.asarray(h5["summary/amplitude"][()], float).reshape([len(axes[k]) for k in keys])
        if keys[0] != "frequency":
            Z = Z.T
        Z = Z.reshape(len(f), -1)
        other = [k for k in keys if k != "frequency"]
        if other and other[0] != "box.Lz":
            raise OutputFileError(f"{h5.filename}: the FRF figure draws one curve per box.Lz; "
                                  f"this sweep's second axis is {other[0]!r}")
        lz = [float(x) for x in axes["box.Lz"]] if other else [None]
        fits = None
        if "fit/M_ef" in h5 and "fit/C_ef" in h5:
            fits = list(zip(h5["fit/M_ef"][()], h5["fit/C_ef"][()]))
        order = np.argsort(f)
        title = f"{cfg.name}: {os.path.basename(h5.filename)}, N = {cfg.n_grains} grains"
        return frf_figure(out, f[order], Z[order], lz, cfg.primary, grain_mass(cfg), fits,
                          title=title)
    finally:
        if close:
            h5.close()


# -- 3-D snapshots -----------------------------------------------------------------------------
def _box_edges(Lx, Ly, Lz, z0):
    c = np.array([[x, y, z0 + z] for z in (0, Lz) for y in (0, Ly) for x in (0, Lx)])
    pairs = [(0, 1), (2, 3), (4, 5), (6, 7), (0, 2), (1, 3), (4, 6), (5, 7),
             (0, 4), (1, 5), (2, 6), (3, 7)]
    return [(c[i], c[j]) for i, j in pairs]


def _draw_snapshot(ax, r, radius, species, box, z_box, color, species_names, zlim, clim,
                   zoom=1.15):
    """Grains as scatter markers with their true size on screen, the box as a wireframe."""
    from matplotlib import colormaps

    Lx, Ly, Lz = box
    mm = 1e3
    for a, b in _box_edges(Lx, Ly, Lz, z_box):
        ax.plot(*(np.array([a, b]).T * mm), color="0.35", lw=0.8)
    # floor and lid shaded lightly so the box reads as a box
    ax.set_xlim(0, Lx * mm)
    ax.set_ylim(0, Ly * mm)
    ax.set_zlim(zlim[0] * mm, zlim[1] * mm)
    ax.set_box_aspect((Lx, Ly, zlim[1] - zlim[0]), zoom=zoom)
    ax.set_proj_type("ortho")
    ax.set_xlabel("x [mm]", fontsize=8)
    ax.set_ylabel("y [mm]", fontsize=8)
    ax.set_zlabel("z [mm] (lab frame)", fontsize=8)
    ax.tick_params(labelsize=7)
    # marker diameter in points: the vertical box edge (length Lz, foreshortened by cos(elev)
    # in the orthographic view) gives the scale
    from mpl_toolkits.mplot3d import proj3d

    fig = ax.figure
    fig.canvas.draw()
    xs, ys, _ = proj3d.proj_transform(np.array([0.0, 0.0]), np.array([0.0, 0.0]),
                                      np.array([z_box, z_box + Lz]) * mm, ax.get_proj())
    p = ax.transData.transform(np.column_stack([xs, ys]))
    pts_per_mm = np.hypot(*(p[1] - p[0])) * 72.0 / fig.dpi / (Lz * mm * np.cos(np.radians(ax.elev)))
    sizes = (2 * np.asarray(radius) * mm * pts_per_mm) ** 2
    if color == "height":
        c = (np.asarray(r)[:, 2] - z_box) * mm
        sc = ax.scatter(*(np.asarray(r).T * mm), s=sizes, c=c, cmap="viridis", vmin=clim[0] * mm,
                        vmax=clim[1] * mm, edgecolors="k", linewidths=0.2, alpha=0.95)
        return sc
    cmap = colormaps["tab10"]
    sp = np.asarray(species)
    for k in np.unique(sp):
        sel = sp == k
        name = species_names[k] if k < len(species_names) else f"species {k}"
        ax.scatter(*(np.asarray(r)[sel].T * mm), s=sizes[sel], color=cmap(int(k) % 10),
                   edgecolors="k", linewidths=0.2, alpha=0.95,
                   label=f"{name} (r = {np.mean(np.asarray(radius)[sel]) * mm:.3g} mm)")
    diam = float(np.sqrt(sizes.max())) if len(sizes) else 8.0
    ax.legend(fontsize=7, loc="upper left", markerscale=min(1.0, 8.0 / max(diam, 1e-9)))
    return None


def snapshot_figure(r, radius, species, box, z_box=0.0, *, color="species", species_names=(),
                    t=None, zlim=None, title=""):
    """3-D view of the grains: positions ``r`` (N, 3) [m], ``radius`` (N,) [m], ``species``
    (N,), box ``(Lx, Ly, Lz)`` [m] with its floor at ``z_box`` [m]; ``color`` is
    ``'species'`` or ``'height'`` (height of the centre above the floor)."""
    if color not in ("species", "height"):
        raise OutputFileError(f"color {color!r}: choose 'species' or 'height'")
    Lx, Ly, Lz = box
    zlim = zlim or (z_box, z_box + Lz)
    fig = _figure(FIGSIZE["snapshot"])
    ax = fig.add_axes((0.0, 0.02, 0.8 if color == "height" else 0.97, 0.9), projection="3d")
    h = np.asarray(r)[:, 2] - z_box
    sc = _draw_snapshot(ax, r, radius, species, box, z_box, color, list(species_names), zlim,
                        (float(h.min()), float(h.max())))
    if sc is not None:
        fig.colorbar(sc, cax=fig.add_axes((0.8, 0.3, 0.03, 0.4)),
                     label="height of the centre above the floor [mm]")
    head = f"t = {t:.5g} s, " if t is not None else ""
    fig.suptitle((title + "\n" if title else "") + f"{head}{len(radius)} grains; "
                 f"box {Lx * 1e3:g} × {Ly * 1e3:g} × {Lz * 1e3:g} mm", fontsize=9)
    return fig


def snapshot_from_file(h5_or_path, frame=-1, color="species"):
    """:func:`snapshot_figure` of snapshot ``frame`` (negative counts from the end)."""
    h5, close = _open(h5_or_path)
    try:
        s = load_snapshots(h5, frames=[frame], what="the snapshot figure")
        cfg = json.loads(h5.attrs["config"])
        return snapshot_figure(s.r[0], s.radius, s.species, s.box, float(s.z_box[0]),
                               color=color, species_names=s.species_names, t=float(s.t[0]),
                               title=_run_title(h5, cfg) + f", snapshot {int(s.frames[0])}")
    finally:
        if close:
            h5.close()


# -- Poincaré section --------------------------------------------------------------------------
def poincare_figure(t, z_cm, vz_cm, frequency, *, phase=0.0, t0=None, t1=None, title="", path=""):
    """Poincaré section of the bed's centre of mass: ``(z_cm, vz_cm)`` sampled once per drive
    period ``1/f`` (at phase ``phase`` of ``cos 2πft``, by
    :func:`jaxdamp.dynamics.poincare_section`), coloured by time, over the thin trajectory in
    the same plane."""
    from .dynamics import poincare_section

    m = _window(t, t0, t1, what="Poincaré section", path=path)
    t, z, v = (np.asarray(a)[m] for a in (t, z_cm, vz_cm))
    sec = poincare_section(t, z, frequency, phase)
    tk, zk = sec.t, sec.x
    # the recorded velocity at the same instants (not the spline's derivative of z_cm, which
    # smooths over collisions)
    vk = poincare_section(t, v, frequency, phase).x
    mm = 1e3
    fig = _figure(FIGSIZE["poincare"])
    ax = fig.subplots()
    ax.plot(z * mm, v, "-", color="0.8", lw=0.5, label="trajectory")
    if len(tk):
        sc = ax.scatter(zk * mm, vk, c=tk, cmap="viridis", s=22, zorder=3,
                        label=f"once per period ({len(tk)} point{'s' if len(tk) != 1 else ''})")
        fig.colorbar(sc, ax=ax, label="time t [s]")
    else:
        ax.text(0.5, 0.5, "no full drive period in the window", transform=ax.transAxes,
                ha="center", va="center")
    ax.set_xlabel("centre of mass $z_{cm}$ [mm] (lab frame)")
    ax.set_ylabel("centre-of-mass velocity $v_{z,cm}$ [m/s]")
    ax.set_title((title + "\n" if title else "") +
                 f"stroboscopic section at T = 1/f = {1e3 / frequency:.4g} ms, phase {phase:g} rad",
                 fontsize=9)
    ax.legend(fontsize=8, loc="best")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def poincare_from_file(h5_or_path, t0=None, t1=None, phase=0.0):
    """:func:`poincare_figure` of a run file at its drive frequency."""
    h5, close = _open(h5_or_path)
    try:
        require(h5, "the Poincaré section", "run", POINCARE_PATHS)
        g = h5["series"]
        cfg = json.loads(h5.attrs["config"])
        return poincare_figure(g["t"][()], g["z_cm"][()], g["vz_cm"][()],
                               float(cfg["frequency"]), phase=phase, t0=t0, t1=t1,
                               title=_run_title(h5, cfg), path=h5.filename)
    finally:
        if close:
            h5.close()


# -- animation ---------------------------------------------------------------------------------
def animate(h5_or_path, out, *, every=1, fps=10, color="species", dpi=80) -> str:
    """Write the snapshots (every ``every``-th) as an animation: ``.gif`` through matplotlib's
    PillowWriter, ``.mp4`` through ffmpeg (must be on ``PATH``). Returns ``out``."""
    from matplotlib.animation import FFMpegWriter, PillowWriter

    out = os.fspath(out)
    ext = os.path.splitext(out)[1].lower()
    if ext == ".gif":
        writer = PillowWriter(fps=fps)
    elif ext == ".mp4":
        if shutil.which("ffmpeg") is None:
            raise OutputFileError(f"{out}: MP4 needs ffmpeg on PATH (not found); write a .gif instead")
        writer = FFMpegWriter(fps=fps)
    else:
        raise OutputFileError(f"{out}: animations are written as .gif or .mp4")
    if color not in ("species", "height"):
        raise OutputFileError(f"color {color!r}: choose 'species' or 'height'")
    h5, close = _open(h5_or_path)
    try:
        s = load_snapshots(h5, every=every, what="the animation")
        cfg = json.loads(h5.attrs["config"])
        title = _run_title(h5, cfg)
    finally:
        if close:
            h5.close()
    Lx, Ly, Lz = s.box
    zlim = (float(s.z_box.min()), float(s.z_box.max()) + Lz)
    h = s.r[:, :, 2] - s.z_box[:, None]
    clim = (float(h.min()), float(h.max()))
    fig = _figure(FIGSIZE["animation"], dpi=dpi)
    ax = fig.add_axes((0.0, 0.01, 0.85 if color == "height" else 1.0, 0.89), projection="3d")
    if color == "height":
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        fig.colorbar(ScalarMappable(Normalize(clim[0] * 1e3, clim[1] * 1e3), "viridis"),
                     cax=fig.add_axes((0.84, 0.3, 0.03, 0.4)), label="height above floor [mm]")
    with writer.saving(fig, out, dpi):
        for k in range(len(s.t)):
            ax.cla()
            _draw_snapshot(ax, s.r[k], s.radius, s.species, s.box, float(s.z_box[k]), color,
                           s.species_names, zlim, clim, zoom=0.95)
            fig.suptitle(f"{title}\nt = {s.t[k]:.5g} s (snapshot {int(s.frames[k])})", fontsize=8)
            writer.grab_frame()
    return out

"""Bed snapshots and animation.

One routine draws a snapshot panel, :func:`draw_snapshot`: grains to scale, coloured by
species or by height above the floor, and the box — in 3-D (orthographic, lab frame) on a
``projection="3d"`` axes, as an x–z side view (box frame) on a plain axes. It is used by

- :func:`snapshot_figure` — one snapshot in 3-D (:func:`snapshot_from_file` from a run file);
- :func:`snapshot_grid_figure` — side views of several beds at several instants (the 2023
  paper's fig. 3; ``jaxdamp efficiency``);
- :func:`animate` — GIF (Pillow) or MP4 (ffmpeg) of a run file's snapshots.
"""

from __future__ import annotations

import json
import os
import shutil

import numpy as np

from jaxdamp.figures._files import open_file, run_title
from jaxdamp.figures.style import FIGSIZE, SPECIES_COLOURS, figure
from jaxdamp.io.export import OutputFileError, load_snapshots

MM = 1e3  # m → mm: every bed drawing is in mm
COLOURINGS = ("species", "height")


def _check_colour(color):
    if color not in COLOURINGS:
        raise OutputFileError(f"color {color!r}: choose 'species' or 'height'")


def draw_snapshot(ax, r, radius, species, config, z_box=0.0, *, color="species",
                  species_names=(), zlim=None, clim=None, zoom=1.15, legend=True, fontsize=8):
    """Draw one bed snapshot on ``ax``; returns the height colour map (a
    :class:`matplotlib.cm.ScalarMappable` for a colour bar) or ``None``.

    Args:
      r: grain centres ``(N, 3)`` [m] (lab frame); radius ``(N,)`` [m]; species ``(N,)``;
        ``config`` the run's :class:`~jaxdamp.config.Config`, whose container
        (:mod:`jaxdamp.physics.containers`) is drawn with its floor at ``z_box`` [m].
      color: ``"species"`` (:data:`jaxdamp.figures.SPECIES_COLOURS`, legend with
        ``species_names`` when ``legend``) or ``"height"`` (of the centre above the floor,
        viridis over ``clim`` [m], default the snapshot's range).
      zlim: 3-D only: the z range [m] (lab frame), default the box.
      zoom: 3-D only: ``set_box_aspect`` zoom.

    On a 3-D axes the view is orthographic in the lab frame, the container a wireframe and each
    grain a marker whose size on screen is its true diameter; on a 2-D axes it is the x–z side
    view in the box frame (``z − z_box``), grains as circles, large ones drawn first.
    """
    from jaxdamp.physics.containers import container  # the physics: on use

    _check_colour(color)
    r, radius, sp = np.asarray(r, float), np.asarray(radius, float), np.asarray(species, int)
    Lz = container(config).height(config)
    h = r[:, 2] - z_box
    if clim is None:
        clim = (float(h.min()), float(h.max())) if len(h) else (0.0, Lz)
    mappable = None
    if color == "height":
        from matplotlib.cm import ScalarMappable
        from matplotlib.colors import Normalize

        mappable = ScalarMappable(Normalize(clim[0] * MM, clim[1] * MM), "viridis")
        faces = mappable.to_rgba(h * MM)
    else:
        from matplotlib.colors import to_rgba_array

        faces = to_rgba_array([SPECIES_COLOURS[k % len(SPECIES_COLOURS)] for k in sp])
    if getattr(ax, "name", "") == "3d":
        _draw_3d(ax, r, radius, faces, config, z_box, zlim or (z_box, z_box + Lz), zoom,
                 fontsize)
    else:
        _draw_side(ax, r, radius, faces, config, z_box, fontsize)
    if legend and color == "species" and len(sp):
        from matplotlib.lines import Line2D

        names = list(species_names)
        handles = [Line2D([], [], ls="", marker="o", ms=7, mfc=SPECIES_COLOURS[k % len(SPECIES_COLOURS)],
                          mec="k", mew=0.3,
                          label=f"{names[k] if k < len(names) else f'species {k}'} "
                                f"(r = {np.mean(radius[sp == k]) * MM:.3g} mm)")
                   for k in np.unique(sp)]
        ax.legend(handles=handles, fontsize=fontsize - 1, loc="upper left")
    return mappable


def _draw_3d(ax, r, radius, faces, config, z_box, zlim, zoom, fontsize):
    from mpl_toolkits.mplot3d import proj3d

    from jaxdamp.physics.containers import container  # the physics: on use
    from jaxdamp.physics.model import cell_outlines, damper_extent

    vessel = container(config)
    Lz = vessel.height(config)
    x0, x1, y0, y1 = damper_extent(config, radius)  # every cell (Config.cells)
    for line in cell_outlines(config, radius, z_box):
        ax.plot(*(np.asarray(line).T * MM), color="0.35", lw=0.8)
    ax.set_xlim(x0 * MM, x1 * MM)
    ax.set_ylim(y0 * MM, y1 * MM)
    ax.set_zlim(zlim[0] * MM, zlim[1] * MM)
    ax.set_box_aspect((x1 - x0, y1 - y0, zlim[1] - zlim[0]), zoom=zoom)
    ax.set_proj_type("ortho")
    ax.set_xlabel("x [mm]", fontsize=fontsize)
    ax.set_ylabel("y [mm]", fontsize=fontsize)
    ax.set_zlabel("z [mm] (lab frame)", fontsize=fontsize)
    ax.tick_params(labelsize=fontsize - 1)
    # marker diameter in points: a vertical edge (length Lz, foreshortened by cos(elev)
    # in the orthographic view) gives the scale
    fig = ax.figure
    fig.canvas.draw()
    xs, ys, _ = proj3d.proj_transform(np.array([x0, x0]) * MM, np.array([y0, y0]) * MM,
                                      np.array([z_box, z_box + Lz]) * MM, ax.get_proj())
    p = ax.transData.transform(np.column_stack([xs, ys]))
    pts_per_mm = np.hypot(*(p[1] - p[0])) * 72.0 / fig.dpi / (Lz * MM * np.cos(np.radians(ax.elev)))
    sizes = (2 * radius * MM * pts_per_mm) ** 2
    ax.scatter(*(r.T * MM), s=sizes, c=faces, edgecolors="k", linewidths=0.2, alpha=0.95)


def _draw_side(ax, r, radius, faces, config, z_box, fontsize):
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle, Rectangle

    from jaxdamp.physics.containers import container  # the physics: on use
    from jaxdamp.physics.model import cell_origins

    vessel = container(config)
    Lz = vessel.height(config)
    c0, c1, _, _ = vessel.extent(config)
    origins = cell_origins(config, radius)[:, 0]  # every cell (Config.cells)
    x0, x1 = c0 + origins.min(), c1 + origins.max()
    order = np.argsort(-radius)  # small grains drawn last, on top
    circles = [Circle((r[k, 0] * MM, (r[k, 2] - z_box) * MM), radius[k] * MM) for k in order]
    ax.add_collection(PatchCollection(circles, facecolor=faces[order], edgecolor="none",
                                      alpha=0.8))
    for ox in origins:
        ax.add_patch(Rectangle(((c0 + ox) * MM, 0), (c1 - c0) * MM, Lz * MM, fill=False,
                               lw=1))
    pad = 0.02 * max(x1 - x0, Lz) * MM
    ax.set_xlim(x0 * MM - pad, x1 * MM + pad)
    ax.set_ylim(-pad, Lz * MM + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]", fontsize=fontsize)
    ax.set_ylabel("z − z_box [mm] (box frame)", fontsize=fontsize)
    ax.tick_params(labelsize=fontsize - 1)


def snapshot_figure(r, radius, species, config, z_box=0.0, *, color="species", species_names=(),
                    t=None, zlim=None, title=""):
    """3-D view of the grains (:func:`draw_snapshot`): positions ``r`` (N, 3) [m], ``radius``
    (N,) [m], ``species`` (N,), the container of ``config`` with its floor at ``z_box`` [m];
    ``color`` is ``'species'`` or ``'height'`` (height of the centre above the floor)."""
    from jaxdamp.physics.containers import container  # the physics: on use

    _check_colour(color)
    vessel = container(config)
    fig = figure(FIGSIZE["snapshot"])
    ax = fig.add_axes((0.0, 0.02, 0.8 if color == "height" else 0.97, 0.9), projection="3d")
    sc = draw_snapshot(ax, r, radius, species, config, z_box, color=color,
                       species_names=species_names, zlim=zlim)
    if sc is not None:
        fig.colorbar(sc, cax=fig.add_axes((0.8, 0.3, 0.03, 0.4)),
                     label="height of the centre above the floor [mm]")
    head = f"t = {t:.5g} s, " if t is not None else ""
    cells = f" × {config.cells} cells" if config.cells > 1 else ""
    fig.suptitle((title + "\n" if title else "") + f"{head}{len(radius)} grains; "
                 f"{vessel.name}{cells}: {vessel.describe(config)}, height "
                 f"{vessel.height(config) * MM:g} mm", fontsize=9)
    return fig


def snapshot_from_file(h5_or_path, frame=-1, color="species"):
    """:func:`snapshot_figure` of snapshot ``frame`` (negative counts from the end)."""
    h5, close = open_file(h5_or_path)
    try:
        s = load_snapshots(h5, frames=[frame], what="the snapshot figure")
        cfg = json.loads(h5.attrs["config"])
        return snapshot_figure(s.r[0], s.radius, s.species, s.config, float(s.z_box[0]),
                               color=color, species_names=s.species_names, t=float(s.t[0]),
                               title=run_title(h5, cfg) + f", snapshot {int(s.frames[0])}")
    finally:
        if close:
            h5.close()


def snapshot_grid_figure(rows, title=""):
    """Side views (x–z, box frame) of beds at chosen instants (:func:`draw_snapshot` on 2-D
    axes), grains to scale, coloured by species (the 2023 paper's fig. 3).

    Args:
      rows: ``[(label, [(caption, r (N, 3) [m], z_box [m]), ...], radii (N,) [m], species
        (N,), config), ...]``; one row per system (``config``: its
        :class:`~jaxdamp.config.Config`, whose container is drawn), one panel per instant.
    """
    ncol = max(len(r[1]) for r in rows)
    w, h = FIGSIZE["snapshot_panel"]
    fig = figure((w * ncol, h * len(rows)))
    axes = fig.subplots(len(rows), ncol, squeeze=False)
    for i, (label, frames, radii, species, config) in enumerate(rows):
        for j, (caption, r, z_box) in enumerate(frames):
            draw_snapshot(axes[i, j], r, radii, species, config, z_box, legend=False,
                          fontsize=7)
            axes[i, j].set_title(f"{label}\n{caption}", fontsize=7)
        for j in range(len(frames), ncol):
            axes[i, j].axis("off")
    fig.suptitle(title + "  (x–z side view, box frame [mm]; red: large, green: small)",
                 fontsize=8)
    fig.tight_layout()
    return fig


def animate(h5_or_path, out, *, every=1, fps=10, color="species", dpi=80) -> str:
    """Write the snapshots (every ``every``-th) as an animation of :func:`draw_snapshot`
    frames: ``.gif`` through matplotlib's PillowWriter, ``.mp4`` through ffmpeg (must be on
    ``PATH``). Returns ``out``."""
    from matplotlib.animation import FFMpegWriter, PillowWriter

    from jaxdamp.physics.containers import container  # the physics: on use

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
    _check_colour(color)
    h5, close = open_file(h5_or_path)
    try:
        s = load_snapshots(h5, every=every, what="the animation")
        cfg = json.loads(h5.attrs["config"])
        title = run_title(h5, cfg)
    finally:
        if close:
            h5.close()
    Lz = container(s.config).height(s.config)
    zlim = (float(s.z_box.min()), float(s.z_box.max()) + Lz)
    h = s.r[:, :, 2] - s.z_box[:, None]
    clim = (float(h.min()), float(h.max()))
    fig = figure(FIGSIZE["animation"], dpi=dpi)
    ax = fig.add_axes((0.0, 0.01, 0.85 if color == "height" else 1.0, 0.89), projection="3d")
    cax = fig.add_axes((0.84, 0.3, 0.03, 0.4)) if color == "height" else None
    with writer.saving(fig, out, dpi):
        for k in range(len(s.t)):
            ax.cla()
            sc = draw_snapshot(ax, s.r[k], s.radius, s.species, s.config, float(s.z_box[k]),
                               color=color, species_names=s.species_names, zlim=zlim,
                               clim=clim, zoom=0.95)
            if k == 0 and sc is not None:
                fig.colorbar(sc, cax=cax, label="height above floor [mm]")
            fig.suptitle(f"{title}\nt = {s.t[k]:.5g} s (snapshot {int(s.frames[k])})", fontsize=8)
            writer.grab_frame()
    return out

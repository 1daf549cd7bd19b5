"""Bed snapshots and animation.

One routine draws a snapshot panel, :func:`draw_snapshot`: grains to scale, coloured by
species or by height above the floor, and the container — in 3-D (orthographic, lab frame) on
a ``projection="3d"`` axes; on a plain axes as the x–z side view or the x–y view from above
(:data:`VIEWS`, box frame). It is used by

- :func:`snapshot_figure` — one snapshot in 3-D, or in any of the views side by side (side and
  top: ``view="side,top"``; :func:`snapshot_from_file` from a run file);
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
from jaxdamp.io.export import OutputFileError, box_offset, load_snapshots

MM = 1e3  # m → mm: every bed drawing is in mm
COLOURINGS = ("species", "height")
#: The views of a bed: ``"3d"`` (orthographic, lab frame, on a ``projection="3d"`` axes),
#: ``"side"`` (the x–z plane seen along +y, box frame) and ``"top"`` (the x–y plane seen from
#: above, box frame), the last two on plain axes.
VIEWS = ("3d", "side", "top")


def _check_colour(color):
    if color not in COLOURINGS:
        raise OutputFileError(f"color {color!r}: choose 'species' or 'height'")


def parse_views(view) -> tuple[str, ...]:
    """The views :func:`snapshot_figure` draws side by side, from one name of :data:`VIEWS`,
    a comma-separated list of them (``"side,top"``) or a sequence; each at most once."""
    names = view.split(",") if isinstance(view, str) else list(view)
    names = [str(v).strip().lower() for v in names]
    bad = [v for v in names if v not in VIEWS]
    if bad or not names or len(set(names)) < len(names):
        raise OutputFileError(f"view {view!r}: choose {', '.join(VIEWS[:-1])} or {VIEWS[-1]}, "
                              "or several of them once each, comma-separated (e.g. side,top)")
    return tuple(names)


def draw_snapshot(ax, r, radius, species, config, z_box=0.0, *, view=None, color="species",
                  species_names=(), zlim=None, clim=None, zoom=1.15, legend=True, fontsize=8):
    """Draw one bed snapshot on ``ax``; returns the height colour map (a
    :class:`matplotlib.cm.ScalarMappable` for a colour bar) or ``None``.

    Args:
      r: grain centres ``(N, 3)`` [m] (lab frame); radius ``(N,)`` [m]; species ``(N,)``;
        ``config`` the run's :class:`~jaxdamp.config.Config`, whose container
        (:mod:`jaxdamp.physics.containers`) is drawn displaced by ``z_box`` [m] along the
        excitation axis (the floor's height for the default vertical drive).
      view: one of :data:`VIEWS`; default ``"3d"`` on a 3-D axes, ``"side"`` on a plain one
        (``"side"`` and ``"top"`` need a plain axes, ``"3d"`` a 3-D one).
      color: ``"species"`` (:data:`jaxdamp.figures.SPECIES_COLOURS`, legend with
        ``species_names`` when ``legend``) or ``"height"`` (of the centre above the floor,
        viridis over ``clim`` [m], default the snapshot's range).
      zlim: 3-D only: the z range [m] (lab frame), default the box.
      zoom: 3-D only: ``set_box_aspect`` zoom.

    On a 3-D axes the view is orthographic in the lab frame, the container a wireframe and each
    grain a marker whose size on screen is its true diameter. The side view is the x–z plane
    in the box frame (``z − z_box``), grains as circles of their radius, large ones drawn first,
    the container's silhouette a rectangle. The top view is the x–y plane seen from above (box
    frame): grains as circles of their radius, the highest drawn last (on top, as seen from
    above), inside the section's outline — the container's ``outline`` edges projected on x–y.
    """
    from jaxdamp.physics.containers import container  # the physics: on use

    _check_colour(color)
    is_3d = getattr(ax, "name", "") == "3d"
    view = view or ("3d" if is_3d else "side")
    if view not in VIEWS or (view == "3d") != is_3d:
        raise OutputFileError(f"view {view!r} on a {'3-D' if is_3d else 'plain'} axes: the "
                              "3-D view needs a projection='3d' axes, the side and top views "
                              "a plain one")
    r, radius, sp = np.asarray(r, float), np.asarray(radius, float), np.asarray(species, int)
    Lz = container(config).height(config)
    offset = box_offset(config, z_box)  # the container's place in the lab frame
    rb = r - offset  # the grains in the box frame
    h = rb[:, 2]
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
    if view == "3d":
        _draw_3d(ax, r, radius, faces, config, offset, zlim or (offset[2], offset[2] + Lz),
                 zoom, fontsize)
    elif view == "side":
        _draw_side(ax, rb, radius, faces, config, fontsize)
    else:
        _draw_top(ax, rb, radius, faces, config, fontsize)
    if legend and color == "species" and len(sp):
        from matplotlib.lines import Line2D

        names = list(species_names)
        handles = [Line2D([], [], ls="", marker="o", ms=7,
                          mfc=SPECIES_COLOURS[k % len(SPECIES_COLOURS)], mec="k", mew=0.3,
                          label=f"{names[k] if k < len(names) else f'species {k}'} "
                                f"(r = {np.mean(radius[sp == k]) * MM:.3g} mm)")
                   for k in np.unique(sp)]
        ax.legend(handles=handles, fontsize=fontsize - 1, loc="upper left")
    return mappable


def _draw_3d(ax, r, radius, faces, config, offset, zlim, zoom, fontsize):
    from mpl_toolkits.mplot3d import proj3d

    from jaxdamp.physics.containers import container  # the physics: on use
    from jaxdamp.physics.model import cell_outlines, damper_extent

    vessel = container(config)
    Lz = vessel.height(config)
    x0, x1, y0, y1 = damper_extent(config, radius)  # every cell (Config.cells)
    for line in cell_outlines(config, radius, 0.0):
        ax.plot(*((np.asarray(line) + offset).T * MM), color="0.35", lw=0.8)
    x0, x1, y0, y1 = x0 + offset[0], x1 + offset[0], y0 + offset[1], y1 + offset[1]
    z_box = offset[2]  # the floor's height in the lab frame
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


def _draw_side(ax, rb, radius, faces, config, fontsize):
    """The x–z side view; ``rb``: the grain centres in the box frame [m]."""
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
    circles = [Circle((rb[k, 0] * MM, rb[k, 2] * MM), radius[k] * MM) for k in order]
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


def _draw_top(ax, rb, radius, faces, config, fontsize):
    """The x–y view from above; ``rb``: the grain centres in the box frame [m]. The section's
    outline is every cell's ``outline`` (3-D edges) projected on the x–y plane: the edges
    that project to a point (vertical ones) are left out, and the lid's edges, which repeat
    the floor's, drawn once."""
    from matplotlib.collections import PatchCollection
    from matplotlib.patches import Circle

    from jaxdamp.physics.model import cell_outlines, damper_extent  # the physics: on use

    x0, x1, y0, y1 = damper_extent(config, radius)  # every cell (Config.cells)
    order = np.argsort(rb[:, 2], kind="stable")  # the highest grains drawn last, on top
    circles = [Circle((rb[k, 0] * MM, rb[k, 1] * MM), radius[k] * MM) for k in order]
    ax.add_collection(PatchCollection(circles, facecolor=faces[order], edgecolor="k",
                                      linewidths=0.2))
    seen = set()
    for line in cell_outlines(config, radius, 0.0):
        xy = np.asarray(line)[:, :2] * MM
        key = np.round(xy, 9).tobytes()
        if np.ptp(xy, axis=0).max() == 0.0 or key in seen:
            continue
        seen.add(key)
        ax.plot(xy[:, 0], xy[:, 1], color="k", lw=1)
    pad = 0.02 * max(x1 - x0, y1 - y0) * MM
    ax.set_xlim(x0 * MM - pad, x1 * MM + pad)
    ax.set_ylim(y0 * MM - pad, y1 * MM + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x [mm]", fontsize=fontsize)
    ax.set_ylabel("y [mm] (box frame, seen from above)", fontsize=fontsize)
    ax.tick_params(labelsize=fontsize - 1)


def snapshot_figure(r, radius, species, config, z_box=0.0, *, view="3d", color="species",
                    species_names=(), t=None, zlim=None, title=""):
    """The grains of one snapshot (:func:`draw_snapshot`) in ``view``: one of :data:`VIEWS`
    or several side by side (``"side,top"``, or a sequence; :func:`parse_views`), for any
    container. Positions ``r`` (N, 3) [m], ``radius`` (N,) [m], ``species`` (N,), the container
    of ``config`` displaced by ``z_box`` [m]; ``color`` is ``'species'`` or ``'height'``
    (height of the centre above the floor, one colour bar for every panel).

    The figure is :data:`FIGSIZE` ``["snapshot"]`` for one or two views, widened by half for
    three; the plain panels keep fixed margins in inches for their labels, their data at equal
    scales in x and y (or z). The plain views of a damper of several cells (a row along x)
    stand one above another, the full width each."""
    from jaxdamp.physics.containers import container  # the physics: on use

    views = parse_views(view)
    _check_colour(color)
    vessel = container(config)
    w, h = FIGSIZE["snapshot"]
    w *= max(1.0, len(views) / 2)
    rows = config.cells > 1 and "3d" not in views  # a row of cells: the views one above another
    if rows:
        w, h = 1.5 * FIGSIZE["snapshot"][0], 0.5 * FIGSIZE["snapshot"][1] * len(views)
    fig = figure((w, h))
    right = 0.8 if color == "height" else 0.97  # room for the colour bar
    cell = right / len(views)
    left, gap, bottom, top = 0.75 / w, 0.15 / w, 0.55 / h, 0.95 / h  # margins [inch] → [-]
    sc = None
    for i, v in enumerate(views):
        if v == "3d":
            ax = fig.add_axes((i * cell, 0.02, cell, 0.9), projection="3d")
        elif rows:
            band = (1 - top) / len(views)
            ax = fig.add_axes((left, 1 - top - (i + 1) * band + bottom, right - left - gap,
                               band - bottom - 0.1 / h))
        else:
            ax = fig.add_axes((i * cell + left, bottom, cell - left - gap, 1 - bottom - top))
        sc = draw_snapshot(ax, r, radius, species, config, z_box, view=v, color=color,
                           species_names=species_names, zlim=zlim, legend=i == 0)
        if len(views) > 1:
            ax.set_title({"3d": "3-D (lab frame)", "side": "side view (x–z)",
                          "top": "top view (x–y)"}[v], fontsize=8)
    if sc is not None:
        fig.colorbar(sc, cax=fig.add_axes((0.8, 0.3, 0.03, 0.4)),
                     label="height of the centre above the floor [mm]")
    head = f"t = {t:.5g} s, " if t is not None else ""
    cells = f" × {config.cells} cells" if config.cells > 1 else ""
    fig.suptitle((title + "\n" if title else "") + f"{head}{len(radius)} grains; "
                 f"{vessel.name}{cells}: {vessel.describe(config)}, height "
                 f"{vessel.height(config) * MM:g} mm", fontsize=9)
    return fig


def snapshot_from_file(h5_or_path, frame=-1, color="species", view="3d"):
    """:func:`snapshot_figure` of snapshot ``frame`` (negative counts from the end) in
    ``view`` (:func:`parse_views`)."""
    views = parse_views(view)  # a bad view named before the file is read
    h5, close = open_file(h5_or_path)
    try:
        s = load_snapshots(h5, frames=[frame], what="the snapshot figure")
        cfg = json.loads(h5.attrs["config"])
        return snapshot_figure(s.r[0], s.radius, s.species, s.config, float(s.z_box[0]),
                               view=views, color=color, species_names=s.species_names,
                               t=float(s.t[0]),
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
            raise OutputFileError(f"{out}: MP4 needs ffmpeg on PATH (not found); write a .gif "
                                  "instead")
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
    floor = box_offset(s.config, s.z_box)[:, 2]  # the floor's height in the lab frame [m]
    zlim = (float(floor.min()), float(floor.max()) + Lz)
    h = s.r[:, :, 2] - floor[:, None]
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

"""Trajectory export of a run file's ``/snapshots``: extended XYZ (OVITO, ASE) and legacy VTK
polydata with a ParaView ``.pvd`` collection. Small self-contained writers, no dependency
beyond numpy and h5py.

Also the shared helpers that open an output file and check what it holds
(:func:`open_output`, :func:`file_kind`, :func:`require`), used by :mod:`jaxdamp.figures`.

Conventions of the written files (SI units, lab frame, as in the run file). The container
(:mod:`jaxdamp.physics.containers`) is fixed in the box frame, which is displaced from the lab
frame by ``e z_box`` (``e`` the excitation axis, ``(0, 0, 1)`` unless ``Config.direction``
says otherwise; ``z_box`` the box's position along it, from ``/series/z_box``):

- **extended XYZ** (``.xyz``, one frame per snapshot)::

      N
      Lattice="Lx 0 0 0 Ly 0 0 0 Lz" Origin="x0 y0 z0" Properties=species:S:1:pos:R:3:...
          ...radius:R:1:orientation:R:4 Time=t pbc="F F F" container=box   (one line)
      steel x y z radius qx qy qz qw

  ``Lattice`` and ``Origin`` are the container's bounding box at the snapshot's time: its
  section's bounding rectangle ``extent`` (for a cylinder of radius ``R_c`` the square
  ``[0, 2 R_c]²`` around it: a cell is a parallelepiped, so a curved wall cannot be one; a
  damper of several cells: the rectangle around all of them,
  :func:`jaxdamp.physics.model.damper_extent`) by its height ``Lz``, its corner at
  ``(x0, y0, 0) + e z_box``; ``container`` names the container (OVITO keeps it as a global
  attribute). ``orientation`` is written in OVITO's component order ``(x, y, z, w)``; the run
  file stores ``(w, x, y, z)``.
- **legacy VTK** (``<stem>_0000.vtk``, ... one per snapshot): ``DATASET POLYDATA`` with the
  grain centres as ``POINTS`` and ``VERTICES``, dataset field data ``TIME`` and ``z_box``, and
  point data ``radius`` [m] (the active scalars, for glyph scaling), ``species`` (index) and
  ``orientation`` ``(w, x, y, z)``. Beside each, ``<stem>_container_0000.vtk``: the
  container's edges (its ``outline``: for a box the 12 edges, for a cylinder the floor and lid
  circles as 72-sided polygons and four vertical lines) as polydata ``LINES`` at the
  snapshot's position, with the same field data. The ``.pvd`` collection indexes both by time
  (the grains as part 0, the container as part 1); ``<stem>.vtk.series`` and
  ``<stem>_container.vtk.series`` (ParaView ≥ 5.5 file-series JSON) list the same frames and
  times, since ParaView's PVD reader is documented for the XML VTK formats only and the
  ``.series`` file is what its legacy-VTK reader uses. ParaView also groups the numbered
  ``.vtk`` files on its own.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass

import h5py
import numpy as np

from jaxdamp.config import Config, ConfigError, from_json


class OutputFileError(ConfigError):
    """An output file is missing, of the wrong kind, or lacks what a figure/export needs."""


def open_output(path) -> h5py.File:
    """Open a jaxdamp HDF5 output file for reading, with an error naming the file if it is
    missing or not HDF5."""
    path = os.fspath(path)
    if not os.path.exists(path):
        raise OutputFileError(f"{path}: no such file")
    try:
        return h5py.File(path, "r")
    except OSError as err:
        raise OutputFileError(f"{path}: not an HDF5 file ({err})") from None


def file_kind(h5: h5py.File) -> str:
    """``'run'`` (``jaxdamp run``), ``'sweep'`` (``jaxdamp frf`` / ``sweep``), ``'optimize'``
    (an optimiser log) or ``'unknown'``: the family of :data:`jaxdamp.io.describe.FAMILIES`."""
    from jaxdamp.io.describe import file_family

    family = file_family(h5)
    return family.removeprefix("jaxdamp-") if family else "unknown"


def require(h5: h5py.File, what: str, kind: str, paths=()) -> None:
    """Raise :class:`OutputFileError` unless ``h5`` is of ``kind`` and holds every dataset in
    ``paths`` (with at least one row). ``what`` names the figure or export in the message."""
    have = file_kind(h5)
    if have != kind:
        from jaxdamp.io.describe import FAMILIES, what_file

        raise OutputFileError(f"{h5.filename}: {what} needs {FAMILIES['jaxdamp-' + kind][0]}, "
                              f"but this is {what_file(h5)}")
    missing = [p for p in paths if p not in h5 or h5[p].shape[:1] == (0,)]
    if missing:
        status = h5.attrs.get("status", "?")
        raise OutputFileError(f"{h5.filename}: {what} needs {', '.join('/' + p for p in missing)}, "
                              f"which the file lacks or holds empty (status {status!r})")


SNAPSHOT_PATHS = ("snapshots/t", "snapshots/r", "snapshots/q", "grains/radius", "grains/species")


@dataclass
class Snapshots:
    """Frames of a run file: ``t`` (S,) [s], ``r`` (S, N, 3) [m] lab frame, ``q`` (S, N, 4)
    ``(w, x, y, z)``, ``z_box`` (S,) [m] floor at each frame, ``radius`` (N,) [m], ``species``
    (N,) index, ``species_names``, ``config`` the run's configuration (its container:
    :mod:`jaxdamp.physics.containers`), ``frames`` (S,) indices into the file's
    ``/snapshots``."""

    t: np.ndarray
    r: np.ndarray
    q: np.ndarray
    z_box: np.ndarray
    radius: np.ndarray
    species: np.ndarray
    species_names: list
    config: Config
    frames: np.ndarray
    path: str


def load_snapshots(h5: h5py.File, every: int = 1, frames=None, what="snapshots") -> Snapshots:
    """Read ``/snapshots`` (every ``every``-th frame, or the given frame indices) with the box
    geometry and the floor height ``z_box`` at each frame (from ``/series``)."""
    require(h5, what, "run", SNAPSHOT_PATHS)
    if every < 1:
        raise OutputFileError(f"--every {every}: need a positive integer")
    n = h5["snapshots/t"].shape[0]
    if frames is None:
        idx = np.arange(0, n, every)
    else:
        idx = np.atleast_1d(np.asarray(frames, dtype=int))
        bad = [int(k) for k in idx if not -n <= k < n]
        if bad:
            raise OutputFileError(f"{h5.filename}: frame {bad[0]} out of range; the file holds "
                                  f"{n} snapshots (0 … {n - 1}, or -1 for the last)")
        idx = np.where(idx < 0, idx + n, idx)
    t = h5["snapshots/t"][()][idx]
    cfg = from_json(h5.attrs["config"])
    if "series/t" in h5 and "series/z_box" in h5 and h5["series/t"].shape[0]:
        z_box = np.interp(t, h5["series/t"][()], h5["series/z_box"][()])
    else:
        z_box = np.zeros_like(t)
    names = json.loads(h5["grains"].attrs.get("species_names", "[]"))
    return Snapshots(
        t=t, r=h5["snapshots/r"][()][idx], q=h5["snapshots/q"][()][idx], z_box=z_box,
        radius=h5["grains/radius"][()], species=h5["grains/species"][()].astype(int),
        species_names=names, config=cfg, frames=idx, path=h5.filename,
    )


def _species_labels(s: Snapshots) -> np.ndarray:
    names = [("_".join(str(n).split()) or f"s{i}") for i, n in enumerate(s.species_names)]
    return np.array([names[k] if k < len(names) else f"s{k}" for k in s.species])


# -- extended XYZ ----------------------------------------------------------------------------
XYZ_PROPERTIES = "species:S:1:pos:R:3:radius:R:1:orientation:R:4"


def box_offset(config: Config, z_box) -> np.ndarray:
    """Where the box frame's origin lies in the lab frame, ``e z_box`` [m]: ``(3,)`` for one
    position ``z_box`` [m] of the box along the excitation axis ``e``
    (:func:`jaxdamp.physics.model.excitation_axis`), ``(S, 3)`` for ``(S,)`` of them. A grain at
    ``r`` (lab frame) is at ``r − e z_box`` in the box frame, where the container is fixed."""
    from jaxdamp.physics.model import excitation_axis  # the physics: on use

    return np.multiply.outer(np.asarray(z_box, dtype=np.float64), excitation_axis(config))


def write_xyz(s: Snapshots, out) -> str:
    """Write every frame of ``s`` to one extended-XYZ file; returns the path."""
    from jaxdamp.physics.containers import container  # the physics: on use
    from jaxdamp.physics.model import damper_extent

    labels = _species_labels(s)
    vessel = container(s.config)
    x0, x1, y0, y1 = damper_extent(s.config, np.asarray(s.radius))  # every cell's
    Lx, Ly, Lz = x1 - x0, y1 - y0, vessel.height(s.config)
    corners = np.array([x0, y0, 0.0]) + box_offset(s.config, s.z_box)
    n = len(s.radius)
    os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    with open(out, "w") as f:
        for k in range(len(s.t)):
            f.write(f"{n}\n")
            f.write(f'Lattice="{Lx:.12g} 0 0 0 {Ly:.12g} 0 0 0 {Lz:.12g}" '
                    f'Origin="{" ".join(f"{v:.12g}" for v in corners[k])}" '
                    f'Properties={XYZ_PROPERTIES} '
                    f'Time={s.t[k]:.12g} pbc="F F F" container={vessel.name}\n')
            q = s.q[k][:, [1, 2, 3, 0]]  # (w, x, y, z) -> OVITO's (x, y, z, w)
            cols = np.column_stack([s.r[k], s.radius, q])
            for lab, row in zip(labels, cols):
                f.write(lab + " " + " ".join(f"{v:.12g}" for v in row) + "\n")
    return os.fspath(out)


# -- legacy VTK + PVD --------------------------------------------------------------------------
def _vtk_head(s: Snapshots, k: int, what: str) -> list[str]:
    """The header and dataset field data (``TIME``, ``z_box``) of frame ``k``'s polydata."""
    return [
        "# vtk DataFile Version 3.0",
        f"jaxdamp {what}, t = {s.t[k]:.12g} s (frame {int(s.frames[k])} of "
        f"{os.path.basename(s.path)})",
        "ASCII",
        "DATASET POLYDATA",
        "FIELD FieldData 2",
        "TIME 1 1 double",
        f"{s.t[k]:.12g}",
        "z_box 1 1 double",
        f"{s.z_box[k]:.12g}",
    ]


def _vtk_text(s: Snapshots, k: int) -> str:
    n = len(s.radius)
    lines = _vtk_head(s, k, "grains") + [f"POINTS {n} double"]
    lines += [" ".join(f"{v:.12g}" for v in p) for p in s.r[k]]
    lines.append(f"VERTICES {n} {2 * n}")
    lines += [f"1 {i}" for i in range(n)]
    lines.append(f"POINT_DATA {n}")
    lines += ["SCALARS radius double 1", "LOOKUP_TABLE default"]
    lines += [f"{v:.12g}" for v in s.radius]
    # further point arrays as field data: VTK's legacy reader keeps only the first SCALARS
    # block unless told to read all of them
    lines += ["FIELD point_fields 2", f"species 1 {n} int"]
    lines += [str(int(v)) for v in s.species]
    lines += [f"orientation 4 {n} double"]
    lines += [" ".join(f"{v:.12g}" for v in q) for q in s.q[k]]
    return "\n".join(lines) + "\n"


def _container_vtk_text(s: Snapshots, k: int, edges: list[np.ndarray], offset) -> str:
    """The container's ``edges`` (its ``outline`` in the box frame, polylines (P, 3) [m])
    moved by ``offset`` (``e z_box`` of frame ``k``) as polydata ``LINES``."""
    points = np.concatenate(edges) + offset
    lines = _vtk_head(s, k, "container") + [f"POINTS {len(points)} double"]
    lines += [" ".join(f"{v:.12g}" for v in p) for p in points]
    lines.append(f"LINES {len(edges)} {sum(len(e) + 1 for e in edges)}")
    start = 0
    for e in edges:
        lines.append(" ".join(str(i) for i in [len(e), *range(start, start + len(e))]))
        start += len(e)
    return "\n".join(lines) + "\n"


def write_vtk(s: Snapshots, pvd) -> tuple[str, list[str]]:
    """Write one legacy-VTK polydata file of the grains and one of the container per frame
    next to ``pvd`` (``<stem>_0000.vtk``, ..., ``<stem>_container_0000.vtk``, ...), the
    ParaView collection ``pvd`` indexing them by time (parts 0 and 1), ``<stem>.vtk.series``
    and ``<stem>_container.vtk.series``. Returns ``(pvd path, [vtk paths])``: the grains'
    frames, then the container's."""
    from jaxdamp.physics.model import cell_outlines  # the physics: on use

    pvd = os.fspath(pvd)
    folder = os.path.dirname(os.path.abspath(pvd))
    os.makedirs(folder, exist_ok=True)
    grains, walls = _frame_names(pvd, len(s.t))
    edges = [np.asarray(e, dtype=np.float64)  # every cell's (Config.cells)
             for e in cell_outlines(s.config, np.asarray(s.radius), 0.0)]
    offsets = box_offset(s.config, s.z_box)
    for k in range(len(s.t)):
        with open(os.path.join(folder, grains[k]), "w") as f:
            f.write(_vtk_text(s, k))
        with open(os.path.join(folder, walls[k]), "w") as f:
            f.write(_container_vtk_text(s, k, edges, offsets[k]))
    entries = "\n".join(f'    <DataSet timestep="{t:.12g}" group="" part="{part}" file="{name}"/>'
                        for t, g, w in zip(s.t, grains, walls)
                        for part, name in ((0, g), (1, w)))
    with open(pvd, "w") as f:
        f.write('<?xml version="1.0"?>\n'
                '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
                f"  <Collection>\n{entries}\n  </Collection>\n</VTKFile>\n")
    for series, names in zip(_series_names(pvd), (grains, walls)):
        with open(series, "w") as f:
            json.dump({"file-series-version": "1.0",
                       "files": [{"name": n, "time": float(t)} for t, n in zip(s.t, names)]},
                      f, indent=1)
    return pvd, [os.path.join(folder, n) for n in grains + walls]


def _frame_names(pvd: str, frames: int) -> tuple[list[str], list[str]]:
    """The names of the grains' and the container's frame files next to ``pvd``."""
    stem = os.path.splitext(os.path.basename(pvd))[0]
    width = max(4, len(str(frames - 1)))
    return ([f"{stem}_{k:0{width}d}.vtk" for k in range(frames)],
            [f"{stem}_container_{k:0{width}d}.vtk" for k in range(frames)])


def _series_names(pvd: str) -> list[str]:
    """The paths of the grains' and the container's ``.vtk.series`` files."""
    folder = os.path.dirname(os.path.abspath(pvd))
    stem = os.path.splitext(os.path.basename(pvd))[0]
    return [os.path.join(folder, f"{stem}{part}.vtk.series") for part in ("", "_container")]


def _vtk_names(pvd: str, frames: int) -> list[str]:
    """The files :func:`write_vtk` writes for ``frames`` frames: the ``.pvd``, the two
    ``.vtk.series`` and two ``.vtk`` per frame (grains, container)."""
    folder = os.path.dirname(os.path.abspath(pvd))
    grains, walls = _frame_names(pvd, frames)
    return [pvd, *_series_names(pvd)] + [os.path.join(folder, n) for n in grains + walls]


def planned_outputs(path, fmt: str, out=None, every: int = 1) -> list[str]:
    """Every file that exporting run file ``path`` as ``fmt`` (``xyz``, ``vtk``, ``gif``,
    ``mp4``) into ``out`` (default: next to ``path``) will write, read from the file without
    writing anything; raises :class:`OutputFileError` if the file cannot be exported."""
    path = os.fspath(path)
    stem = os.path.splitext(path)[0]
    with open_output(path) as h5:
        require(h5, f"export --format {fmt}", "run", SNAPSHOT_PATHS)
        if every < 1:
            raise OutputFileError(f"--every {every}: need a positive integer")
        frames = len(range(0, h5["snapshots/t"].shape[0], every))
    if fmt == "vtk":
        return _vtk_names(os.fspath(out or stem + ".pvd"), frames)
    return [os.fspath(out or f"{stem}.{fmt}")]


def export(path, fmt: str, out=None, every: int = 1) -> list[str]:
    """Export the snapshots of run file ``path`` as ``fmt`` (``'xyz'`` or ``'vtk'``).

    ``out`` defaults to the run file's name with ``.xyz`` / ``.pvd``. Returns the written paths
    (for VTK: the ``.pvd`` first, then the grains' frames, then the container's)."""
    path = os.fspath(path)
    if fmt not in ("xyz", "vtk"):
        raise OutputFileError(f"unknown export format {fmt!r}; choose xyz or vtk")
    stem = os.path.splitext(path)[0]
    with open_output(path) as h5:
        s = load_snapshots(h5, every=every, what=f"export --format {fmt}")
    if fmt == "xyz":
        return [write_xyz(s, out or stem + ".xyz")]
    pvd, files = write_vtk(s, out or stem + ".pvd")
    return [pvd] + files

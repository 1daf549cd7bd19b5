"""Figures and trajectory export from real output files: `jaxdamp plot`, `jaxdamp export`."""

import json
import math
import os
import shutil
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest
from matplotlib import image as mpimg

from jaxdamp import cli, figures
from jaxdamp.cases import presets
from jaxdamp.config import apply_overrides, from_json
from jaxdamp.studies.runner import run
from jaxdamp.studies.sweep import sweep

RUN = ["grains.0.count=30", "numerics.duration=0.1", "numerics.chunk=0.02",
       "numerics.settle_time=0.1"]
#: the same grains in a cylinder of the box's base area (the README's command line)
RC = 0.0207
CYLINDER = ["container.shape=cylinder", f"container.radius={RC}", "container.Lz=0.1225"]
SWEEP = ["grains.0.count=20", "numerics.duration=0.04", "numerics.chunk=0.02",
         "numerics.settle_time=0.05"]


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("vis") / "run.h5"
    run(apply_overrides(presets.get("sanchez2012-optimal"), RUN), out=str(path), progress=False,
        echo=None)
    return path


@pytest.fixture(scope="module")
def cylinder_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("vis") / "cylinder.h5"
    run(apply_overrides(presets.get("sanchez2012-optimal"), RUN + CYLINDER), out=str(path),
        progress=False, echo=None)
    return path


@pytest.fixture(scope="module")
def sweep_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("vis") / "sweep.h5"
    sweep(apply_overrides(presets.get("sanchez2012-optimal"), SWEEP),
          {"frequency": [12.0, 15.0, 18.0]}, out=str(path), progress=False, echo=None)
    return path


def _png_size(kind):
    w, h = figures.FIGSIZE[kind]
    return round(h * figures.DPI), round(w * figures.DPI)


@pytest.mark.parametrize("kind", ["band", "energy", "snapshot", "poincare", "frf"])
def test_every_plot_kind_writes_a_png_of_the_expected_size(kind, run_file, sweep_file, tmp_path,
                                                             capsys):
    src = sweep_file if kind == "frf" else run_file
    out = tmp_path / f"{kind}.png"
    assert cli.main(["plot", str(src), "--kind", kind, "--out", str(out)]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    img = mpimg.imread(out)
    assert img.shape[:2] == _png_size(kind)
    assert out.stat().st_size > 20_000
    # not a blank canvas: many distinct colours
    assert len(np.unique(img.reshape(-1, img.shape[-1]), axis=0)) > 50


def test_plot_default_output_name_and_snapshot_by_height(run_file, tmp_path, capsys):
    src = tmp_path / "copy.h5"
    shutil.copy(run_file, src)
    assert cli.main(["plot", str(src), "--kind", "snapshot", "--frame", "0",
                     "--color", "height"]) == 0
    assert (tmp_path / "copy_snapshot.png").stat().st_size > 20_000


def test_band_figure_draws_the_series_in_the_window(run_file):
    with h5py.File(run_file) as h:
        s = {k: h["series"][k][()] for k in ("t", "z_box", "z_cm", "z_lowest", "z_highest")}
        Lz = json.loads(h.attrs["config"])["box"]["Lz"]
    fig = figures.band_from_file(run_file, t0=0.03, t1=0.07)
    ax = fig.axes[0]
    m = (s["t"] >= 0.03) & (s["t"] <= 0.07)
    lines = {line.get_label(): line for line in ax.get_lines()}
    floor = next(v for k, v in lines.items() if k.startswith("floor"))
    lid = next(v for k, v in lines.items() if k.startswith("lid"))
    cm = next(v for k, v in lines.items() if k.startswith("centre of mass"))
    np.testing.assert_allclose(floor.get_xdata(), s["t"][m])
    np.testing.assert_allclose(floor.get_ydata(), s["z_box"][m] * 1e3)
    np.testing.assert_allclose(lid.get_ydata(), (s["z_box"][m] + Lz) * 1e3)
    np.testing.assert_allclose(cm.get_ydata(), s["z_cm"][m] * 1e3)
    band = ax.collections[0].get_paths()[0].vertices
    lo, hi = s["z_lowest"][m].min() * 1e3, s["z_highest"][m].max() * 1e3
    assert band[:, 1].min() == pytest.approx(lo) and band[:, 1].max() == pytest.approx(hi)
    # the default window is the last BAND_PERIODS drive periods (here: the whole short run)
    fig = figures.band_from_file(run_file)
    x = fig.axes[0].get_lines()[0].get_xdata()
    f = 15.16
    assert x[0] >= max(s["t"][0], s["t"][-1] - figures.BAND_PERIODS / f) - 1e-12
    assert x[-1] == s["t"][-1]


def test_poincare_points_are_the_series_once_per_period(run_file):
    with h5py.File(run_file) as h:
        t, z, v = (h["series"][k][()] for k in ("t", "z_cm", "vz_cm"))
    f = 15.16
    fig = figures.poincare_from_file(run_file)
    pts = fig.axes[0].collections[0].get_offsets()
    tk = np.arange(math.ceil(t[0] * f), math.floor(t[-1] * f) + 1) / f
    assert len(pts) == len(tk) >= 1
    # against linear interpolation of the 4 kHz samples (the section uses a cubic spline)
    np.testing.assert_allclose(pts[:, 0], np.interp(tk, t, z) * 1e3, atol=0.05)
    np.testing.assert_allclose(pts[:, 1], np.interp(tk, t, v), atol=0.05)


def _assert_labelled(fig):
    """The project rule: every drawn axis has a label with a unit in brackets, or says what it
    counts or is a ratio of."""
    for ax in fig.axes:
        if not ax.axison:
            continue
        if getattr(ax, "_colorbar", None) is not None:  # a colour bar: its long axis
            assert "[" in ax.get_ylabel(), ax.get_ylabel()
            continue
        # a shared x axis is labelled once, on the bottom panel
        xlabel = next((a.get_xlabel() for a in ax.get_shared_x_axes().get_siblings(ax)
                       if a.get_xlabel()), "")
        labels = [xlabel, ax.get_ylabel()] + ([ax.get_zlabel()] if ax.name == "3d" else [])
        for lab in labels:
            assert lab and ("[" in lab or "ratio" in lab or "grains" in lab or "phase" in lab), \
                (ax.get_title(), labels)


def test_every_figure_has_labelled_axes(run_file, sweep_file):
    with h5py.File(run_file) as h:
        r, ts = h["snapshots/r"][()], h["snapshots/t"][()]
        zb = np.interp(ts, h["series/t"][()], h["series/z_box"][()])
        radius, species = h["grains/radius"][()], h["grains/species"][()]
        box = from_json(h.attrs["config"])  # the run's configuration: its container is drawn
    rows = [("bed", [(f"t = {ts[k]:.3f} s", r[k], zb[k]) for k in (0, 2, 4)], radius, species,
             box), ("again", [("last", r[-1], zb[-1])], radius, species, box)]
    for fig in (figures.band_from_file(run_file), figures.energy_from_file(run_file),
                figures.frf_from_file(sweep_file), figures.poincare_from_file(run_file),
                figures.snapshot_from_file(run_file, 0, "height"),
                figures.snapshot_from_file(run_file), figures.snapshot_grid_figure(rows, "test")):
        _assert_labelled(fig)


def test_snapshot_panels_share_one_drawing_routine(run_file):
    """The side-view grid and the 3-D figure draw the same grains to scale: circles of radius
    r in the side view, the same colours per species in both."""
    from matplotlib.collections import PatchCollection

    with h5py.File(run_file) as h:
        r = h["snapshots/r"][-1]
        radius, species = h["grains/radius"][()], h["grains/species"][()]
        box = from_json(h.attrs["config"])  # the run's configuration: its container is drawn
    fig = figures.figure((3, 3))
    ax = fig.subplots()
    figures.draw_snapshot(ax, r, radius, species, box, 0.0)
    pc = next(c for c in ax.collections if isinstance(c, PatchCollection))
    assert len(pc.get_paths()) == len(radius)
    ext = pc.get_paths()[0].get_extents()  # the first (largest) circle, in mm
    assert len(ax.get_legend().get_texts()) == len(np.unique(species))
    fig3 = figures.snapshot_figure(r, radius, species, box)
    sc = fig3.axes[0].collections[-1]
    np.testing.assert_allclose(sc.get_facecolors()[0][:3], pc.get_facecolors()[0][:3])
    assert ext.width == pytest.approx(2 * radius.max() * 1e3, rel=1e-6)


def _read_xyz(path):
    frames = []
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        n = int(lines[i])
        head = lines[i + 1]
        rows = [ln.split() for ln in lines[i + 2:i + 2 + n]]
        assert all(len(r) == 9 for r in rows)
        frames.append((head, [r[0] for r in rows], np.array([r[1:] for r in rows], float)))
        i += 2 + n
    return frames


def _header_value(head, key):
    rest = head.split(key + "=", 1)[1]
    return rest[1:].split('"', 1)[0] if rest.startswith('"') else rest.split()[0]


def test_export_xyz_one_frame_per_snapshot(run_file, tmp_path, capsys):
    out = tmp_path / "traj.xyz"
    assert cli.main(["export", str(run_file), "--format", "xyz", "--out", str(out)]) == 0
    with h5py.File(run_file) as h:
        ts, r, q = h["snapshots/t"][()], h["snapshots/r"][()], h["snapshots/q"][()]
        radius = h["grains/radius"][()]
        zb = np.interp(ts, h["series/t"][()], h["series/z_box"][()])
        box = json.loads(h.attrs["config"])["box"]
    frames = _read_xyz(out)
    assert len(frames) == len(ts) == 5
    for k, (head, species, cols) in enumerate(frames):
        assert cols.shape == (r.shape[1], 8)
        assert "Properties=species:S:1:pos:R:3:radius:R:1:orientation:R:4" in head
        assert float(_header_value(head, "Time")) == pytest.approx(ts[k], abs=1e-9)
        lat = np.array(_header_value(head, "Lattice").split(), float).reshape(3, 3)
        np.testing.assert_allclose(np.diag(lat), [box["Lx"], box["Ly"], box["Lz"]])
        origin = np.array(_header_value(head, "Origin").split(), float)
        np.testing.assert_allclose(origin, [0, 0, zb[k]], atol=1e-9)
        assert set(species) == {"steel"}
        np.testing.assert_allclose(cols[:, :3], r[k], atol=1e-9, rtol=0)
        np.testing.assert_allclose(cols[:, 3], radius, atol=1e-12)
        np.testing.assert_allclose(cols[:, 4:], q[k][:, [1, 2, 3, 0]], atol=1e-9)
    # --every 2: frames 0, 2, 4
    out2 = tmp_path / "every2.xyz"
    assert cli.main(["export", str(run_file), "--format", "xyz", "--out", str(out2),
                     "--every", "2"]) == 0
    frames2 = _read_xyz(out2)
    assert len(frames2) == 3
    np.testing.assert_allclose(frames2[1][2][:, :3], r[2], atol=1e-9, rtol=0)


def _read_vtk(path):
    """Minimal reader of the legacy-VTK polydata we write: points, vertices, point arrays."""
    tok = open(path).read().split("\n")
    assert tok[0].startswith("# vtk DataFile") and tok[2] == "ASCII"
    assert tok[3] == "DATASET POLYDATA"
    words = " ".join(tok[4:]).split()
    out, i = {"field": {}, "point": {}}, 0

    def take(n, conv=float):
        nonlocal i
        vals = [conv(w) for w in words[i:i + n]]
        i += n
        return np.array(vals)

    section = "field"
    while i < len(words):
        w = words[i]
        if w == "FIELD":
            n_arr = int(words[i + 2])
            i += 3
            for _ in range(n_arr):
                name, ncomp, ntup = words[i], int(words[i + 1]), int(words[i + 2])
                i += 4
                out[section][name] = take(ncomp * ntup).reshape(ntup, ncomp).squeeze()
        elif w == "POINTS":
            n = int(words[i + 1])
            i += 3
            out["points"] = take(3 * n).reshape(n, 3)
        elif w == "VERTICES":
            n, size = int(words[i + 1]), int(words[i + 2])
            i += 3
            cells = take(size, int).reshape(n, 2)
            assert (cells[:, 0] == 1).all()
            out["vertices"] = cells[:, 1]
        elif w == "LINES":
            n, size = int(words[i + 1]), int(words[i + 2])
            i += 3
            flat, out["lines"] = take(size, int), []
            for _ in range(n):
                out["lines"].append(flat[1:1 + flat[0]])
                flat = flat[1 + flat[0]:]
            assert len(flat) == 0
        elif w == "POINT_DATA":
            section = "point"
            i += 2
        elif w == "SCALARS":
            name, i = words[i + 1], i + 6  # SCALARS name type 1 LOOKUP_TABLE default
            out["point"][name] = take(len(out["points"]))
        else:
            raise AssertionError(f"unexpected token {w!r} in {path}")
    return out


def test_export_vtk_frames_and_pvd(run_file, tmp_path, capsys):
    pvd = tmp_path / "vtk" / "grains.pvd"
    assert cli.main(["export", str(run_file), "--format", "vtk", "--out", str(pvd)]) == 0
    assert "indexing 5 frames of the grains and of the container" in capsys.readouterr().out
    with h5py.File(run_file) as h:
        ts, r, q = h["snapshots/t"][()], h["snapshots/r"][()], h["snapshots/q"][()]
        radius, species = h["grains/radius"][()], h["grains/species"][()]
        zb = np.interp(ts, h["series/t"][()], h["series/z_box"][()])
        box = json.loads(h.attrs["config"])["box"]
    N = r.shape[1]
    entries = ET.parse(pvd).getroot().find("Collection").findall("DataSet")
    grains = [e for e in entries if e.get("part") == "0"]
    walls = [e for e in entries if e.get("part") == "1"]
    assert len(grains) == len(walls) == len(ts) and len(entries) == 2 * len(ts)
    for k, e in enumerate(grains):
        assert float(e.get("timestep")) == pytest.approx(ts[k], abs=1e-9)
        d = _read_vtk(pvd.parent / e.get("file"))
        assert d["points"].shape == (N, 3)
        np.testing.assert_array_equal(d["vertices"], np.arange(N))
        np.testing.assert_allclose(d["points"], r[k], atol=1e-9, rtol=0)
        np.testing.assert_allclose(d["point"]["radius"], radius, atol=1e-12)
        np.testing.assert_array_equal(d["point"]["species"], species)
        np.testing.assert_allclose(d["point"]["orientation"], q[k], atol=1e-9)
        assert float(d["field"]["TIME"]) == pytest.approx(ts[k], abs=1e-9)
    for k, e in enumerate(walls):  # the box's 12 edges, its floor at z_box
        assert float(e.get("timestep")) == pytest.approx(ts[k], abs=1e-9)
        d = _read_vtk(pvd.parent / e.get("file"))
        assert len(d["lines"]) == 12 and all(len(c) == 2 for c in d["lines"])
        ends = np.array([d["points"][c] for c in d["lines"]])  # (12, 2, 3)
        lengths = np.sort(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=1))
        np.testing.assert_allclose(lengths, [box["Lx"]] * 4 + [box["Ly"]] * 4 + [box["Lz"]] * 4,
                                   atol=1e-11)  # 12 digits written
        lo, hi = d["points"].min(0), d["points"].max(0)
        np.testing.assert_allclose(lo, [0, 0, zb[k]], atol=1e-11)
        np.testing.assert_allclose(hi, [box["Lx"], box["Ly"], zb[k] + box["Lz"]], atol=1e-11)
        assert float(d["field"]["z_box"]) == pytest.approx(zb[k], abs=1e-11)
    for name, part in (("grains", grains), ("grains_container", walls)):
        series = json.loads((tmp_path / "vtk" / f"{name}.vtk.series").read_text())
        assert [f["name"] for f in series["files"]] == [e.get("file") for e in part]
        np.testing.assert_allclose([f["time"] for f in series["files"]], ts, atol=1e-9)
    assert sorted(os.listdir(pvd.parent)) == sorted(
        [e.get("file") for e in entries]
        + ["grains.pvd", "grains.vtk.series", "grains_container.vtk.series"])


def test_gif_has_one_frame_per_exported_snapshot(run_file, tmp_path, capsys):
    from PIL import Image

    out = tmp_path / "grains.gif"
    assert cli.main(["export", str(run_file), "--format", "gif", "--out", str(out),
                     "--every", "2"]) == 0
    with Image.open(out) as im:
        assert im.n_frames == 3
        assert im.size == (round(figures.FIGSIZE["animation"][0] * 80),
                           round(figures.FIGSIZE["animation"][1] * 80))
    mp4 = tmp_path / "grains.mp4"
    rc = cli.main(["export", str(run_file), "--format", "mp4", "--out", str(mp4)])
    if shutil.which("ffmpeg"):
        assert rc == 0 and mp4.stat().st_size > 1000
    else:
        assert rc == 2 and "MP4 needs ffmpeg on PATH" in capsys.readouterr().err


def _error(capsys, argv):
    assert cli.main(argv) == 2
    return capsys.readouterr().err


def test_wrong_file_kinds_and_missing_parts_are_named(run_file, sweep_file, tmp_path, capsys):
    png = str(tmp_path / "x.png")
    err = _error(capsys, ["plot", str(run_file), "--kind", "frf", "--out", png])
    assert str(run_file) in err and "needs a sweep file" in err and "this is a run file" in err
    for kind in ("band", "energy", "snapshot", "poincare"):
        err = _error(capsys, ["plot", str(sweep_file), "--kind", kind, "--out", png])
        assert str(sweep_file) in err and "needs a run file" in err and "sweep file" in err
    err = _error(capsys, ["export", str(sweep_file), "--format", "xyz"])
    assert str(sweep_file) in err and "export --format xyz needs a run file" in err
    err = _error(capsys, ["plot", str(run_file), "--kind", "snapshot", "--frame", "9", "--out",
                          png])
    assert "frame 9 out of range" in err and "holds 5 snapshots" in err
    err = _error(capsys, ["plot", str(run_file), "--kind", "band", "--t0", "5", "--t1", "6",
                          "--out", png])
    assert "fewer than 2 samples in t = 5 … 6 s" in err
    err = _error(capsys, ["plot", str(tmp_path / "nope.h5"), "--kind", "band"])
    assert "nope.h5: no such file" in err
    text = tmp_path / "notes.h5"
    text.write_text("not hdf5")
    assert "not an HDF5 file" in _error(capsys, ["plot", str(text), "--kind", "energy"])
    # a run file without snapshots (written with snapshots=False, or cut short)
    bare = tmp_path / "bare.h5"
    shutil.copy(run_file, bare)
    with h5py.File(bare, "a") as h:
        del h["snapshots"]
        del h["series/force_box"]
    err = _error(capsys, ["export", str(bare), "--format", "vtk"])
    assert str(bare) in err and "/snapshots/t" in err and "lacks or holds empty" in err
    err = _error(capsys, ["plot", str(bare), "--kind", "band", "--out", png])
    assert "/series/force_box" in err
    assert not os.path.exists(png)


# -- the view from above, side and top side by side; a cylinder's export --------------------
def _circles(ax):
    """Centres (n, 2) and radii (n,) [mm] of the grain circles a plain panel drew."""
    from matplotlib.collections import PatchCollection

    pc = next(c for c in ax.collections if isinstance(c, PatchCollection))
    ext = [p.get_extents() for p in pc.get_paths()]
    return (np.array([[(e.x0 + e.x1) / 2, (e.y0 + e.y1) / 2] for e in ext]),
            np.array([e.width / 2 for e in ext]), pc)


def _inside_outline(centres, radii, segments, sagitta):
    """Whether every circle lies inside the convex polygon the ``segments`` (m, 2, 2) draw, up
    to ``sagitta`` (how far a polygon drawn through points of a curved wall lies inside it)
    plus 1 µm [mm]: the centre inside, at least its radius from every edge."""
    from matplotlib.path import Path
    from scipy.spatial import ConvexHull

    pts = segments.reshape(-1, 2)
    hull = Path(pts[ConvexHull(pts).vertices])
    a, b = segments[:, 0][None], segments[:, 1][None]  # (1, m, 2)
    p = centres[:, None]  # (n, 1, 2)
    u = np.clip(np.sum((p - a) * (b - a), -1) / np.sum((b - a) ** 2, -1), 0, 1)
    dist = np.linalg.norm(p - (a + u[..., None] * (b - a)), axis=-1).min(1)
    return hull.contains_points(centres).all() and (dist >= radii - sagitta - 1e-3).all()


@pytest.mark.parametrize("bed", ["box", "cylinder"])
def test_top_view_draws_the_grains_inside_the_section(bed, run_file, cylinder_file, tmp_path,
                                                     capsys):
    """``jaxdamp plot --kind snapshot --view top`` writes the PNG; the panel's circles are the
    grains (x, y in mm, their radii) and lie inside the drawn section: the box's rectangle, or
    the cylinder's circle of radius R_c around (R_c, R_c) (72 chords: inside it by its sagitta
    R_c (1 − cos 2.5°) = 0.020 mm at most)."""
    src = run_file if bed == "box" else cylinder_file
    out = tmp_path / "top.png"
    assert cli.main(["plot", str(src), "--kind", "snapshot", "--view", "top", "--out",
                     str(out)]) == 0
    img = mpimg.imread(out)
    assert img.shape[:2] == _png_size("snapshot") and out.stat().st_size > 20_000
    with h5py.File(src) as h:
        r, radius = h["snapshots/r"][-1], h["grains/radius"][()]
        cfg = json.loads(h.attrs["config"])
    fig = figures.snapshot_from_file(src, view="top")
    _assert_labelled(fig)
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x [mm]" and ax.get_ylabel().startswith("y [mm]")
    centres, radii, _ = _circles(ax)
    order = np.lexsort(r[:, :2].T[::-1])
    drawn = np.lexsort(centres.T[::-1])
    np.testing.assert_allclose(centres[drawn], r[order, :2] * 1e3, atol=1e-9)
    np.testing.assert_allclose(radii[drawn], radius[order] * 1e3, rtol=1e-9)
    segments = np.concatenate([np.stack([np.column_stack(line.get_data())[:-1],
                                         np.column_stack(line.get_data())[1:]], 1)
                               for line in ax.get_lines()])
    pts = segments.reshape(-1, 2)
    if bed == "box":
        Lx, Ly = cfg["box"]["Lx"] * 1e3, cfg["box"]["Ly"] * 1e3
        assert len(ax.get_lines()) == 4  # the floor's 4 edges; the lid's and the posts left out
        np.testing.assert_allclose([pts.min(0), pts.max(0)], [[0, 0], [Lx, Ly]], atol=1e-12)
        sagitta = 0.0
    else:
        R = RC * 1e3
        assert len(ax.get_lines()) == 1  # the ring, once
        np.testing.assert_allclose(np.hypot(*(pts - R).T), R, rtol=1e-12)
        sagitta = R * (1 - np.cos(np.pi / 72))
        assert 0.019 < sagitta < 0.02
    assert _inside_outline(centres, radii, segments, sagitta)
    # the check can fail: the grains moved by a radius towards a wall are not inside
    assert not _inside_outline(centres + [radii.max(), 0.0], radii, segments, sagitta)


def test_side_and_top_views_side_by_side(cylinder_file, tmp_path):
    """``view="side,top"``: two panels of the same grains, the side view (x, z − z_box) and the
    top view (x, y), same colours, one colour bar when coloured by height; three views make the
    figure half as wide again; unknown views and views on the wrong axes are refused."""
    from jaxdamp.io.export import OutputFileError

    with h5py.File(cylinder_file) as h:
        r, radius, species = h["snapshots/r"][-1], h["grains/radius"][()], h["grains/species"][()]
        zb = float(np.interp(h["snapshots/t"][-1], h["series/t"][()], h["series/z_box"][()]))
        cfg = from_json(h.attrs["config"])
    fig = figures.snapshot_figure(r, radius, species, cfg, zb, view="side,top", color="height")
    _assert_labelled(fig)
    side, top, bar = fig.axes
    assert bar._colorbar is not None
    assert side.get_title() == "side view (x–z)" and top.get_title() == "top view (x–y)"
    for ax, (i, j), dz in ((side, (0, 2), zb), (top, (0, 1), 0.0)):
        centres, radii, pc = _circles(ax)
        assert len(radii) == len(radius)
        want = (r[:, [i, j]] - [0.0, dz]) * 1e3
        np.testing.assert_allclose(np.sort(centres, 0), np.sort(want, 0), atol=1e-9)
    faces = {ax: _circles(ax)[2].get_facecolors()[:, :3] for ax in (side, top)}
    np.testing.assert_allclose(np.sort(faces[side], 0), np.sort(faces[top], 0), atol=1e-12)
    out = figures.save(fig, tmp_path / "st.png")
    assert mpimg.imread(out).shape[:2] == _png_size("snapshot")
    fig3 = figures.snapshot_figure(r, radius, species, cfg, zb, view=("3d", "side", "top"))
    assert [ax.name for ax in fig3.axes] == ["3d", "rectilinear", "rectilinear"]
    w, h = figures.FIGSIZE["snapshot"]
    np.testing.assert_allclose(fig3.get_size_inches(), [1.5 * w, h])
    for bad in ("front", "side,side", ""):
        with pytest.raises(OutputFileError, match="choose 3d, side or top"):
            figures.snapshot_figure(r, radius, species, cfg, zb, view=bad)
    ax = figures.figure((3, 3)).subplots()
    with pytest.raises(OutputFileError, match="needs a projection='3d' axes"):
        figures.draw_snapshot(ax, r, radius, species, cfg, zb, view="3d")


def test_plot_view_option_is_checked(run_file, tmp_path, capsys):
    png = tmp_path / "v.png"
    err = _error(capsys, ["plot", str(run_file), "--kind", "snapshot", "--view", "front",
                          "--out", str(png)])
    assert "view 'front': choose 3d, side or top" in err
    err = _error(capsys, ["plot", str(run_file), "--kind", "band", "--view", "top", "--out",
                          str(png)])
    assert "--view applies to --kind snapshot only, not band" in err
    assert not png.exists()
    assert cli.main(["plot", str(run_file), "--kind", "snapshot", "--view", "side,top",
                     "--color", "height", "--out", str(png)]) == 0
    assert mpimg.imread(png).shape[:2] == _png_size("snapshot")


def test_export_of_a_cylinder_run(cylinder_file, tmp_path, capsys):
    """XYZ: the cell is the cylinder's bounding box, 2 R_c × 2 R_c × Lz from (0, 0, z_box),
    and every grain lies inside the cylinder; VTK: the container's frames hold its two rings
    (radius R_c around the axis at (R_c, R_c), at z_box and z_box + Lz) and four posts."""
    xyz, pvd = tmp_path / "c.xyz", tmp_path / "vtk" / "c.pvd"
    assert cli.main(["export", str(cylinder_file), "--format", "xyz", "--out", str(xyz)]) == 0
    assert cli.main(["export", str(cylinder_file), "--format", "vtk", "--out", str(pvd)]) == 0
    with h5py.File(cylinder_file) as h:
        ts, r, radius = h["snapshots/t"][()], h["snapshots/r"][()], h["grains/radius"][()]
        zb = np.interp(ts, h["series/t"][()], h["series/z_box"][()])
        Lz = json.loads(h.attrs["config"])["container"]["Lz"]
    frames = _read_xyz(xyz)
    assert len(frames) == len(ts)
    for k, (head, _, cols) in enumerate(frames):
        lat = np.array(_header_value(head, "Lattice").split(), float).reshape(3, 3)
        np.testing.assert_allclose(lat, np.diag([2 * RC, 2 * RC, Lz]), atol=1e-12)
        origin = np.array(_header_value(head, "Origin").split(), float)
        np.testing.assert_allclose(origin, [0, 0, zb[k]], atol=1e-11)
        assert _header_value(head, "container") == "cylinder"
        np.testing.assert_allclose(cols[:, :3], r[k], atol=1e-9, rtol=0)
        np.testing.assert_allclose(cols[:, 3], radius, atol=1e-12)
        rho = np.hypot(cols[:, 0] - RC, cols[:, 1] - RC)
        assert (rho + cols[:, 3] <= RC + 1e-9).all()  # inside the wall (no overlap here)
        assert (cols[:, 2] - cols[:, 3] >= origin[2] - 1e-9).all()
        assert (cols[:, 2] + cols[:, 3] <= origin[2] + Lz).all()
    walls = [e for e in ET.parse(pvd).getroot().find("Collection").findall("DataSet")
             if e.get("part") == "1"]
    assert len(walls) == len(ts)
    for k, e in enumerate(walls):
        d = _read_vtk(pvd.parent / e.get("file"))
        rings = [c for c in d["lines"] if len(c) > 2]
        posts = [c for c in d["lines"] if len(c) == 2]
        assert len(rings) == 2 and len(posts) == 4
        for c, z in zip(rings, (zb[k], zb[k] + Lz)):
            p = d["points"][c]
            np.testing.assert_allclose(np.hypot(p[:, 0] - RC, p[:, 1] - RC), RC, atol=1e-11)
            np.testing.assert_allclose(p[:, 2], z, atol=1e-11)
            np.testing.assert_allclose(p[0], p[-1], atol=1e-11)  # closed
        for c in posts:
            p = d["points"][c]
            np.testing.assert_allclose(np.hypot(p[:, 0] - RC, p[:, 1] - RC), RC, atol=1e-11)
            np.testing.assert_allclose(p[:, 2], [zb[k], zb[k] + Lz], atol=1e-11)


def test_a_box_driven_along_x_is_drawn_and_exported_where_it_is(tmp_path):
    """With the drive along x (``direction = (1, 0, 0)``) the box is displaced by z_box along
    x: the XYZ cell's origin is (z_box, 0, 0), and the top view draws the grains at their
    box-frame positions r − e z_box, inside the section (built by hand: no run needed)."""
    import dataclasses

    from jaxdamp.io.export import Snapshots, write_xyz

    cfg = dataclasses.replace(presets.get("sanchez2012-optimal"), direction=(1.0, 0.0, 0.0))
    L, zb = cfg.box.Lx, 0.004
    r_box = np.array([[0.002, 0.002, 0.002], [L - 0.002, L / 2, 0.01]])  # near x = 0, x = Lx
    lab = r_box + [zb, 0.0, 0.0]
    s = Snapshots(t=np.array([0.1]), r=lab[None], q=np.tile([1.0, 0, 0, 0], (1, 2, 1)),
                  z_box=np.array([zb]), radius=np.array([0.0015, 0.0015]),
                  species=np.array([0, 0]), species_names=["steel"], config=cfg,
                  frames=np.array([0]), path="made.h5")
    head = _read_xyz(write_xyz(s, tmp_path / "x.xyz"))[0][0]
    np.testing.assert_allclose(np.array(_header_value(head, "Origin").split(), float),
                               [zb, 0, 0], atol=1e-15)
    fig = figures.snapshot_figure(s.r[0], s.radius, s.species, cfg, zb, view="side,top")
    side, top = fig.axes
    np.testing.assert_allclose(np.sort(_circles(top)[0], 0), np.sort(r_box[:, :2] * 1e3, 0),
                               atol=1e-9)
    np.testing.assert_allclose(np.sort(_circles(side)[0], 0),
                               np.sort(r_box[:, [0, 2]] * 1e3, 0), atol=1e-9)

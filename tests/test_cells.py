"""A damper of several identical cells on one primary degree of freedom (``Config.cells``).

Each cell is its own container and bed, the cells side by side in the box frame
(:func:`jaxdamp.physics.model.cell_origins`); the sum of the cells' wall forces acts on the
primary. Checked here: the input is refused in one line where it is wrong; a mass ratio is the
whole damper's; no neighbour list of any engine ever holds a pair across cells; identical cells
move identically and together push exactly ``k`` times one cell's force; the engines agree on a
two-cell bed; the energy balance closes and the per-cell records add up to the totals.
"""

import dataclasses

import numpy as np
import pytest
from helpers import STEEL, mixture, mixture_bed, start

from jaxdamp.cases import presets
from jaxdamp.config import (
    Box,
    Config,
    ConfigError,
    Drive,
    Numerics,
    Primary,
    Species,
    Structure,
    apply_overrides,
)
from jaxdamp.engine import native, neighbors
from jaxdamp.engine.packing import fcc_lattice, poured
from jaxdamp.engine.simulate import chunk_fn
from jaxdamp.physics.energy import granular_loss
from jaxdamp.physics.model import build, cell_origins, grain_cell, grain_radii
from jaxdamp.validation import validate

THESIS = presets.get("sanchez2012-optimal")


@pytest.mark.parametrize("value, words", [
    (0, "cells = 0: must be an integer ≥ 1"),
    (2.5, "cells = 2.5: must be an integer ≥ 1"),
    (True, "cells = True: must be an integer ≥ 1"),
])
def test_bad_cell_counts_are_refused_in_one_line(value, words):
    with pytest.raises(ConfigError) as e:
        validate(dataclasses.replace(THESIS, cells=value))
    assert str(e.value).startswith(words) and "\n" not in str(e.value)


@pytest.mark.parametrize("attach, words", [
    ([0, 1, 1], "structure.attach = [0, 1, 1]: a list gives the degree of freedom (0..1) of "
                "each of the 2 cell(s)"),
    ([0, 2], "structure.attach = [0, 2]: a list gives the degree of freedom (0..1)"),
    (2, "structure.attach = 2: must be a degree of freedom 0..1"),
])
def test_cells_on_a_structure_name_their_degrees_of_freedom(attach, words):
    """On a multi-DOF structure each cell sits on the degree of freedom ``structure.attach``
    names (one number for all, or a list of one per cell); a list of the wrong length or a
    degree of freedom out of range is refused in one line."""
    cfg = apply_overrides(mixture("primary", "arithmetic"), {
        "cells": 2, "structure.M": [[0.5, 0.0], [0.0, 1.0]],
        "structure.K": [[2e4, -1e4], [-1e4, 2e4]]})
    validate(cfg)
    validate(apply_overrides(cfg, {"structure.attach": [1, 0]}))
    with pytest.raises(ConfigError) as e:
        validate(apply_overrides(cfg, {"structure.attach": attach}))
    msg = str(e.value)
    assert msg.startswith(words) and "\n" not in msg


def _primary(cells, structure=None, n=10):
    """A light 1-DOF primary (50 g, 32 Hz) carrying ``cells`` cells of ``n`` equal steel grains
    (3 g a cell: they move it), friction and damping on; or the structure ``structure``."""
    steel = dataclasses.replace(STEEL, mu=0.3, gamma_n=40.0, gamma_s=120.0)
    return Config(system="primary", frequency=30.0,
                  grains=(Species(count=n, radius=2e-3, material=steel),),
                  box=Box(0.02, 0.02, 0.03), primary=Primary(M=0.05, K=2e3, C=0.3, U=0.004),
                  gravity=9.8, structure=structure, cells=cells, name="cells",
                  numerics=Numerics(duration=0.01, chunk=0.005, record_dt=1e-4, v_impact=2.0))


def _two_dofs(coupling=0.0, attach=(0, 1)):
    """The 1-DOF primary of :func:`_primary` twice, coupled by a spring ``coupling`` [N/m]."""
    k = 2e3
    return Structure(M=((0.05, 0.0), (0.0, 0.05)), K=((k + coupling, -coupling),
                                                      (-coupling, k + coupling)),
                     C=((0.3, 0.0), (0.0, 0.3)), attach=attach)


def _bed_in_cells(cfg, r, v, z, zd):
    """``start`` of ``cfg`` with the bed ``r``, ``v`` copied into each of its cells."""
    model, params = build(cfg)
    n = len(r)
    src = np.tile(np.arange(n), cfg.cells)
    return start(cfg, r[src] + np.c_[np.asarray(params.origin), np.zeros(len(src))], v[src],
                 z=z, zd=zd)


@pytest.mark.parametrize("engine", [pytest.param("jax", marks=pytest.mark.long), "native",
                                    pytest.param("fused", marks=pytest.mark.long)])
def test_cells_on_two_uncoupled_degrees_of_freedom_are_two_dampers(engine):
    """Two cells on the two degrees of freedom of an uncoupled structure, each the 1-DOF
    primary of a one-cell damper, started apart (the second moving at 0.1 m/s): each degree of
    freedom and each cell's bed move as the one-cell damper started like it does, each cell's
    loss is that damper's, and the cells' forces load their own degrees of freedom."""
    r, v, _ = mixture_bed(10, spacing=0.0045)
    r[:, 2] += 0.004
    steps = (3, 100) if engine != "fused" else (2, 25)
    one = {}
    for zd in (0.0, 0.1):
        model, pb, st, nbrs = start(_primary(1), r, v, z=0.0, zd=zd)
        s, _, rec = chunk_fn(model, *steps, engine=engine)(st, nbrs, pb)
        one[zd] = (s, {k: np.asarray(x)[0] for k, x in rec.items()})
    cfg = _primary(2, _two_dofs())
    model, pb, st, nbrs = _bed_in_cells(cfg, r, v, [0.0, 0.0], [0.0, 0.1])
    assert model.cell_dofs == (0, 1)
    s, _, rec = chunk_fn(model, *steps, engine=engine)(st, nbrs, pb)
    rec = {k: np.asarray(x)[0] for k, x in rec.items()}
    cell, origin = model.cell_index(), np.asarray(pb.origin)[0]
    (s0, r0), (s1, r1) = one[0.0], one[0.1]
    assert abs(r1["z_box"][-1] - r0["z_box"][-1]) > 1e-7  # the two dampers differ
    assert r0["loss_cell"][-1, 0] > 0 and r1["loss_cell"][-1, 0] != r0["loss_cell"][-1, 0]
    np.testing.assert_allclose(rec["z_box"], r0["z_box"], rtol=1e-9, atol=1e-14)
    np.testing.assert_allclose(rec["y_dofs"][:, 0], r1["z_box"], rtol=1e-9, atol=1e-14)
    for c, (sc, rc) in enumerate(((s0, r0), (s1, r1))):
        got = np.asarray(s.r)[0][cell == c] - np.c_[origin[cell == c], np.zeros(10)]
        np.testing.assert_allclose(got, np.asarray(sc.r)[0], rtol=0, atol=1e-12)
        for key in ("z_cm_cell", "vz_cm_cell", "e_kinetic_cell", "loss_cell"):
            np.testing.assert_allclose(rec[key][:, c], rc[key][:, 0], rtol=1e-9, atol=1e-14,
                                       err_msg=key)
        for key in ("n_floor_cell", "n_lid_cell"):
            np.testing.assert_array_equal(rec[key][:, c], rc[key][:, 0], err_msg=key)
    np.testing.assert_allclose(rec["force_box"], r0["force_box"] + r1["force_box"],
                               rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("engine", ["native", pytest.param("fused", marks=pytest.mark.long)])
def test_cells_on_a_coupled_structure_agree_with_jax(engine):
    """Three cells, two on the second degree of freedom of a coupled two-DOF structure and one
    on the first (the box): the native kernel (and the fused step in its simulator) agree
    with the JAX engine to round-off, and each closes the energy balance to the integrator's
    error (6e-5 of the grains' kinetic energy after 100 steps, as with all cells on the box's
    degree of freedom; it falls 4× at half the time step)."""
    cfg = _primary(3, _two_dofs(coupling=500.0, attach=(1, 0, 1)), n=4)
    r, v, _ = mixture_bed(4, spacing=0.0045)
    r[:, 2] += 0.004
    model, pb, st, nbrs = _bed_in_cells(cfg, r, v, [0.0, 0.0], [0.05, -0.05])
    assert model.cell_dofs == (0, 1, 0)  # the box is cell 0's: degree of freedom 1 first
    steps = (2, 50)
    out = {e: chunk_fn(model, *steps, engine=e)(st, nbrs, pb) for e in ("jax", engine)}
    _agree(out[engine], out["jax"])
    for e, (_, _, rec) in out.items():
        res = np.asarray(rec["balance_residual"])[0]
        assert np.abs(res).max() < 1e-4 * np.asarray(rec["e_kinetic"])[0].max(), e


def test_set_cells_and_a_mass_ratio_split_over_the_cells():
    """``--set cells=4``: the mass ratio is the damper's, each cell holds ``μ/k`` of it; the
    counts are per cell, the damper holds ``k`` times them."""
    one = validate(apply_overrides(THESIS, {"grains.0.mass_ratio": 0.09}))
    four = validate(apply_overrides(THESIS, ["cells=4", "grains.0.mass_ratio=0.09"]))
    m_grain = THESIS.grains[0].material.density * 4 / 3 * np.pi * THESIS.grains[0].radius**3
    assert one.grains[0].count == round(0.09 * THESIS.primary.M / m_grain) == 235
    assert four.cells == 4  # 0.09 M / m = 234.9 grains in all: 58.7 per cell
    assert four.grains[0].count == round(0.09 * THESIS.primary.M / (4 * m_grain)) == 59
    assert four.n_grains == 4 * 59
    model, params = build(four)
    assert model.n == 236 and model.cells == 4 and model.species == (236,)
    assert np.bincount(model.cell_index()).tolist() == [59] * 4


def _worst_case(cfg, model, params):
    """Every cell's lattice, and each cell's grains pressed against the cell's walls that face
    the neighbouring cells (x = R and x = Lx - R): the closest grains across cells can come."""
    r = poured(params, model, cfg, 0)
    radius = np.asarray(params.radius)
    origin = np.asarray(params.origin)
    x0, x1, _, _ = (0.0, cfg.box.Lx, 0.0, cfg.box.Ly)
    first = np.r_[True, np.diff(grain_cell(cfg)) != 0]  # one grain of each cell at its x = 0
    last = np.r_[np.diff(grain_cell(cfg)) != 0, True]   # one at its x = Lx
    r[first, 0] = origin[first, 0] + x0 + radius[first]
    r[last, 0] = origin[last, 0] + x1 - radius[last]
    return r


def test_no_engine_lists_a_pair_across_cells():
    """Three cells of the thesis' box: the JAX engine's all-pairs builder and host lists and
    the native kernel's cell grid (at its widest skin, ``2 R_max`` more than the model's) never
    list a pair of grains of different cells, not even with grains pressed against the facing
    walls; the device kernel lists by the native kernel's criterion (``|r_i − r_j| < R_i + R_j
    + skin``, the same widened skin), so the gap below bounds it too."""
    cfg = validate(apply_overrides(THESIS, ["cells=3", "grains.0.count=40"]))
    model, params = build(cfg)
    cell = model.cell_index()
    r = _worst_case(cfg, model, params)
    radius = np.asarray(params.radius)
    r_max = radius.max()
    # the geometry: across cells, centres are further apart than any engine's listing distance
    across = cell[:, None] != cell[None, :]
    d = np.linalg.norm(r[:, None] - r[None], axis=-1)
    listing = 4.0 * r_max + model.skin + neighbors._MARGIN * model.skin
    assert d[across].min() > 2.0 * listing
    # the JAX engine: its host lists and its traced all-pairs builder (every grain at R_max)
    nb = neighbors.allocate(model, r[None], 1.5)
    for idx in (np.asarray(nb.idx[0]),
                np.asarray(neighbors._build(model, neighbors.capacity(nb), r[None]).idx[0])):
        i, j = np.nonzero(idx < model.n)
        assert len(i) > 100  # neighbours within the cells are listed
        assert (cell[i] == cell[idx[i, j]]).all()
    # the native kernel's cell grid, at its widest skin
    n = model.n
    pi, pj, pc = np.empty(1, np.int64), np.empty(1, np.int64), np.empty((1, 5))
    k, pi, pj, pc = native._pairs(r, 0.0, 0.0, 0.0, 4.0 * r_max + model.skin, pi, pj, pc,
                                  np.empty((n, 3)), radius, np.asarray(params.mass),
                                  model.species_index().astype(np.int64),
                                  np.asarray(params.pair_table), 0)
    assert k > 100 and (cell[pi[:k]] == cell[pj[:k]]).all()


def test_each_cell_is_poured_as_one_cell():
    """The pour repeats the one-cell lattice (same seed) at every cell's corner; one cell is
    today's lattice, and the radii of one cell are the one-cell damper's draws."""
    cfg = validate(apply_overrides(THESIS, ["cells=3", "grains.0.count=40"]))
    one = dataclasses.replace(cfg, cells=1)
    model, params = build(cfg)
    assert np.array_equal(grain_radii(one), grain_radii(cfg)[:40])
    r = poured(params, model, cfg, 5)
    origins = cell_origins(cfg, np.asarray(params.radius))
    assert origins[0].tolist() == [0.0, 0.0] and np.all(np.diff(origins[:, 0]) > 2 * cfg.box.Lx)
    for c in range(3):
        sel = model.cell_index() == c
        want = fcc_lattice(np.asarray(params.radius)[sel], cfg, 5)
        want[:, 0] += origins[c, 0]
        np.testing.assert_array_equal(r[sel], want)
    m1, p1 = build(one)
    assert not np.asarray(p1.origin).any() and not m1.cell_index().any()
    np.testing.assert_array_equal(poured(p1, m1, one, 5),
                                  fcc_lattice(np.asarray(p1.radius), one, 5))


def _driven(cells, n=12):
    """A prescribed box (S2, 8 mm at 25 Hz, gravity) of ``cells`` cells of ``n`` equal steel
    grains each, friction and damping on."""
    steel = dataclasses.replace(STEEL, mu=0.3, gamma_n=40.0, gamma_s=120.0)
    return Config(system="driven", frequency=25.0,
                  grains=(Species(count=n, radius=2e-3, material=steel),),
                  box=Box(0.02, 0.02, 0.03), drive=Drive(0.008), gravity=9.8,
                  numerics=Numerics(duration=0.01, chunk=0.005, record_dt=1e-4, v_impact=2.0),
                  name="cells", cells=cells)


@pytest.mark.parametrize("engine", [pytest.param("jax", marks=pytest.mark.long), "native"])
def test_identical_cells_move_alike_and_push_k_times_one_cell(engine):
    """Three identical cells started from one cell's bed copied into each: every cell moves as
    the one-cell damper does (to round-off: the cells' positions differ by their offsets), each
    cell dissipates what the one-cell damper does (its ``loss_cell``, the granular channels of
    the one-cell run), and the force on the driven box, its input work and every loss are three
    times one cell's."""
    r, v, w = mixture_bed(12, spacing=0.0045)
    r[:, 2] += 0.004
    out = {}
    for k in (1, 3):
        cfg = _driven(k)
        model, params = build(cfg)
        origin = np.asarray(params.origin)
        cell = model.cell_index()
        rk = r[np.tile(np.arange(12), k)] + np.c_[origin, np.zeros(model.n)]
        model, pb, st, nbrs = start(cfg, rk, v[np.tile(np.arange(12), k)],
                                    w[np.tile(np.arange(12), k)])
        s, _, rec = chunk_fn(model, 4, 50, engine=engine)(st, nbrs, pb)
        out[k] = (s, {key: np.asarray(x)[0] for key, x in rec.items()}, cell, origin)
    (s1, r1, _, _), (s3, r3, cell, origin) = out[1], out[3]
    assert np.abs(r1["force_box"]).max() > 0.1 and r1["work"][-1, 4] > 0  # the walls work
    assert r1["work"][-1, 2] > 0  # and the pairs
    a = np.asarray(s1.r)[0]
    b = np.asarray(s3.r)[0] - np.c_[origin, np.zeros(len(cell))]
    for c in range(3):
        np.testing.assert_allclose(b[cell == c], a, rtol=0, atol=1e-12)
        np.testing.assert_allclose(np.asarray(s3.v)[0][cell == c], np.asarray(s1.v)[0],
                                   rtol=1e-9, atol=1e-10)
        for key in ("z_cm_cell", "vz_cm_cell", "e_kinetic_cell", "loss_cell"):
            np.testing.assert_allclose(r3[key][:, c], r1[key][:, 0], rtol=1e-9, atol=1e-12,
                                       err_msg=key)
        for key in ("n_floor_cell", "n_lid_cell"):
            np.testing.assert_array_equal(r3[key][:, c], r1[key][:, 0], err_msg=key)
    np.testing.assert_allclose(r3["force_box"], 3 * r1["force_box"], rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(r3["work"], 3 * r1["work"], rtol=1e-9, atol=1e-15)
    np.testing.assert_array_equal(r3["n_floor"], 3 * r1["n_floor"])
    np.testing.assert_allclose(r3["e_kinetic_cell"].sum(axis=1), r3["e_kinetic"], rtol=1e-12)
    np.testing.assert_allclose(r1["loss_cell"][:, 0], granular_loss(r1["work"]), rtol=1e-12,
                               atol=1e-18)
    assert r1["loss_cell"][-1, 0] > 0


CYLINDER = ["container.shape=cylinder", "container.radius=0.012", "container.Lz=0.02"]


def _two_cells(n=(10, 15), extras=()):
    """The two-species mixture of tests/test_native.py in two cells, each cell its own copy of
    a fast, spinning bed of ``n`` grains (big ones with a 5 % radius spread: the cells differ);
    ``extras``: overrides (another container)."""
    cfg = apply_overrides(dataclasses.replace(mixture("primary", "arithmetic", counts=n),
                                              cells=2), list(extras))
    model, params = build(cfg)
    r, v, w = mixture_bed(sum(n), spacing=0.0042)
    big, small = np.arange(n[0]), np.arange(n[0], sum(n))
    src = np.r_[big, big, small, small]  # species after species, cell after cell
    rk = r[src] + np.c_[np.asarray(params.origin), np.zeros(len(src))]
    return cfg, start(cfg, rk, v[src], w[src])


def _agree(got, ref, rtol=1e-9):
    (sa, _, ra), (sb, _, rb) = ref, got
    for f in ("r", "v", "w", "q", "z", "zd", "work", "work_cell", "e_elastic", "f_box",
              "n_floor", "n_side"):
        a, b = np.asarray(getattr(sa, f)), np.asarray(getattr(sb, f))
        np.testing.assert_allclose(b, a, rtol=rtol,
                                   atol=1e-12 * max(1.0, np.abs(a).max(initial=0.0)), err_msg=f)
    for k in ra:
        a = np.asarray(ra[k])
        np.testing.assert_allclose(np.asarray(rb[k]), a, rtol=10 * rtol,
                                   atol=1e-12 * max(1.0, float(np.abs(a).max(initial=0.0))),
                                   err_msg=k)


@pytest.mark.parametrize("extras", [(), pytest.param(CYLINDER, marks=pytest.mark.long)],
                         ids=["box", "cylinder"])
def test_native_equals_jax_on_two_cells(extras):
    """Two cells of the two-species mixture (friction, rotation, the primary), in boxes and in
    cylinders: the native kernel and the JAX engine agree to round-off after 300 steps,
    per-cell records included; each engine's cells' losses sum to its damper's."""
    _, (model, pb, st, nbrs) = _two_cells(extras=extras)
    out = {e: chunk_fn(model, 3, 100, engine=e)(st, nbrs, pb) for e in ("jax", "native")}
    work = np.asarray(out["jax"][0].work[0])
    assert work[2] > 0 and work[4] > 0  # pair and wall contacts
    ke = np.asarray(out["jax"][2]["e_kinetic_cell"])[0]
    assert np.all(ke[:, 0] != ke[:, 1])  # the cells differ (their radii)
    for e, (_, _, rec) in out.items():
        loss = np.asarray(rec["loss_cell"])[0]
        np.testing.assert_allclose(loss.sum(axis=-1), granular_loss(np.asarray(rec["work"])[0]),
                                   rtol=1e-12, err_msg=e)
        assert np.all(loss[-1] > 0) and loss[-1, 0] != loss[-1, 1], e
    _agree(out["native"], out["jax"])


@pytest.mark.long
def test_fused_equals_jax_on_two_cells():
    """The fused device step, in numba-cuda's CUDA simulator, on a two-cell bed of 12 grains:
    it agrees with the JAX engine to the native kernel's tolerance."""
    from jaxdamp.engine import fused

    if not fused.available()[0]:
        pytest.skip("numba-cuda (the cuda extra) not installed")
    _, (model, pb, st, nbrs) = _two_cells(n=(3, 3))
    out = {e: chunk_fn(model, 2, 50, engine=e)(st, nbrs, pb) for e in ("jax", "fused")}
    _agree(out["fused"], out["jax"])


@pytest.mark.long
@pytest.mark.parametrize("engine", ["jax", "native"])
def test_a_run_of_three_cells_closes_its_energy_balance(engine):
    """The thesis' damper in three cells through the runner (poured, briefly settled, 0.05 s
    at resonance): the balance closes, every cell holds a bed, and the per-cell records add up
    to the whole damper's."""
    from jaxdamp.studies.runner import run

    cfg = apply_overrides(THESIS, ["cells=3", "grains.0.count=30", "box.Lz=0.05",
                                   "numerics.duration=0.05", "numerics.chunk=0.025",
                                   "numerics.settle_time=0.05", f"numerics.engine='{engine}'"])
    res = run(cfg, progress=False, echo=None)
    assert res.summary["balance_error"] < 1e-3
    rec = {k: np.asarray(v) for k, v in res.records.items()}
    np.testing.assert_allclose(rec["e_kinetic_cell"].sum(axis=-1), rec["e_kinetic"],
                               rtol=1e-10)
    np.testing.assert_allclose(rec["z_cm_cell"].mean(axis=-1), rec["z_cm"], rtol=1e-10)
    assert (rec["n_floor_cell"].sum(axis=-1) == rec["n_floor"]).all()
    assert (rec["n_floor_cell"].max(axis=0) > 0).all()  # every cell's bed hits its floor
    np.testing.assert_allclose(rec["loss_cell"].sum(axis=-1), granular_loss(rec["work"]),
                               rtol=1e-10)
    assert (rec["loss_cell"][-1] > 0).all()
    for c in range(3):
        assert res.summary[f"mean_e_kinetic_cell{c}"] > 0
        assert res.summary[f"granular_loss_per_cycle_cell{c}"] > 0
    assert sum(res.summary[f"granular_loss_per_cycle_cell{c}"] for c in range(3)) == (
        pytest.approx(res.summary["granular_loss_per_cycle"], rel=1e-10))


@pytest.mark.long
def test_a_run_of_cells_on_two_degrees_of_freedom_closes_its_energy_balance():
    """The thesis' damper in three cells on a two-DOF chain through the runner (poured,
    settled, each cell's bed moved to its degree of freedom's static position, 0.05 s): the
    balance closes, each cell's bed rests on its own floor at the start, and the cells'
    losses sum to the damper's."""
    from jaxdamp.studies.runner import run

    cfg = apply_overrides(THESIS, [
        "cells=3", "grains.0.count=30", "box.Lz=0.05", "numerics.duration=0.05",
        "numerics.chunk=0.025", "numerics.settle_time=0.05", "numerics.engine='native'",
        "structure.M=[[2.0, 0.0], [0.0, 2.37]]",
        "structure.K=[[43000.0, -21500.0], [-21500.0, 21500.0]]",
        "structure.C=[[15.2, -7.6], [-7.6, 7.6]]", "structure.attach=[1, 0, 0]"])
    res = run(cfg, progress=False, echo=None)
    assert res.summary["balance_error"] < 1e-3
    rec = {k: np.asarray(v) for k, v in res.records.items()}
    assert (rec["n_floor_cell"][0] > 0).all()  # every bed starts on its own floor
    np.testing.assert_allclose(rec["loss_cell"].sum(axis=-1), granular_loss(rec["work"]),
                               rtol=1e-10)
    assert (rec["loss_cell"][-1] > 0).all()
    y, z = rec["y_dofs"][:, 0], rec["z_box"]  # DOF 0 (cells 1, 2) and DOF 1 (cell 0, the box)
    assert np.ptp(y) > 0 and np.ptp(z) > 0 and not np.allclose(y, z)


def test_the_preset_is_its_documented_toml(tmp_path):
    """``sanchez2012-cells`` is the TOML of docs/physics.md §5 over ``sanchez2012-optimal``:
    four cells of 62 grains (248 in all) of the thesis' box section, ``Lz = 0.0932`` m."""
    from jaxdamp.config import load_toml

    f = tmp_path / "cells.toml"
    f.write_text('cells = 4\n[box]\nLx = 0.03675\nLy = 0.03675\nLz = 0.0932\n[[grains]]\n'
                 'count = 62\nradius = 0.003\nname = "steel"\n[grains.material]\nE = 2.03e11\n'
                 'nu = 0.28\ndensity = 8030.0\nmu = 0.3\ngamma_n = 3660.0\ngamma_s = 10980.0\n')
    preset = validate(presets.get("sanchez2012-cells"))
    toml = load_toml(str(f), THESIS)
    assert dataclasses.replace(toml, name=preset.name, notes=preset.notes) == preset
    assert preset.n_grains == 248
    # a mass ratio of 0.095 for the whole damper gives the same cells
    ratio = validate(apply_overrides(presets.get("sanchez2012-cells"),
                                     {"grains.0.count": None, "grains.0.mass_ratio": 0.095}))
    assert ratio.grains[0].count == 62


def test_figures_and_exports_see_every_cell():
    """Each cell's outline is the container's at its corner; the bounding box of the damper
    (figures' limits, the XYZ export's ``Lattice``) runs from the first cell's wall to the
    last one's."""
    from jaxdamp.physics.containers import container
    from jaxdamp.physics.model import cell_outlines, damper_extent

    cfg = validate(apply_overrides(THESIS, ["cells=3", "grains.0.count=40"]))
    radii = grain_radii(cfg)
    origins = cell_origins(cfg, radii)
    one = container(cfg).outline(cfg, 0.01)
    lines = cell_outlines(cfg, radii, 0.01)
    assert len(lines) == 3 * len(one)
    for c in range(3):
        for a, b in zip(one, lines[c * len(one):(c + 1) * len(one)]):
            np.testing.assert_array_equal(b, a + [origins[c, 0], origins[c, 1], 0.0])
    x0, x1, y0, y1 = damper_extent(cfg, radii)
    assert (x0, y0, y1) == (0.0, 0.0, cfg.box.Ly) and x1 == origins[2, 0] + cfg.box.Lx
    assert damper_extent(dataclasses.replace(cfg, cells=1), radii[:40]) == (
        0.0, cfg.box.Lx, 0.0, cfg.box.Ly)


@pytest.mark.long  # the native kernel's spring form (compiled once, cached)
@pytest.mark.parametrize("layout", ["box", "two_dofs"])
def test_native_springs_equal_jax_in_cells(layout):
    """The tangential springs with history in several cells (``tangential_law = "mindlin"``):
    the two-cell mixture in boxes (300 steps), and three cells on the two degrees of freedom
    of a coupled structure (100 steps), whose cells' walls move apart, so that each grain's
    wall springs grow with its own cell's wall: the native kernel and the JAX engine agree to
    round-off, per-cell records and the springs' energy included, with springs loaded,
    slipping and released on pairs and walls."""
    from jaxdamp.physics.model import CH

    if layout == "box":
        _, (model, pb, st, nbrs) = _two_cells(extras=["tangential_law=mindlin"])
        steps = (3, 100)
    else:
        cfg = dataclasses.replace(_primary(3, _two_dofs(coupling=500.0, attach=(1, 0, 1)), n=4),
                                  tangential_law="mindlin")
        r, v, _ = mixture_bed(4, spacing=0.0045)
        r[:, 2] += 0.004
        model, pb, st, nbrs = _bed_in_cells(cfg, r, v, [0.0, 0.0], [0.05, -0.05])
        assert model.cell_dofs == (0, 1, 0)
        steps = (2, 50)
    assert model.springs
    out = {e: chunk_fn(model, *steps, engine=e)(st, nbrs, pb) for e in ("jax", "native")}
    _agree(out["native"], out["jax"])
    (a, _, _), (b, _, _) = out["native"], out["jax"]
    assert float(a.e_spring[0]) == pytest.approx(float(b.e_spring[0]), rel=1e-7, abs=1e-18)
    work = np.asarray(b.work[0])
    assert work[CH["pw_slip"]] > 0 and work[CH["spring_stiffness"]] != 0
    if layout == "box":
        assert work[CH["pp_slip"]] > 0
    scale = float(np.abs(np.asarray(b.spring_wall)).max())
    np.testing.assert_allclose(np.asarray(a.spring_wall), np.asarray(b.spring_wall), rtol=0,
                               atol=1e-9 * scale)
    held_a, held_b = _pair_springs(a), _pair_springs(b)  # the engines keep other row layouts
    assert held_a.keys() == held_b.keys()
    for key, force in held_b.items():
        np.testing.assert_allclose(held_a[key], force, rtol=0, atol=1e-9 * scale, err_msg=key)


def _pair_springs(s):
    """``{(grain, partner): force}`` of the pair springs held in system 0's state."""
    part, force = np.asarray(s.spring_partner[0]), np.asarray(s.spring_pair[0])
    return {(int(i), int(part[i, k])): force[i, k]
            for i, k in zip(*np.nonzero(np.abs(force).sum(-1)), strict=True)}

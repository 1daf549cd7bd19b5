"""Neighbour-list forces equal brute-force all-pairs forces, also after an overflow."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from helpers import advance, config, start

from jaxdamp.config import Material
from jaxdamp.engine import neighbors as nb
from jaxdamp.physics.integrate import box_frame
from jaxdamp.physics.model import build
from jaxdamp.physics.pairs import all_pairs, pair_forces

MAT = Material(E=2e9, nu=0.3, density=7850.0, mu=0.3, gamma_n=50.0, gamma_s=150.0)


def _dense_packing(n, radius, side, seed):
    """Random dense packing with many overlaps: jittered cubic lattice of spacing 1.9 R."""
    rng = np.random.default_rng(seed)
    k = int(np.ceil(n ** (1 / 3)))
    grid = np.stack(np.meshgrid(*[np.arange(k)] * 3, indexing="ij"), -1).reshape(-1, 3)[:n]
    r = (grid + 0.5) * 1.9 * radius + rng.uniform(-0.15, 0.15, (n, 3)) * radius
    return r, rng.normal(0, 0.3, (n, 3)), rng.normal(0, 100.0, (n, 3))


def test_neighbor_list_forces_equal_all_pairs():
    n, radius = 216, 1e-3
    cfg = config(n=n, radius=radius, material=MAT, box=(0.02, 0.02, 0.02))
    model, params = build(cfg)
    r, v, w = _dense_packing(n, radius, 0.02, seed=3)
    nbrs = nb.allocate(model, jnp.asarray(r)[None], 1.5)
    ref = pair_forces(jnp.asarray(r), jnp.asarray(v), jnp.asarray(w), all_pairs(n), params, model)
    got = pair_forces(jnp.asarray(r), jnp.asarray(v), jnp.asarray(w), nbrs.idx[0], params, model)
    scale = float(jnp.abs(ref.force).max())
    assert scale > 0 and float(ref.friction_loss) > 0
    np.testing.assert_allclose(got.force, ref.force, atol=1e-12 * scale)
    np.testing.assert_allclose(got.torque, ref.torque,
                               atol=1e-12 * float(jnp.abs(ref.torque).max()))
    for field in ("elastic_energy", "normal_loss", "friction_loss"):
        assert float(getattr(got, field)) == pytest.approx(float(getattr(ref, field)), rel=1e-12)
    # Newton's third law holds exactly for the summed pair forces
    assert float(jnp.abs(got.force.sum(axis=0)).max()) < 1e-12 * scale


def test_overflow_reallocates_and_redoes_the_chunk():
    """A list allocated too small overflows; `advance` re-allocates and the chunk's result
    equals a run that had enough capacity from the start (no contact dropped)."""
    n, radius = 64, 1e-3
    cfg = config(n=n, radius=radius, material=MAT, box=(0.01, 0.01, 0.01))
    r, v, w = _dense_packing(n, radius, 0.01, seed=5)
    model, pb, st, good = start(cfg, r, v, w, dt=2e-7)
    small = nb._build(model, 2, box_frame(st, pb))
    assert bool(small.overflow.any())
    calls = []
    a, rec_a = advance(model, st, small, pb, 5, 20,
                       on_realloc=lambda old, new: calls.append((old, new)))
    b, rec_b = advance(model, st, good, pb, 5, 20)
    out_a, nb_a, out_b = a.states, a.nbrs, b.states
    assert calls and calls[0][0] == 2 and calls[0][1] > 2
    assert not bool(nb_a.overflow.any())
    np.testing.assert_allclose(out_a.r, out_b.r, rtol=0, atol=1e-15)
    np.testing.assert_allclose(out_a.v, out_b.v, rtol=1e-10, atol=1e-13)


@pytest.mark.parametrize("movers", [(0,), (0, 5), (1, 2, 6, 7, 3)])
def test_rebuild_is_per_system_and_lists_stay_complete(movers):
    """Eight systems in one batch (rebuild groups of 1, 4 and 8): after one grain of each
    system in ``movers`` moved past skin/2, exactly those systems' lists are rebuilt — through
    the gathered group of one or four, or the whole batch (five movers) — the others keep
    theirs, and every list still contains every pair closer than the cutoff and equals a fresh
    build where rebuilt."""
    n, radius, B = 64, 1e-3, 8
    assert nb.rebuild_groups(B) == (1, 4, B)
    cfg = config(n=n, radius=radius, material=MAT, box=(0.01, 0.01, 0.01))
    model, _ = build(cfg)
    r, _, _ = _dense_packing(n, radius, 0.01, seed=7)
    pos = jnp.stack([jnp.asarray(r)] * B)
    nbrs = nb.allocate(model, pos, 2.0)
    moved = pos
    for k in movers:  # one grain of system k moves a full skin, a different one per system
        moved = moved.at[k, k, 0].add(model.skin)
    updated = jax.jit(lambda nbr, p: nb.update(model, nbr, p))(nbrs, moved)
    fresh = nb._build(model, nb.capacity(nbrs), moved)
    for b in range(B):
        expect = moved[b] if b in movers else pos[b]
        np.testing.assert_array_equal(np.asarray(updated.reference[b]), np.asarray(expect))
        ref = fresh.idx[b] if b in movers else nbrs.idx[b]
        np.testing.assert_array_equal(np.asarray(updated.idx[b]), np.asarray(ref))
        idx = np.asarray(updated.idx[b])
        x = np.asarray(moved[b])
        d = np.linalg.norm(x[:, None] - x[None], axis=-1)
        for i in range(n):
            close = set(np.nonzero((d[i] < model.cutoff) & (np.arange(n) != i))[0])
            assert close <= set(idx[i][idx[i] < n])
    assert not bool(updated.overflow.any())


def _all_pairs_lists(positions, radius, skin, capacity):
    """The dense lists by their definition, from every pair in numpy (independent of both
    builders' metric and compaction): pair ``(i, j)``, ``i != j``, is listed when the grains'
    surfaces are closer than the skin plus the margin, ``|r_i - r_j| - R_i - R_j <
    (1 + margin) skin``; each row holds its first ``capacity`` neighbours in increasing ``j``,
    padded with ``N``; a system overflows when a grain has more."""
    b, n, _ = positions.shape
    idx = np.full((b, n, capacity), n, np.int64)
    overflow = np.zeros(b, bool)
    for k in range(b):
        x = positions[k]
        gap = np.linalg.norm(x[:, None] - x[None], axis=-1) - radius[:, None] - radius[None]
        listed = (gap < (1 + nb._MARGIN) * skin) & ~np.eye(n, dtype=bool)
        for i in range(n):
            js = np.flatnonzero(listed[i])
            overflow[k] |= len(js) > capacity
            idx[k, i, : min(len(js), capacity)] = js[:capacity]
    return idx, overflow


def test_both_builders_list_every_pair_within_the_skin():
    """Both builders (host cell lists at allocation, the traced all-pairs build in the JAX
    engine) list exactly the pairs of :func:`_all_pairs_lists`, in the same order, with the
    same overflow flags: a mixture (size-aware cutoff) in a gas and in a dense state, at a
    capacity that fits and at one that overflows. (Before jax-md was dropped, the traced
    build was compared with jax-md's dense list here; this reference needs no jax-md.)"""
    from jaxdamp.cases import presets

    mix = presets.family("varela2023-b", 0.5)
    m, p = build(mix)
    rng = np.random.default_rng(3)
    pos = rng.uniform(0, [mix.box.Lx, mix.box.Ly, 0.03], (2, m.n, 3)) * np.array(
        [[[1, 1, 1]], [[1, 1, 0.4]]])
    radius = np.asarray(p.radius)
    assert radius.min() < radius.max()  # two sizes: the cutoff depends on the pair
    full = nb.capacity(nb.allocate(m, jnp.asarray(pos), 1.0, radius=p.radius))
    for cap in (full, 3):
        ref_idx, ref_overflow = _all_pairs_lists(pos, radius, m.skin, cap)
        host = nb._dense(m, cap, nb._with_radius(m, jnp.asarray(pos), p.radius))
        traced = nb._build(m, cap, jnp.asarray(pos), nb._radius_array(m, jnp.asarray(pos),
                                                                        p.radius))
        for idx, overflow in (host, (traced.idx, traced.overflow)):
            np.testing.assert_array_equal(np.asarray(idx), ref_idx)
            np.testing.assert_array_equal(np.asarray(overflow), ref_overflow)
        assert ref_overflow.tolist() == [cap == 3] * 2  # fits / overflows in both
        if cap == full:  # it lists pairs, more of them in the dense state
            assert (ref_idx[1] < m.n).sum() > (ref_idx[0] < m.n).sum() > 0


def _with_cells(monkeypatch, model, pos, multiplier=1.5, radius=None):
    """Lists allocated with a cell grid whatever the bed's size (:data:`nb.CELLS_FROM` set
    to 0 for the call)."""
    monkeypatch.setattr(nb, "CELLS_FROM", 0)
    nbrs = nb.allocate(model, pos, multiplier, radius=radius)
    assert nb.has_grid(nbrs)
    dims = nbrs.cells.shape[1:4]
    assert np.prod(dims) > 27  # more cells than one neighbourhood: the grid prunes
    return nbrs


def _cell_build(model, nbrs, cap, pos, radius=None):
    return nb._build_cells(model, cap, pos, nb._radius_array(model, pos, radius), nbrs.grid,
                           nbrs.cells)


def _one_size_gas_and_bed(n=343, seed=11):
    """A batch of two systems of ``n`` equal grains (R = 1 mm): a gas (uniform at random in a
    cube, solid fraction 0.1) and the dense packing of :func:`_dense_packing`."""
    cfg = config(n=n, radius=1e-3, material=MAT, box=(0.05, 0.05, 0.05))
    model, _ = build(cfg)
    r, _, _ = _dense_packing(n, 1e-3, 0.02, seed=seed)
    side = (n * 4.0 / 3.0 * np.pi * 1e-9 / 0.1) ** (1 / 3)
    gas = np.random.default_rng(seed).uniform(0.0, side, (n, 3))
    return model, np.stack([gas, r])


@pytest.mark.parametrize("case", ["mixture", "one size"])
def test_cell_builder_lists_every_pair_within_the_skin(monkeypatch, case):
    """The in-loop cell builder lists exactly the pairs of :func:`_all_pairs_lists` (and of
    the traced all-pairs build), in the same order, with the same overflow flags, for a batch
    of two systems, a gas and a dense bed: a mixture (the size-aware cutoff; radii 1.25 and
    2.5 mm) and one size, at a capacity that fits and at one that overflows (3 neighbours: the
    flag is the same, and every row that fits is the same; a row that overflows holds 3 of its
    neighbours, not necessarily the first, :func:`nb._build_cells_traced`)."""
    from jaxdamp.cases import presets

    if case == "mixture":
        mix = presets.family("varela2023-b", 0.5)
        model, p = build(mix)
        rng = np.random.default_rng(3)
        pos = rng.uniform(0, [mix.box.Lx, mix.box.Ly, 0.03], (2, model.n, 3)) * np.array(
            [[[1, 1, 1]], [[1, 1, 0.4]]])
        radius = np.asarray(p.radius)
        assert radius.min() < radius.max()
    else:
        model, pos = _one_size_gas_and_bed()
        radius = np.full(model.n, 0.5 * (model.cutoff - model.skin))
    pos = jnp.asarray(pos)
    nbrs = _with_cells(monkeypatch, model, pos, radius=radius)
    full = nb.capacity(nbrs)
    every, _ = _all_pairs_lists(np.asarray(pos), radius, model.skin, model.n - 1)
    for cap in (full, 3):
        ref_idx = every[..., :cap]  # the first `cap` of every row, by definition
        fits = (every < model.n).sum(axis=-1) <= cap  # (2, N) rows within the capacity
        ref_overflow = ~fits.all(axis=-1)
        cells = _cell_build(model, nbrs, cap, pos, radius)
        traced = nb._build(model, cap, pos, nb._radius_array(model, pos, radius))
        np.testing.assert_array_equal(np.asarray(traced.idx), ref_idx)
        np.testing.assert_array_equal(np.asarray(traced.overflow), ref_overflow)
        assert fits.any() and (fits.all() == (cap == full))  # at 3, some rows overflow
        np.testing.assert_array_equal(np.asarray(cells.idx)[fits], ref_idx[fits])
        got_rows = np.sort(np.asarray(cells.idx)[~fits], axis=-1)
        assert (got_rows < model.n).all()  # the rows that overflow are full
        np.testing.assert_array_equal(np.asarray(cells.overflow), ref_overflow)
        assert ref_overflow.tolist() == [cap == 3] * 2  # fits / overflows in both
        if cap == full:
            np.testing.assert_array_equal(np.asarray(cells.idx), np.asarray(nbrs.idx))
            assert (ref_idx[1] < model.n).sum() > (ref_idx[0] < model.n).sum() > 0


def test_cell_builder_finds_pairs_outside_its_grid(monkeypatch):
    """Grains that left the grid allocated for them are clamped into its edge cells and keep
    every pair: a touching pair carried far beyond the grid's corner (listed with each other),
    a grain pushed just beyond a face (listed with the edge grains it is near), and a grain at
    a non-finite position (no pairs, as in the other builders) — the lists equal
    :func:`_all_pairs_lists` entry for entry, without overflow."""
    model, both = _one_size_gas_and_bed()
    pos = jnp.asarray(both[1:])  # the dense bed
    nbrs = _with_cells(monkeypatch, model, pos)
    lo = np.asarray(nbrs.grid[0, 0])
    side = float(nbrs.grid[0, 1, 0])
    hi = lo + side * np.asarray(nbrs.cells.shape[1:4])
    x = np.asarray(pos[0]).copy()
    i, j = 0, int(nbrs.idx[0, 0, 0])  # grain 0 and its first neighbour
    assert j < model.n
    far = hi + 7.0 * side
    x[j] = far + (x[j] - x[i])
    x[i] = far
    k = int(np.argmin(x[:, 1]))  # the lowest grain in y: beyond the face y = lo_y
    x[k, 1] = lo[1] - 0.3 * side
    x[5, 2] = np.nan
    assert (x[[i, j]] > hi).all() and x[k, 1] < lo[1]
    moved = jnp.asarray(x)[None]
    radius = np.full(model.n, 0.5 * (model.cutoff - model.skin))
    cap = nb.capacity(nbrs)
    ref_idx, ref_overflow = _all_pairs_lists(x[None], radius, model.skin, cap)
    got = _cell_build(model, nbrs, cap, moved)
    np.testing.assert_array_equal(np.asarray(got.idx), ref_idx)
    assert not bool(got.overflow[0]) and not ref_overflow[0]
    assert j in ref_idx[0, i] and i in ref_idx[0, j]  # the pair beyond the corner
    assert (ref_idx[0, k] < model.n).sum() > 0  # the grain beyond the face has neighbours
    assert (ref_idx[0, 5] == model.n).all() and not (ref_idx[0] == 5).any()  # NaN: none


def test_a_crowded_cell_flags_overflow(monkeypatch):
    """A cell holding more grains than its capacity flags overflow (a grain past the capacity
    is in no cell: its pairs would be lost), where the all-pairs build of the same lists does
    not; at a capacity of exactly the most grains in a cell nothing is flagged."""
    model, both = _one_size_gas_and_bed()
    pos = jnp.asarray(both[1:])
    nbrs = _with_cells(monkeypatch, model, pos)
    most = nb._cell_occupancy(np.asarray(nb._with_radius(model, pos, None)),
                              np.asarray(nbrs.grid), nbrs.cells.shape[1:4])
    assert most > 1
    cap = nb.capacity(nbrs)
    assert not bool(nb._build(model, cap, pos).overflow[0])
    for room, flagged in ((most, False), (most - 1, True)):
        shaped = nb.Neighbors(nbrs.idx, nbrs.reference, nbrs.overflow, nbrs.grid,
                              jnp.zeros(nbrs.cells.shape[:4] + (room, 0), jnp.int32))
        got = _cell_build(model, shaped, cap, pos)
        assert bool(got.overflow[0]) == flagged, room
        if not flagged:
            np.testing.assert_array_equal(np.asarray(got.idx), np.asarray(nbrs.idx))


def test_cell_occupancy_of_dense_beds():
    """The basis of :data:`nb.MIN_CELL_CAPACITY`: the most grains in one cell of the grid of a
    dense bed of equal grains (cells of side 2.315 R at the default skin) is 4 in the thesis
    bed's fcc pour and 8 in the strongly overlapping cubic packing of spacing 1.9 R."""
    from test_large_beds import _bed

    model, params, r = _bed(1000)
    pts = np.asarray(nb._with_radius(model, jnp.asarray(r)[None], params.radius))
    fcc = nb._cell_occupancy(pts, *nb.cell_grid(model, pts))
    model, both = _one_size_gas_and_bed(512)
    pts = np.asarray(nb._with_radius(model, jnp.asarray(both[1:]), None))
    cubic = nb._cell_occupancy(pts, *nb.cell_grid(model, pts))
    assert (fcc, cubic) == (4, 8) and cubic <= nb.MIN_CELL_CAPACITY


def test_reallocation_grows_the_cells_until_all_pairs(monkeypatch):
    """The re-allocation after an overflow (``at_least`` = 1.5 × the capacity + 1, as
    ``driver.grow``) grows the cells' capacity with the lists', strictly, and ends in the
    all-pairs builder (the cells' 27 neighbourhoods as large as the bed) in a few steps, so
    that the driver's redo loop always ends; below :data:`nb.CELLS_FROM` grains no grid."""
    model, both = _one_size_gas_and_bed(1000)
    pos = jnp.asarray(both[1:])
    nbrs = _with_cells(monkeypatch, model, pos)
    rooms = [nbrs.cells.shape[-2]]
    for _ in range(10):
        nbrs = nb.allocate(model, pos, 1.5, at_least=int(np.ceil(nb.capacity(nbrs) * 1.5)) + 1)
        if not nb.has_grid(nbrs):
            break
        rooms.append(nbrs.cells.shape[-2])
    assert not nb.has_grid(nbrs) and len(rooms) >= 3
    assert all(b > 1.4 * a for a, b in zip(rooms, rooms[1:])), rooms
    monkeypatch.setattr(nb, "CELLS_FROM", model.n + 1)
    assert not nb.has_grid(nb.allocate(model, pos, 1.5))


def test_checkpoint_arrays_keep_the_grid(monkeypatch):
    """:func:`nb.to_numpy` / :func:`nb.from_numpy` keep the grid and its shape; arrays
    without them (checkpoints from before the cell builder) give all-pairs lists."""
    model, both = _one_size_gas_and_bed()
    nbrs = _with_cells(monkeypatch, model, jnp.asarray(both[1:]))
    back = nb.from_numpy(nb.to_numpy(nbrs))
    assert back.cells.shape == nbrs.cells.shape
    np.testing.assert_array_equal(np.asarray(back.grid), np.asarray(nbrs.grid))
    old = {k: v for k, v in nb.to_numpy(nbrs).items() if k in ("idx", "reference", "overflow")}
    legacy = nb.from_numpy(old)
    assert not nb.has_grid(legacy) and legacy.grid.shape == (1, 2, 3)


def test_update_rebuilds_from_the_cells(monkeypatch):
    """:func:`nb.update` of lists with a cell grid (four systems, rebuild groups of 1 and 4):
    the systems whose grain moved past skin/2 get the cell builder's lists — equal to the
    all-pairs build's, entry for entry — the others keep theirs, and the grid travels along."""
    model, both = _one_size_gas_and_bed()
    B = 4
    pos = jnp.asarray(np.stack([both[1]] * B))
    nbrs = _with_cells(monkeypatch, model, pos)
    step = jax.jit(lambda nbr, p: nb.update(model, nbr, p))
    for movers in ((2,), (0, 1, 3)):
        moved = pos
        for k in movers:
            moved = moved.at[k, 10 * k, 2].add(3 * model.skin)  # past skin/2: rebuilt
        updated = step(nbrs, moved)
        fresh = nb._build(model, nb.capacity(nbrs), moved)
        assert updated.cells.shape == nbrs.cells.shape
        np.testing.assert_array_equal(np.asarray(updated.grid), np.asarray(nbrs.grid))
        for b in range(B):
            ref = fresh.idx[b] if b in movers else nbrs.idx[b]
            np.testing.assert_array_equal(np.asarray(updated.idx[b]), np.asarray(ref))
        assert not bool(updated.overflow.any())
        assert not np.array_equal(np.asarray(fresh.idx[movers[0]]),
                                  np.asarray(nbrs.idx[movers[0]]))  # a list did change


@pytest.mark.long
def test_jax_engine_with_cells_equals_all_pairs(monkeypatch):
    """A JAX-engine run of a bed large enough for the cell builder (:data:`nb.CELLS_FROM`
    grains or more: 1000 overlapping grains flying apart at up to ~25 m/s, rebuilt in every
    chunk) is bit-identical to the same run with the all-pairs builder: the two build the same
    lists entry for entry and the step reads nothing else. A cell grid allocated too small
    (one grain per cell) overflows; the driver re-allocates (the cells and the lists grown)
    and redoes the chunk, which then equals the run with room (to round-off: the capacity, so
    the padding of the rows, differs)."""
    n, radius = 1000, 1e-3
    assert n >= nb.CELLS_FROM
    cfg = config(n=n, radius=radius, material=MAT, box=(0.05, 0.05, 0.05))
    r, v, w = _dense_packing(n, radius, 0.02, seed=5)
    model, pb, st, cells = start(cfg, r, 10 * v, w, dt=2e-7)
    assert nb.has_grid(cells)
    monkeypatch.setattr(nb, "CELLS_FROM", n + 1)
    _, _, _, pairs = start(cfg, r, 10 * v, w, dt=2e-7)
    monkeypatch.undo()
    assert not nb.has_grid(pairs)
    np.testing.assert_array_equal(np.asarray(cells.idx), np.asarray(pairs.idx))
    small = nb.Neighbors(cells.idx, cells.reference, cells.overflow, cells.grid,
                         jnp.zeros(cells.cells.shape[:4] + (1, 0), jnp.int32))
    runs, calls = {}, []
    for name, nbrs in (("cells", cells), ("pairs", pairs), ("small", small)):
        s, rebuilt = st, 0
        for _ in range(3):
            b, _ = advance(model, s, nbrs, pb, 5, 20,
                           on_realloc=lambda old, new: calls.append((name, old, new)))
            rebuilt += bool(np.any(np.asarray(b.nbrs.reference) != np.asarray(nbrs.reference)))
            s, nbrs = b.states, b.nbrs
        runs[name] = (s, nbrs, rebuilt)
    (a, na, ra), (b_, nb_, rb), (c, nc, _) = runs["cells"], runs["pairs"], runs["small"]
    assert ra == rb == 3 and nb.has_grid(na) and not nb.has_grid(nb_)
    assert [x[0] for x in calls] == ["small"]  # only the small grid re-allocated, once
    for field in ("r", "v", "w", "q", "z", "work"):
        np.testing.assert_array_equal(np.asarray(getattr(a, field)),
                                      np.asarray(getattr(b_, field)))
    np.testing.assert_array_equal(np.asarray(na.idx), np.asarray(nb_.idx))
    assert nb.has_grid(nc) and nc.cells.shape[-2] > 1
    np.testing.assert_allclose(np.asarray(c.r), np.asarray(a.r), rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.asarray(c.v), np.asarray(a.v), rtol=1e-10, atol=1e-13)


def test_the_grid_covers_the_extent(monkeypatch):
    """With ``extent`` (here the floor's and the lid's corners) the grid reaches the lid
    although the bed lies low, so grains thrown up towards the lid fall into cells of their
    own rather than into the top cells of the bed's grid."""
    model, both = _one_size_gas_and_bed()
    pos = jnp.asarray(both[1:])
    monkeypatch.setattr(nb, "CELLS_FROM", 0)
    lid = 0.05
    low = nb.allocate(model, pos, 1.5)
    high = nb.allocate(model, pos, 1.5, extent=[[0.0, 0.0, 0.0], [0.0, 0.0, lid]])

    def top(x):
        return float(x.grid[0, 0, 2] + x.grid[0, 1, 2] * x.cells.shape[3])

    assert top(low) < 0.5 * lid and lid <= top(high) < lid + float(high.grid[0, 1, 2])
    assert float(high.grid[0, 0, 2]) == 0.0  # from the floor

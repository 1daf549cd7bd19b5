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
    np.testing.assert_allclose(got.torque, ref.torque, atol=1e-12 * float(jnp.abs(ref.torque).max()))
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

"""The native kernel's large-bed path (grains in cell order, blocks of cell layers, one system
over the cores) computes the step of the small-bed path: same physics, other summation order."""

import numpy as np
import pytest
from helpers import BASE_EXTRAS, STRUCTURE, mixture, mixture_bed, start

from jaxdamp.config import apply_overrides
from jaxdamp.engine import native
from jaxdamp.engine.simulate import chunk_fn

pytestmark = pytest.mark.skipif(not native.AVAILABLE, reason="numba not installed")

FIELDS = ("r", "v", "w", "q", "a", "alpha", "z", "zd", "y", "yd", "work", "work_cell",
          "e_elastic", "f_box", "n_floor", "n_lid", "n_side")


def _chunk(cfg, r, v, w, large: int, block: int = 8, batch: int = 1, n_records=6, every=100,
           chunk: int = 2, fields=FIELDS):
    """States and samples after ``n_records × every`` steps of the native kernel, with the
    large-bed path from ``large`` grains on (blocks of ``block`` grains, the sweep's chunks of
    ``chunk`` blocks: 2, the fewest, puts the most blocks where two chunks meet)."""
    import jax

    model, pb, st, nbrs = start(cfg, r, v, w)
    if batch > 1:
        tile = lambda x: jax.numpy.concatenate([x] * batch)  # noqa: E731
        st, nbrs, pb = (jax.tree_util.tree_map(tile, t) for t in (st, nbrs, pb))
    old = native.LARGE, native.BLOCK_GRAINS, native.CHUNK_BLOCKS
    native.LARGE, native.BLOCK_GRAINS, native.CHUNK_BLOCKS = large, block, chunk
    try:
        s, _, rec = chunk_fn(model, n_records, every, engine="native")(st, nbrs, pb)
    finally:
        native.LARGE, native.BLOCK_GRAINS, native.CHUNK_BLOCKS = old
    return ({f: np.asarray(getattr(s, f)) for f in fields},
            {k: np.asarray(x) for k, x in rec.items()})


def _mixture_bed(system, extras):
    """The two-species bed of 50 grains (fast, spinning) as ``system`` with the overrides
    ``extras``: copied into each cell at its corner (``cells``, species after species), or
    moved into the circle of a cylinder (``container.radius``; the lattice is 9 mm about its
    centre). Returns ``(config, r, v, w)``."""
    cells = extras.get("cells", 1)
    cfg = apply_overrides(mixture(system, "harmonic", counts=(20 // cells, 30 // cells)), extras)
    r, v, w = mixture_bed(50 // cells)
    if cells > 1:
        from jaxdamp.physics.model import build

        big = 20 // cells
        src = np.r_[np.tile(np.arange(big), cells), np.tile(np.arange(big, len(r)), cells)]
        origin = np.asarray(build(cfg)[1].origin)
        r, v, w = r[src] + np.c_[origin, np.zeros(len(src))], v[src], w[src]
    if "container.radius" in extras:
        r = r + [extras["container.radius"] - 0.009, extras["container.radius"] - 0.009, 0.0]
    return cfg, r, v, w


@pytest.mark.parametrize("system, extras", [
    ("primary", {}), ("driven", {}), ("primary", BASE_EXTRAS), ("primary", STRUCTURE),
    ("driven", {"cells": 2}),
    ("primary", {"container.shape": "cylinder", "container.radius": 0.0135, "container.Lz": 0.02})])
def test_large_path_equals_small_path(system, extras):
    """A two-species bed (friction, fast spins, walls) through both paths of the kernel over
    600 steps, the large one in blocks of 8 grains (so that the blocks' pairs cross into the
    next block) swept in chunks of 2 blocks (so that most blocks are done where two chunks
    meet): states and samples agree to round-off (the paths add the forces in another
    order), in the user's numbering of the grains; also with several damper cells, a 3-DOF
    structure and curved sides."""
    cfg, r, v, w = _mixture_bed(system, extras)
    (sa, ra), (sb, rb) = (_chunk(cfg, r, v, w, large) for large in (10**9, 2))
    assert sa["work"][0][2] > 0  # grain pairs touched
    for f in FIELDS:
        a, b = sa[f], sb[f]
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(a).max(initial=0)),
                                   err_msg=f)
    for k in ra:
        np.testing.assert_allclose(rb[k], ra[k], rtol=1e-8,
                                   atol=1e-12 * max(1.0, float(np.abs(ra[k]).max(initial=0))),
                                   err_msg=k)


SPRINGS = ("e_spring", "spring_wall", "spring_partner", "spring_pair")


@pytest.mark.long  # the native kernel's spring form (compiled once, cached)
@pytest.mark.parametrize("system, extras", [
    ("primary", {}), ("driven", {"cells": 2}),
    ("primary", {"container.shape": "cylinder", "container.radius": 0.0135, "container.Lz": 0.02})])
def test_large_path_with_springs_equals_small_path(system, extras):
    """The tangential springs with history (``tangential_law = "mindlin"``) on the large-bed
    path: the two-species bed over 600 steps in blocks of 8 grains and chunks of 2 blocks, its
    lists rebuilt (the grains re-sorted, the springs carried by pair identity) — states,
    samples, the springs' energy and every spring held, pairs and walls, agree with the small
    path to round-off, in the user's numbering; in two cells and in a cylinder too (the
    pairs' springs slip in all three, the walls' in the box and the cells; the springs held
    at the end compared by pair identity)."""
    cfg, r, v, w = _mixture_bed(system, {**extras, "tangential_law": "mindlin"})
    (sa, ra), (sb, rb) = (_chunk(cfg, r, v, w, large, fields=FIELDS + SPRINGS)
                          for large in (10**9, 2))
    from jaxdamp.physics.model import CH

    work = sa["work"][0]
    assert work[CH["pp_slip"]] > 0  # the pairs' springs slipped
    if "container.radius" not in extras:  # (this bed does not reach the cylinder's walls)
        assert work[CH["pw_slip"]] > 0
    for f in FIELDS + ("e_spring", "spring_wall"):
        a, b = sa[f], sb[f]
        np.testing.assert_allclose(b, a, rtol=1e-9, atol=1e-12 * max(1.0, np.abs(a).max(initial=0)),
                                   err_msg=f)
    held = [{(i, int(s["spring_partner"][0][i, k])): s["spring_pair"][0][i, k]
             for i, k in zip(*np.nonzero(np.abs(s["spring_pair"][0]).sum(-1)), strict=True)}
            for s in (sa, sb)]
    assert held[0].keys() == held[1].keys()
    assert held[0] or "container.radius" in extras  # (the cylinder's bed ends apart)
    scale = max((np.abs(x).max() for x in held[0].values()), default=0.0)
    for key, force in held[0].items():
        np.testing.assert_allclose(held[1][key], force, rtol=0, atol=1e-9 * scale, err_msg=key)
    for k in ra:
        np.testing.assert_allclose(rb[k], ra[k], rtol=1e-8,
                                   atol=1e-12 * max(1.0, float(np.abs(ra[k]).max(initial=0))),
                                   err_msg=k)


@pytest.mark.parametrize("chunk", [2, 3, 100])
def test_large_path_is_the_same_on_any_core_count_and_batch(chunk):
    """One system alone (its chunks of blocks over the cores) and the same system twice in a
    batch (the systems over the cores, each one's chunks in turn) give the same bits: the
    chunks depend on the bed alone and the blocks' sums are added in a fixed order (chunks of
    2 and 3 blocks, and one chunk of them all)."""
    cfg = mixture("driven", "harmonic")
    r, v, w = mixture_bed(50)
    one, _ = _chunk(cfg, r, v, w, 2, block=6, chunk=chunk)
    two, _ = _chunk(cfg, r, v, w, 2, block=6, batch=2, chunk=chunk)
    for f in FIELDS:
        np.testing.assert_array_equal(two[f][0], one[f][0], err_msg=f)
        np.testing.assert_array_equal(two[f][1], one[f][0], err_msg=f)


def _long_bed(n_cols: int = 18, seed: int = 3):
    """The two-species bed of :func:`helpers.mixture` in a long box (9 cm × 9 mm × 2 cm), its
    ``4 n_cols`` grains on a jittered lattice of 4.5 mm, fast and spinning: its cell layers
    along x make many blocks, so that the sweep has many chunks."""
    cfg = apply_overrides(mixture("driven", "harmonic", counts=(2 * n_cols, 2 * n_cols)),
                          {"box.Lx": 0.09, "box.Ly": 0.009})
    rng = np.random.default_rng(seed)
    grid = np.stack(np.meshgrid(np.arange(n_cols), np.arange(2), np.arange(2), indexing="ij"),
                    -1).reshape(-1, 3)
    r = (grid + 0.5) * 0.0045 + rng.uniform(-3e-4, 3e-4, grid.shape)
    r[:, 2] += 0.001
    return cfg, r, rng.normal(0, 0.5, r.shape), rng.normal(0, 100.0, r.shape)


def test_many_chunks_long_bed():
    """A long bed (about 16 cell layers) in blocks of 4 grains and chunks of 2 blocks: seven
    places where two chunks meet, each done after the chunks; the large path equals the small
    one to round-off, and alone equals itself in a batch bit for bit."""
    cfg, r, v, w = _long_bed()
    (sa, _), (sb, _) = (_chunk(cfg, r, v, w, large, block=4) for large in (10**9, 2))
    assert sa["work"][0][2] > 0  # grain pairs touched
    for f in FIELDS:
        np.testing.assert_allclose(sb[f], sa[f], rtol=1e-9,
                                   atol=1e-12 * max(1.0, np.abs(sa[f]).max(initial=0)), err_msg=f)
    two, _ = _chunk(cfg, r, v, w, 2, block=4, batch=2)
    for f in FIELDS:
        np.testing.assert_array_equal(two[f][0], sb[f][0], err_msg=f)
        np.testing.assert_array_equal(two[f][1], sb[f][0], err_msg=f)


def test_a_large_bed_alone_starts_the_threads_itself():
    """In a fresh process whose first kernel call is one large bed (its blocks over the
    cores, parallel regions started from inside a serial kernel), numba's threads are
    launched first: before, that call crashed the process (a null pointer, exit 139)."""
    import subprocess
    import sys

    code = (
        "import sys; sys.path.insert(0, 'tests')\n"
        "from test_native_large import _chunk, mixture, mixture_bed\n"
        "s, _ = _chunk(mixture('driven', 'harmonic'), *mixture_bed(50), 2, n_records=1,"
        " every=20)\n"
        "print('ok', s['r'].shape)\n")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                       timeout=600)
    assert p.returncode == 0 and "ok (1, 50, 3)" in p.stdout, (p.returncode, p.stderr[-2000:])

"""Neighbour lists for grain–grain contacts, each system's rebuilt when its own grains moved.

The rebuild policy (:func:`update`) is per system: a system's list is rebuilt when one of its
grains moved more than ``skin / 2`` since its last build, and only then, so one fast system
does not force a rebuild of thousands. A per-system ``lax.cond`` (as jax-md's
``NeighborList.update`` takes it) becomes a select under ``vmap``, which would rebuild every
system at every step; instead the systems that need it are gathered (static shapes) into the
smallest of a few group sizes (:func:`rebuild_groups`) that holds them, rebuilt and scattered
back, with one ``lax.switch`` per step on the batch as a whole. The capacity (neighbours per grain, a static shape) is allocated for the whole
batch. The policy is independent of the builder (:func:`_build_traced`, all pairs).

Positions given to the list are in the box frame (``z`` measured from the floor): pair
distances do not change under the box's rigid translation, and a bed that rides with the box
does not trigger rebuilds.

A rebuild is needed once any grain moved more than ``skin / 2`` since the last build, judged
at the positions where the next forces are evaluated (the predictor's,
``box_frame(state, params, dt)``;
both engines); the list holds every pair whose surfaces are closer than ``skin`` (centres
closer than ``R_i + R_j + skin``, plus a small safety margin). The size-aware
cutoff keeps mixtures cheap: with radii differing tenfold a uniform ``2 R_max + skin`` would list
hundreds of small neighbours per small grain, where a few dozen can touch. It is a metric on
positions carrying the radius as a fourth coordinate,
``max(0, |r_i - r_j| - R_i - R_j + 2 R_max)``, compared with ``2 R_max + skin``; for equal radii
this is the plain distance. Overflow (a grain with more neighbours than the capacity) is
flagged, sticky, in :attr:`Neighbors.overflow`; the runner re-allocates and redoes the chunk.
The format is dense: ``idx (N, K)``, each row's neighbours in increasing order, padded with
``N`` (jax-md's ``Dense`` format, so that code written for it reads these lists).

Two builders list the same pairs, entry for entry (``tests/test_large_beds.py``):

* allocation (the capacity and the first lists, :func:`allocate`) on the host, on a cell grid
  of side ``2 R_max + skin`` (:func:`host_pairs`): time and memory linear in ``N``, so a
  50 000-grain bed starts in seconds and a few hundred MB;
* the rebuild *inside* the jitted JAX engine (:func:`update`): all pairs at once in plain JAX
  (:func:`_build_traced`), ``O(N²)`` memory per rebuild — fine for the differentiable runs of
  small beds the JAX engine is for. It replaced jax-md's dense all-pairs list (cell lists off),
  the one part of jax-md the project used; that removed 51 packages and 432 MB from the
  install and a 6–15 s import (``benchmarks/install_size.py``, ``benchmarks/RESULTS.md``).
  ``tests/test_neighbors.py`` checks both builders against a brute-force list of all pairs.

The compiled CPU engine (:mod:`jaxdamp.engine.native`) builds its own cell lists.
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.physics.model import Model, pytree_dataclass

#: Extra cutoff beyond 2 R_max + skin, as a fraction of the skin, covering the one step that
#: moves grains between the rebuild check and the force evaluation.
_MARGIN = 0.05


@pytree_dataclass
class Neighbors:
    """A (batch of) neighbour list(s). ``idx``: ``(..., N, K)`` indices padded with ``N``;
    ``reference``: ``(..., N, 3)`` box-frame positions at the last build [m]; ``overflow``:
    ``(...)`` bool, true once a build found more than ``K`` neighbours for some grain."""

    idx: jnp.ndarray
    reference: jnp.ndarray
    overflow: jnp.ndarray


def _gap_metric(model: Model):
    """Metric on ``(x, y, z, R)`` points: the surface gap shifted by ``2 R_max``."""
    shift = model.cutoff - model.skin  # 2 R_max

    def metric(a, b, **unused):
        d = a[..., :-1] - b[..., :-1]
        return jnp.maximum(jnp.sqrt(jnp.sum(d * d, axis=-1)) - a[..., -1] - b[..., -1] + shift, 0.0)

    return metric


def _with_radius(model: Model, positions, radius):
    """Positions ``(..., N, 3)`` with the radii as a fourth column; ``radius=None`` means every
    grain has the largest radius (the uniform cutoff ``2 R_max + skin``)."""
    positions = jnp.asarray(positions)
    if radius is None:
        radius = 0.5 * (model.cutoff - model.skin)
    radius = jnp.broadcast_to(jnp.asarray(radius, positions.dtype), positions.shape[:-1])
    return jnp.concatenate([positions, radius[..., None]], axis=-1)


def host_pairs(points: np.ndarray, cutoff: float, shift: float):
    """Every ordered pair ``(i, j)``, ``i != j``, of one system listed by the gap metric
    (:func:`_gap_metric`: ``max(0, |r_i - r_j| - R_i - R_j + shift)``, squared, below
    ``cutoff²``, as :func:`_build_traced` compares it), sorted by ``i`` then ``j``.

    ``points``: ``(N, 4)`` host array ``(x, y, z, R)``. Candidates come from a cell grid of side
    ``cutoff`` (the metric is at least the centre distance minus ``2 R_max - shift = 0``, so a
    listed pair is never more than one cell apart): time and memory ``O(N)`` for a bed, never an
    ``N × N`` array. Grains at non-finite positions have no pairs. Returns ``(i, j)`` int64."""
    points = np.asarray(points, np.float64)
    x, R = points[:, :3], points[:, 3]
    good = np.isfinite(points).all(axis=1)
    ids = np.flatnonzero(good)
    if len(ids) < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    xg = x[ids]
    cell = np.floor((xg - xg.min(axis=0)) / cutoff).astype(np.int64)
    dims = cell.max(axis=0) + 1
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    sorted_key = key[order]
    cutoff_sq = cutoff * cutoff
    out_i, out_j = [], []
    for dx in (-1, 0, 1):
        for dy in (-1, 0, 1):
            for dz in (-1, 0, 1):
                other = cell + np.array([dx, dy, dz])
                ok = ((other >= 0) & (other < dims)).all(axis=1)
                okey = (other[:, 0] * dims[1] + other[:, 1]) * dims[2] + other[:, 2]
                lo = np.searchsorted(sorted_key, okey, "left")
                hi = np.searchsorted(sorted_key, okey, "right")
                count = np.where(ok, hi - lo, 0)
                total = int(count.sum())
                if total == 0:
                    continue
                a = np.repeat(np.arange(len(ids)), count)
                first = np.repeat(lo - (np.cumsum(count) - count), count)
                b = order[first + np.arange(total)]
                keep = a != b
                a, b = a[keep], b[keep]
                d = xg[a] - xg[b]
                gap = np.maximum(np.sqrt((d * d).sum(axis=1)) - R[ids[a]] - R[ids[b]] + shift,
                                 0.0)
                close = gap * gap < cutoff_sq
                out_i.append(ids[a[close]])
                out_j.append(ids[b[close]])
    if not out_i:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    i, j = np.concatenate(out_i), np.concatenate(out_j)
    rank = np.lexsort((j, i))
    return i[rank], j[rank]


def _host_lists(model: Model, points) -> list[tuple[np.ndarray, np.ndarray]]:
    """:func:`host_pairs` of every system of a batch of points ``(B, N, 4)``."""
    cutoff = model.cutoff + _MARGIN * model.skin
    shift = model.cutoff - model.skin  # 2 R_max
    return [host_pairs(p, cutoff, shift) for p in np.asarray(points)]


def _occupancy(model: Model, points) -> int:
    """Largest number of listed neighbours of any grain in the batch (``points`` ``(B, N, 4)``),
    from host cell lists (linear in ``N``)."""
    return max((int(np.bincount(i, minlength=model.n).max()) if len(i) else 0)
               for i, _ in _host_lists(model, points))


def _dense(model: Model, capacity: int, points) -> tuple[np.ndarray, np.ndarray]:
    """Dense neighbour blocks ``(B, N, capacity)`` (padding ``N``, each row's neighbours in
    increasing order) and the overflow flags ``(B,)``."""
    n = model.n
    lists = _host_lists(model, points)
    idx = np.full((len(lists), n, capacity), n, np.int32)
    overflow = np.zeros(len(lists), bool)
    for b, (i, j) in enumerate(lists):
        if not len(i):
            continue
        counts = np.bincount(i, minlength=n)
        slot = np.arange(len(i)) - np.repeat(np.cumsum(counts) - counts, counts)
        fits = slot < capacity
        overflow[b] = not fits.all()
        idx[b, i[fits], slot[fits]] = j[fits]
    return idx, overflow


#: Smallest capacity allocated: the kissing number of equal spheres, so that a gas-like start
#: does not re-allocate as soon as the grains settle into a bed.
MIN_CAPACITY = 12


def capacity_for(model: Model, positions, multiplier: float, at_least: int = 0,
                 radius=None) -> int:
    """Capacity for a batch of box-frame positions ``(B, N, 3)`` (radii ``(B, N)`` or ``(N,)``,
    ``None``: all ``R_max``): max occupancy × multiplier (at least :data:`MIN_CAPACITY` and
    ``at_least``, at most ``N - 1``)."""
    if model.n < 2:
        return 0
    occ = _occupancy(model, _with_radius(model, positions, radius))
    cap = max(int(math.ceil(occ * multiplier)), at_least, MIN_CAPACITY)
    return min(cap, model.n - 1)


def allocate(model: Model, positions, multiplier: float, at_least: int = 0,
             radius=None) -> Neighbors:
    """Build lists for a batch of box-frame positions ``(B, N, 3)`` with a shared capacity.

    ``radius``: grain radii [m], ``(B, N)`` or ``(N,)`` (``Params.radius``); ``None`` treats
    every grain as the largest (exact for one size, wasteful for mixtures)."""
    positions = jnp.asarray(positions)
    if model.n < 2:
        b = positions.shape[0]
        return Neighbors(
            idx=jnp.zeros((b, model.n, 0), jnp.int32),
            reference=positions,
            overflow=jnp.zeros((b,), bool),
        )
    cap = capacity_for(model, positions, multiplier, at_least, radius)
    idx, overflow = _dense(model, cap, _with_radius(model, positions, radius))
    return Neighbors(idx=jnp.asarray(idx), reference=positions, overflow=jnp.asarray(overflow))


def capacity(nbrs: Neighbors) -> int:
    return int(nbrs.idx.shape[-1])


def _radius_array(model: Model, positions, radius):
    return _with_radius(model, positions, radius)[..., 3]


#: Ratio of successive rebuild group sizes (:func:`rebuild_groups`): the systems that need a
#: new list are rebuilt as the smallest group that holds them, at most this many times their
#: number; each size is one branch (one more compiled copy of the builder).
GROUP_RATIO = 4


def rebuild_groups(batch: int) -> tuple[int, ...]:
    """The group sizes a batch of ``batch`` systems rebuilds in: 1, 4, 16, … and ``batch``."""
    sizes = [1]
    while sizes[-1] * GROUP_RATIO < batch:
        sizes.append(sizes[-1] * GROUP_RATIO)
    return tuple(s for s in sizes if s < batch) + (batch,)


def update(model: Model, nbrs: Neighbors, positions, radius=None) -> Neighbors:
    """Rebuild the list of every system of which a grain moved more than ``skin / 2``.

    Traceable (use inside ``jit``/``scan``); ``positions`` are box-frame, ``(B, N, 3)``;
    ``radius`` as in :func:`allocate`. Systems whose grains did not move that far keep their
    lists (a system's trajectory does not depend on the batch it runs in). The systems that
    need it are gathered into the smallest group of :func:`rebuild_groups` that holds them,
    rebuilt together and scattered back (one ``lax.switch`` per step on the batch); the group
    of the whole batch rebuilds every system and keeps the others' lists. No gradient flows
    through a rebuild (the lists are integers; the reference positions only decide the next
    rebuild).
    """
    if model.n < 2:
        return nbrs
    b = positions.shape[0]
    cap = capacity(nbrs)
    positions = jax.lax.stop_gradient(positions)
    radii = lambda: _radius_array(model, positions, radius)  # noqa: E731 - in a rebuild only
    moved2 = jnp.sum((positions - nbrs.reference) ** 2, axis=-1)
    need = jnp.any(moved2 > (0.5 * model.skin) ** 2, axis=-1)  # (B,)
    count = jnp.sum(need)
    sizes = rebuild_groups(b)

    def rebuild_all(nb):
        fresh = _build_traced(model, cap, positions, radii())
        keep = lambda new, old: jnp.where(  # noqa: E731
            need.reshape(need.shape + (1,) * (old.ndim - 1)), new, old)
        return Neighbors(keep(fresh.idx, nb.idx), keep(fresh.reference, nb.reference),
                         nb.overflow | (need & fresh.overflow))

    def group_of(size):
        def rebuild(nb):
            sel = jnp.nonzero(need, size=size, fill_value=b)[0]  # those that need it, then b
            take = jnp.minimum(sel, b - 1)
            fresh = _build_traced(model, cap, positions[take], radii()[take])
            return Neighbors(nb.idx.at[sel].set(fresh.idx, mode="drop"),
                             nb.reference.at[sel].set(fresh.reference, mode="drop"),
                             nb.overflow.at[sel].set(nb.overflow[take] | fresh.overflow,
                                                     mode="drop"))
        return rebuild

    branches = [lambda nb: nb] + [group_of(s) for s in sizes[:-1]] + [rebuild_all]
    if len(branches) == 2:
        return jax.lax.cond(count > 0, branches[1], branches[0], nbrs)
    which = sum((count > s).astype(jnp.int32) for s in (0,) + sizes[:-1])
    return jax.lax.switch(which, branches, nbrs)


def _build_traced(model: Model, capacity: int, positions, radius=None) -> Neighbors:
    """Dense lists of a batch of box-frame positions ``(B, N, 3)`` from all pairs (traceable):
    pair ``(i, j)``, ``i != j``, is listed when ``metric² < (cutoff + margin)²``; each row's
    first ``capacity`` neighbours in increasing ``j``, padded with ``N``; ``overflow`` where a
    grain has more.

    Compaction without a scatter: with ``c_i`` the running count of listed ``j`` along row
    ``i``, the ``s``-th neighbour (``s = 1, 2, ...``) is the first ``j`` with ``c_i[j] = s``, a
    binary search in the non-decreasing ``c_i`` (``N`` where the row has fewer than ``s``):
    2.3× faster than scattering every listed ``j`` to its slot on the CPU (moving thesis bed,
    batch 32: 1.21 → 0.52 ms per system and rebuild)."""
    n = model.n
    points = _with_radius(model, positions, radius)
    metric = _gap_metric(model)
    cut = model.cutoff + _MARGIN * model.skin
    j = jnp.arange(n)
    s = jnp.arange(1, capacity + 1, dtype=jnp.int32)

    def one(p):
        d = metric(p[:, None, :], p[None, :, :])  # (N, N)
        listed = (d * d < cut * cut) & (j[:, None] != j[None, :])
        count = jnp.cumsum(listed.astype(jnp.int32), axis=1)  # (N, N), non-decreasing rows
        idx = jax.vmap(lambda c: jnp.searchsorted(c, s, side="left", method="scan_unrolled"))(
            count).astype(jnp.int32)
        return idx, jnp.any(count[:, -1] > capacity)

    idx, overflow = jax.vmap(one)(points)
    return Neighbors(idx=idx, reference=positions, overflow=overflow)


_build = jax.jit(_build_traced, static_argnums=(0, 1))


def to_numpy(nbrs: Neighbors) -> dict[str, np.ndarray]:
    return {k: np.asarray(getattr(nbrs, k)) for k in ("idx", "reference", "overflow")}


def from_numpy(d: dict[str, np.ndarray]) -> Neighbors:
    return Neighbors(
        idx=jnp.asarray(d["idx"], jnp.int32),
        reference=jnp.asarray(d["reference"]),
        overflow=jnp.asarray(d["overflow"], bool),
    )

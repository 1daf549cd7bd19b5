"""Neighbour lists for grain–grain contacts, each system's rebuilt when its own grains moved.

The rebuild policy (:func:`update`) is per system: a system's list is rebuilt when one of its
grains moved more than ``skin / 2`` since its last build, and only then, so one fast system
does not force a rebuild of thousands. A per-system ``lax.cond`` (as jax-md's
``NeighborList.update`` takes it) becomes a select under ``vmap``, which would rebuild every
system at every step; instead the systems that need it are gathered (static shapes) into the
smallest of a few group sizes (:func:`rebuild_groups`) that holds them, rebuilt and scattered
back, with one ``lax.switch`` per step on the batch as a whole. The capacity (neighbours per
grain, a static shape) is allocated for the whole batch. The policy is independent of the
builder (below).

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
this is the plain distance. Overflow (a grain with more neighbours than the capacity, or a cell
of the in-loop cell list with more grains than its capacity) is flagged, sticky, in
:attr:`Neighbors.overflow`; the runner re-allocates (both capacities grown) and redoes the
chunk. The format is dense: ``idx (N, K)``, each row's neighbours in increasing order, padded
with ``N`` (jax-md's ``Dense`` format, so that code written for it reads these lists).

Three builders list the same pairs, entry for entry (``tests/test_neighbors.py``,
``tests/test_large_beds.py``, each against a brute-force list of all pairs; the in-loop cell
builder fills a row that overflows with other neighbours, :func:`_build_cells_traced`):

* allocation (the capacity and the first lists, :func:`allocate`) on the host, on a cell grid
  of side ``2 R_max + skin`` (:func:`host_pairs`): time and memory linear in ``N``, so a
  50 000-grain bed starts in seconds and a few hundred MB;
* the rebuild *inside* the jitted JAX engine (:func:`update`) of a bed of
  :data:`CELLS_FROM` grains or more, from a cell list in plain JAX
  (:func:`_build_cells_traced`): the grains sorted into a static grid of cubic cells at least
  the listing distance wide, each grain's candidates the grains of the 27 cells around its
  own — time ``O(N log N)`` (one sort) and memory ``O(N)`` per rebuild (one thesis-like bed
  on a 2-core CPU: 86 ms and 56 MB of scratch at 16 000 grains, 0.28 s and 174 MB at 50 000,
  where all pairs would take 20 GB). The grid (its corner, the cells' side, their number per
  axis and the grains a cell holds) is fixed on the host at allocation, from the positions
  and the space the grains may reach (:func:`cell_grid`), and travels in
  :attr:`Neighbors.grid` and the shape of :attr:`Neighbors.cells`; a grain outside it counts
  to the edge cell (no pair is lost, :func:`_cell_coords`);
* the rebuild of smaller beds from all pairs at once (:func:`_build_traced`), ``O(N²)``
  memory, faster there on the CPU (:data:`CELLS_FROM`) — the differentiable runs of small
  beds the JAX engine is mostly for. It replaced jax-md's dense all-pairs list (cell lists
  off: jax-md's cell lists take 2-D or 3-D positions, not the radius as a fourth coordinate
  of the size-aware metric), the one part of jax-md the project used; that removed 51 packages
  and 432 MB from the install and a 6–15 s import (``benchmarks/install_size.py``,
  ``benchmarks/RESULTS.md``).

Which in-loop builder a list uses is decided at allocation and carried by the list (lists
without a grid — fewer than :data:`CELLS_FROM` grains, or a grid that would not prune — are
rebuilt from all pairs), so a trajectory does not depend on the builder: both give the same
lists, bit for bit (``tests/test_neighbors.py``).

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
    ``(...)`` bool, true once a build found more than ``K`` neighbours for some grain, or more
    grains in a cell than its capacity; ``grid``: ``(..., 2, 3)`` the cell grid of the
    in-loop cell builder, its lower corner and its cells' sides [m] (box frame; zeros without
    a grid); ``cells``: an empty int32 array whose *shape* ``(..., g_x, g_y, g_z, C, 0)`` is
    the grid's, ``g_x × g_y × g_z`` cells of at most ``C`` grains (static numbers travel
    through ``jit`` as shapes); ``(..., 0, 0, 0, 0, 0)``: no grid, the all-pairs builder
    (:func:`allocate` decides; module docstring)."""

    idx: jnp.ndarray
    reference: jnp.ndarray
    overflow: jnp.ndarray
    grid: jnp.ndarray
    cells: jnp.ndarray


def _no_grid(batch: int) -> tuple[jnp.ndarray, jnp.ndarray]:
    """``(grid, cells)`` of lists rebuilt from all pairs (:class:`Neighbors`)."""
    return jnp.zeros((batch, 2, 3)), jnp.zeros((batch, 0, 0, 0, 0, 0), jnp.int32)


def _listing_cutoff(model: Model) -> float:
    """The listing distance of the gap metric (:func:`_gap_metric`) [m]: ``2 R_max + skin``
    plus the margin ``_MARGIN skin``; a pair is listed when its metric is below it."""
    return model.cutoff + _MARGIN * model.skin


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
    shift = model.cutoff - model.skin  # 2 R_max
    return [host_pairs(p, _listing_cutoff(model), shift) for p in np.asarray(points)]


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


def _capacities(model: Model, points, multiplier: float, at_least: int) -> tuple[int, int]:
    """``(base, capacity)`` for a batch of points ``(B, N, 4)``: ``base`` = max occupancy ×
    multiplier (at least :data:`MIN_CAPACITY`), ``capacity`` = ``base`` or ``at_least`` if
    larger; both at most ``N - 1``."""
    occ = _occupancy(model, points)
    base = min(max(int(math.ceil(occ * multiplier)), MIN_CAPACITY), model.n - 1)
    return base, min(max(base, at_least), model.n - 1)


def capacity_for(model: Model, positions, multiplier: float, at_least: int = 0,
                 radius=None) -> int:
    """Capacity for a batch of box-frame positions ``(B, N, 3)`` (radii ``(B, N)`` or ``(N,)``,
    ``None``: all ``R_max``): max occupancy × multiplier (at least :data:`MIN_CAPACITY` and
    ``at_least``, at most ``N - 1``)."""
    if model.n < 2:
        return 0
    return _capacities(model, _with_radius(model, positions, radius), multiplier, at_least)[1]


#: Beds of at least this many grains are rebuilt in the JAX engine from a cell list
#: (:func:`_build_cells_traced`), smaller ones from all pairs (:func:`_build_traced`), which
#: is faster there on the CPU. One rebuild of one thesis-like bed (``test_large_beds._bed``:
#: the fcc pour; capacities 18 neighbours, 8 grains per cell), jitted, after compiling, on a
#: shared 2-core CPU (minimum of 15 repeats; 4 at 16 000), all pairs / cells: 0.46 / 0.78 ms
#: at N = 250, 1.7 / 1.5 ms at 500, 3.8 / 3.0 ms at 1000, 131 / 12 ms at 4000, 2.3 s / 86 ms
#: at 16 000 (2026-12-06).
CELLS_FROM = 500

#: Smallest cell capacity allocated (grains per cell of the in-loop cell list), so that a
#: gas-like start does not re-allocate when it settles: cells are ``2 R_max + 1.05 skin``
#: wide, 1.16 diameters at the default skin ``0.3 R_max``, and the most grains in one cell of
#: dense beds of equal grains are 4 (the thesis bed's fcc pour) and 8 (a cubic packing of
#: spacing 1.9 R, strongly overlapping; ``tests/test_neighbors.py``).
MIN_CELL_CAPACITY = 8

#: Most cells of the grid per grain: a grid over a container much larger than its bed (or a
#: gas) gets larger cells instead of more (the cell table is ``cells × C`` integers).
MAX_CELLS_PER_GRAIN = 8

#: Relative widening of the cells beyond the listing distance, so that rounding in a cell
#: index never puts a listed pair two cells apart.
_SIDE_GUARD = 1e-6

#: The 27 offsets of a cell's neighbourhood, itself included, ``(27, 3)``.
_STENCIL = np.stack(np.meshgrid(*[np.arange(-1, 2)] * 3, indexing="ij"), -1).reshape(-1, 3)


def _cell_coords(x, grid, dims, xp=jnp):
    """Cell of box-frame positions ``x`` ``(..., N, 3)`` in the grid ``(..., 2, 3)`` (lower
    corner, cell sides [m]) of ``dims`` cells per axis: ``floor((x - corner) / side)`` per
    axis, clamped into ``[0, dims - 1]`` (a grain outside the grid counts to the edge cell;
    non-finite coordinates to cell 0), ``(..., N, 3)`` int32; ``xp``: numpy or jax.numpy.
    Clamping keeps listed pairs findable: it never moves two indices further apart, so a pair
    at most one cell apart (centres closer than a side) stays at most one apart."""
    u = (x - grid[..., 0:1, :]) / grid[..., 1:2, :]
    u = xp.where(xp.isfinite(u), u, 0.0)
    u = xp.clip(u, 0.0, xp.asarray(dims, u.dtype) - 1.0)
    return xp.floor(u).astype(xp.int32)


def _cell_key(c, dims):
    """Flat cell number ``(c_x g_y + c_y) g_z + c_z`` of cell coordinates ``(..., 3)``."""
    return (c[..., 0] * dims[1] + c[..., 1]) * dims[2] + c[..., 2]


def cell_grid(model: Model, points, extent=None) -> tuple[np.ndarray, tuple[int, int, int]]:
    """The cell grid of the in-loop cell builder for a batch of points ``(B, N, 4)`` (host):
    ``(grid (B, 2, 3), dims)`` — each system's lower corner and cell sides [m], and the cells
    per axis, shared by the batch.

    The grid spans the bounding box of a system's finite positions and of ``extent`` (box-frame
    points ``(P, 3)`` or ``(B, P, 3)`` the grains may reach, e.g. the floor's and the lid's
    corners ``(0, 0, 0)``, ``(0, 0, L_z)``: a bed that rises towards the lid then stays inside
    the grid). Cells are cubes at least the listing distance (:func:`_listing_cutoff`) wide, so
    that the pairs of a grain lie in the 27 cells around its own: ``g = ceil(span / side)`` (at
    least 1) per axis, from the batch's largest span, with the side the listing distance or,
    where the grid would have more than :data:`MAX_CELLS_PER_GRAIN` cells per grain, as much
    wider as that needs."""
    pts = np.asarray(points, np.float64)
    x = pts[..., :3]
    finite = np.isfinite(pts).all(axis=-1, keepdims=True)
    lo = np.where(finite, x, np.inf).min(axis=-2)
    hi = np.where(finite, x, -np.inf).max(axis=-2)
    if extent is not None:
        e = np.asarray(extent, np.float64)
        e = np.broadcast_to(e, (pts.shape[0],) + e.shape[-2:])
        lo, hi = np.minimum(lo, e.min(axis=-2)), np.maximum(hi, e.max(axis=-2))
    empty = ~(np.isfinite(lo) & np.isfinite(hi))
    lo, hi = np.where(empty, 0.0, lo), np.where(empty, 0.0, hi)
    span = (hi - lo).max(axis=0)
    side = _listing_cutoff(model) * (1.0 + _SIDE_GUARD)
    widen = 1.0
    while True:
        dims = np.maximum(np.ceil(span / (side * widen)), 1).astype(np.int64)
        if dims.prod() <= max(MAX_CELLS_PER_GRAIN * model.n, 27):
            break
        widen *= 1.1
    sides = np.full_like(lo, side * widen)
    return np.stack([lo, sides], axis=-2), tuple(int(g) for g in dims)


def _cell_occupancy(points, grid, dims) -> int:
    """Most grains of one system of the batch ``(B, N, 4)`` in one cell of the grid."""
    pts = np.asarray(points, np.float64)
    keys = _cell_key(_cell_coords(pts[..., :3], np.asarray(grid), dims, np), dims)
    finite = np.isfinite(pts).all(axis=-1)
    return max((int(np.bincount(k[f]).max()) if f.any() else 0) for k, f in zip(keys, finite))


def _cell_list_shape(model: Model, points, multiplier: float, growth: float, extent=None):
    """``(grid, cells)`` of :class:`Neighbors` for a batch of points ``(B, N, 4)``: the cell
    grid (:func:`cell_grid`) and the cell capacity ``C`` = most grains in a cell × multiplier
    (at least :data:`MIN_CELL_CAPACITY`) × ``growth``, the ratio of the neighbour capacity
    allocated to the one these positions need (so that the re-allocation after an overflow,
    :func:`allocate` with ``at_least``, grows the cells as it grows the lists); no grid
    (:func:`_no_grid`) below :data:`CELLS_FROM` grains or where the 27 cells around a grain
    would hold ``N`` candidates or more (all pairs are then as cheap)."""
    b = points.shape[0]
    if model.n < CELLS_FROM:
        return _no_grid(b)
    grid, dims = cell_grid(model, points, extent)
    occ = _cell_occupancy(points, grid, dims)
    cap = int(math.ceil(max(int(math.ceil(occ * multiplier)), MIN_CELL_CAPACITY) * growth))
    if len(_STENCIL) * cap >= model.n:
        return _no_grid(b)
    return jnp.asarray(grid), jnp.zeros((b,) + dims + (cap, 0), jnp.int32)


def allocate(model: Model, positions, multiplier: float, at_least: int = 0,
             radius=None, extent=None) -> Neighbors:
    """Build lists for a batch of box-frame positions ``(B, N, 3)`` with a shared capacity.

    ``radius``: grain radii [m], ``(B, N)`` or ``(N,)`` (``Params.radius``); ``None`` treats
    every grain as the largest (exact for one size, wasteful for mixtures). From
    :data:`CELLS_FROM` grains the lists carry a cell grid for their rebuilds in the JAX engine
    (:func:`_cell_list_shape`; ``extent``: box-frame points it must cover besides the grains,
    :func:`cell_grid`). A larger ``at_least`` (the re-allocation after an overflow) grows the
    cells' capacity in the same proportion as the lists', up to the all-pairs builder: with
    ``N - 1`` neighbours per grain, or where the cells would hold ``N`` candidates, so that
    re-allocating always ends."""
    positions = jnp.asarray(positions)
    if model.n < 2:
        b = positions.shape[0]
        grid, cells = _no_grid(b)
        return Neighbors(
            idx=jnp.zeros((b, model.n, 0), jnp.int32),
            reference=positions,
            overflow=jnp.zeros((b,), bool),
            grid=grid,
            cells=cells,
        )
    points = _with_radius(model, positions, radius)
    base, cap = _capacities(model, points, multiplier, at_least)
    idx, overflow = _dense(model, cap, points)
    if cap < model.n - 1:
        grid, cells = _cell_list_shape(model, np.asarray(points), multiplier, cap / base, extent)
    else:
        grid, cells = _no_grid(positions.shape[0])
    return Neighbors(idx=jnp.asarray(idx), reference=positions, overflow=jnp.asarray(overflow),
                     grid=grid, cells=cells)


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
    positions = jax.lax.stop_gradient(positions)
    radii = lambda: _radius_array(model, positions, radius)  # noqa: E731 - in a rebuild only
    moved2 = jnp.sum((positions - nbrs.reference) ** 2, axis=-1)
    need = jnp.any(moved2 > (0.5 * model.skin) ** 2, axis=-1)  # (B,)
    count = jnp.sum(need)
    sizes = rebuild_groups(b)

    def rebuild_all(nb):
        fresh = _rebuild(model, nb, positions, radii())
        keep = lambda new, old: jnp.where(  # noqa: E731
            need.reshape(need.shape + (1,) * (old.ndim - 1)), new, old)
        return Neighbors(keep(fresh.idx, nb.idx), keep(fresh.reference, nb.reference),
                         nb.overflow | (need & fresh.overflow), nb.grid, nb.cells)

    def group_of(size):
        def rebuild(nb):
            sel = jnp.nonzero(need, size=size, fill_value=b)[0]  # those that need it, then b
            take = jnp.minimum(sel, b - 1)
            fresh = _rebuild(model, jax.tree_util.tree_map(lambda x: x[take], nb),
                             positions[take], radii()[take])
            return Neighbors(nb.idx.at[sel].set(fresh.idx, mode="drop"),
                             nb.reference.at[sel].set(fresh.reference, mode="drop"),
                             nb.overflow.at[sel].set(nb.overflow[take] | fresh.overflow,
                                                     mode="drop"), nb.grid, nb.cells)
        return rebuild

    branches = [lambda nb: nb] + [group_of(s) for s in sizes[:-1]] + [rebuild_all]
    if len(branches) == 2:
        return jax.lax.cond(count > 0, branches[1], branches[0], nbrs)
    which = sum((count > s).astype(jnp.int32) for s in (0,) + sizes[:-1])
    return jax.lax.switch(which, branches, nbrs)


def has_grid(nbrs: Neighbors) -> bool:
    """Whether ``nbrs`` are rebuilt from a cell list (else from all pairs)."""
    return nbrs.cells.shape[-2] > 0


def _rebuild(model: Model, like: Neighbors, positions, radius) -> Neighbors:
    """Fresh lists of a batch of box-frame positions ``(B, N, 3)`` (radii ``(B, N)``) with the
    capacity and the builder of ``like``: its cell grid (:func:`_build_cells_traced`) or, when
    it has none, all pairs (:func:`_build_traced`)."""
    if has_grid(like):
        return _build_cells_traced(model, capacity(like), positions, radius, like.grid,
                                   like.cells)
    return _build_traced(model, capacity(like), positions, radius)


def _build_cells_traced(model: Model, capacity: int, positions, radius, grid,
                        cells) -> Neighbors:
    """Dense lists of a batch of box-frame positions ``(B, N, 3)`` from a cell list
    (traceable): the same lists as :func:`_build_traced`, entry for entry, and the same
    overflow flags where the cells fit, in memory linear in ``N`` and time ``O(N log N)`` (one
    sort). ``grid`` ``(B, 2, 3)``, ``cells`` ``(B, g_x, g_y, g_z, C, 0)``: the grid
    (:class:`Neighbors`). (A row with more than ``capacity`` neighbours holds ``capacity`` of
    them, not necessarily the first ones as there: its system is flagged, and the lists are
    re-allocated and rebuilt before they are used.)

    Every finite grain goes to its cell (:func:`_cell_coords`; a grain outside the grid to the
    edge cell): the grains sorted by cell (stable: increasing index within a cell), a grain's
    slot in its cell is its rank among them, and the cell table ``(g_x g_y g_z, C)`` holds each
    cell's grains, padded with ``N``; a cell of more than ``C`` grains sets ``overflow``. A
    listed pair's centres are closer than the listing distance ``d_l``, since the metric is
    at least the centre distance (``R_i + R_j ≤ 2 R_max``); the cells are at least ``d_l`` wide,
    so its grains are at most one cell apart along every axis: grain ``i``'s candidates are
    the ``27 C`` entries of the cells around its own (those inside the grid), and ``(i, j)``
    is listed when ``j ≠ i`` and ``metric² < d_l²``, the test of :func:`_build_traced` on the
    same numbers. The listed ones are compacted by the binary search of
    :func:`_build_traced` over the running count along the candidates, then each row of
    ``capacity`` sorted (increasing ``j``, padding ``N`` last); ``overflow`` where a grain has
    more. Grains at non-finite positions are in no cell and have no pairs, as in the other
    builders."""
    n = model.n
    points = _with_radius(model, positions, radius)
    metric = _gap_metric(model)
    cut = _listing_cutoff(model)
    dims = tuple(int(g) for g in cells.shape[-5:-2])
    room = int(cells.shape[-2])
    n_cells = dims[0] * dims[1] * dims[2]
    ids = jnp.arange(n, dtype=jnp.int32)
    s = jnp.arange(1, capacity + 1, dtype=jnp.int32)
    stencil = jnp.asarray(_STENCIL, jnp.int32)
    upper = jnp.asarray(dims, jnp.int32)

    def one(p, g):
        finite = jnp.all(jnp.isfinite(p), axis=-1)
        c = _cell_coords(p[:, :3], g, dims)  # (N, 3)
        key = jnp.where(finite, _cell_key(c, dims), n_cells)  # non-finite: after every cell
        order = jnp.argsort(key, stable=True).astype(jnp.int32)
        sorted_key = key[order]
        new_cell = jnp.concatenate([jnp.ones((1,), bool), sorted_key[1:] != sorted_key[:-1]])
        slot = ids - jax.lax.cummax(jnp.where(new_cell, ids, 0))  # rank within the cell
        on_grid = sorted_key < n_cells
        table = jnp.full((n_cells + 1, room), n, jnp.int32).at[  # row n_cells: empty
            jnp.where(on_grid, sorted_key, n_cells + 1), slot].set(order, mode="drop")
        crowded = jnp.any(on_grid & (slot >= room))
        around = c[:, None, :] + stencil  # (N, 27, 3)
        inside = jnp.all((around >= 0) & (around < upper), axis=-1) & finite[:, None]
        cand = table[jnp.where(inside, _cell_key(around, dims), n_cells)].reshape(n, -1)
        d = metric(p[:, None, :], p[jnp.minimum(cand, n - 1)])  # (N, 27 C)
        listed = (cand < n) & (cand != ids[:, None]) & (d * d < cut * cut)
        count = jnp.cumsum(listed.astype(jnp.int32), axis=1)
        at = jax.vmap(lambda c_: jnp.searchsorted(c_, s, side="left",
                                                  method="scan_unrolled"))(count)
        padded = jnp.concatenate([cand, jnp.full((n, 1), n, jnp.int32)], axis=1)
        idx = jnp.sort(jnp.take_along_axis(padded, at, axis=1), axis=1)
        return idx, jnp.any(count[:, -1] > capacity) | crowded

    idx, overflow = jax.vmap(one)(points, grid)
    return Neighbors(idx=idx, reference=positions, overflow=overflow, grid=grid, cells=cells)


_build_cells = jax.jit(_build_cells_traced, static_argnums=(0, 1))


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
    cut = _listing_cutoff(model)
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
    grid, cells = _no_grid(points.shape[0])
    return Neighbors(idx=idx, reference=positions, overflow=overflow, grid=grid, cells=cells)


_build = jax.jit(_build_traced, static_argnums=(0, 1))


def to_numpy(nbrs: Neighbors) -> dict[str, np.ndarray]:
    return {k: np.asarray(getattr(nbrs, k))
            for k in ("idx", "reference", "overflow", "grid", "cells")}


def from_numpy(d: dict[str, np.ndarray]) -> Neighbors:
    """Inverse of :func:`to_numpy`. Arrays without ``grid``/``cells`` (checkpoints written
    before the cell builder) give lists rebuilt from all pairs, as they were."""
    idx = jnp.asarray(d["idx"], jnp.int32)
    grid, cells = _no_grid(idx.shape[0]) if idx.ndim == 3 else _no_grid(1)
    if idx.ndim != 3:  # a single system's lists
        grid, cells = grid[0], cells[0]
    return Neighbors(
        idx=idx,
        reference=jnp.asarray(d["reference"]),
        overflow=jnp.asarray(d["overflow"], bool),
        grid=jnp.asarray(d["grid"]) if "grid" in d else grid,
        cells=jnp.asarray(d["cells"], jnp.int32) if "cells" in d else cells,
    )

"""Neighbour lists for grain–grain contacts, built by jax-md and rebuilt once per batch.

jax-md's ``NeighborList.update`` decides per system with ``lax.cond`` whether to rebuild; under
``vmap`` that cond becomes a select, so every system would rebuild at every step. Here the
decision is made once for the whole batch (``any`` over systems, one ``lax.cond``) and the
capacity (neighbours per grain, a static shape) is allocated for the whole batch.

Positions given to the list are in the box frame (``z`` measured from the floor): pair
distances do not change under the box's rigid translation, and a bed that rides with the box
does not trigger rebuilds.

A rebuild is needed once any grain moved more than ``skin / 2`` since the last build; the list
holds every pair whose surfaces are closer than ``skin`` (centres closer than ``R_i + R_j +
skin``, plus a small margin for the one step that runs before the next check). The size-aware
cutoff keeps mixtures cheap: with radii differing tenfold a uniform ``2 R_max + skin`` would list
hundreds of small neighbours per small grain, where a few dozen can touch. It enters jax-md as a
metric on positions carrying the radius as a fourth coordinate,
``max(0, |r_i - r_j| - R_i - R_j + 2 R_max)``, compared with ``2 R_max + skin``; for equal radii
this is the plain distance. Overflow (a grain with more neighbours than the capacity) is
flagged, sticky, in :attr:`Neighbors.overflow`; the runner re-allocates and redoes the chunk.
"""

from __future__ import annotations

import math
import warnings
from functools import partial

import jax
import jax.numpy as jnp
import numpy as np
from jax_md import partition

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
    """jax-md metric on ``(x, y, z, R)`` points: the surface gap shifted by ``2 R_max``."""
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


def _jaxmd_fns(model: Model):
    return partition.neighbor_list(
        _gap_metric(model),
        box=1.0,  # unused: cell lists are off (all-pairs candidates, rebuilt rarely)
        r_cutoff=model.cutoff + _MARGIN * model.skin,
        dr_threshold=0.0,  # jax-md then always rebuilds; the decision is ours (see module doc)
        capacity_multiplier=1.0,
        disable_cell_list=True,
        format=partition.Dense,
    )


@partial(jax.jit, static_argnums=(0,))
def _occupancy(model: Model, points):
    """Largest number of listed neighbours of any grain in the batch (``points`` ``(B, N, 4)``)."""
    cutoff = model.cutoff + _MARGIN * model.skin
    metric = _gap_metric(model)

    def one(p):
        d = metric(p[:, None, :], p[None, :, :])
        close = (d < cutoff) & ~jnp.eye(p.shape[0], dtype=bool)
        return close.sum(axis=1).max()

    return jax.vmap(one)(points).max()


def _template(model: Model, capacity: int):
    """jax-md functions and an empty list of the given capacity (no compute: traceable)."""
    fns = _jaxmd_fns(model)
    template = partition.NeighborList(
        idx=jnp.full((model.n, capacity), model.n, jnp.int32),
        reference_position=jnp.zeros((model.n, 4)),
        error=partition.PartitionError(jnp.zeros((), jnp.uint8)),
        cell_list_capacity=None,
        max_occupancy=capacity,
        format=partition.Dense,
        cell_size=None,
        cell_list_fn=None,
        update_fn=fns.update,
    )
    return fns, template


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
    occ = int(_occupancy(model, _with_radius(model, positions, radius)))
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
    return _build(model, cap, positions, _radius_array(model, positions, radius))


def capacity(nbrs: Neighbors) -> int:
    return int(nbrs.idx.shape[-1])


def _radius_array(model: Model, positions, radius):
    return _with_radius(model, positions, radius)[..., 3]


def update(model: Model, nbrs: Neighbors, positions, radius=None) -> Neighbors:
    """Rebuild every list of the batch if any grain of any system moved more than skin/2.

    Traceable (use inside ``jit``/``scan``); ``positions`` are box-frame, ``(B, N, 3)``;
    ``radius`` as in :func:`allocate`.
    """
    if model.n < 2:
        return nbrs
    cap = capacity(nbrs)
    moved2 = jnp.sum((positions - nbrs.reference) ** 2, axis=-1)
    need = jnp.any(moved2 > (0.5 * model.skin) ** 2)

    def rebuild(nb):
        fresh = _build_traced(model, cap, positions, _radius_array(model, positions, radius))
        return Neighbors(fresh.idx, fresh.reference, nb.overflow | fresh.overflow)

    return jax.lax.cond(need, rebuild, lambda nb: nb, nbrs)


def _build_traced(model: Model, capacity: int, positions, radius=None) -> Neighbors:
    fns, template = _template(model, capacity)
    points = _with_radius(model, positions, radius)

    def one(p):
        nb = fns.update(p, template)
        return nb.idx, nb.did_buffer_overflow > 0

    with warnings.catch_warnings():
        # jax-md's dense pruning scatters int64 into int32 under x64; harmless, silenced here.
        warnings.filterwarnings("ignore", "scatter inputs have incompatible types", FutureWarning)
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

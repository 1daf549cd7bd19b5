"""Contact history carried by pair identity across neighbour-list rebuilds (issue 39).

A tangential spring (:mod:`jaxdamp.physics.tangential`) remembers, per contact, how far the two
surfaces have moved against each other. In the JAX engine a grain–grain contact lives in a slot
of the dense neighbour list (``idx (N, K)``: grain ``i``'s neighbours in increasing order,
padded with ``N``; :mod:`jaxdamp.engine.neighbors`), and a rebuild moves the pairs between
slots: a new neighbour enters a row and shifts the ones after it. The history therefore follows
the *pair* ``(i, j)``, not the slot — as LAMMPS' ``fix neigh/history`` does — by looking each
new slot's partner up in the row's old partners (a binary search: the rows are sorted).

Nothing is dropped silently: a pair that had a history but is not in the new list is counted
(:func:`carry`'s ``lost``). A touching pair is always within the listing distance, so a lost
history means a list that overflowed (the runner redoes such a chunk with a larger list) or a
bug; the engines stop on it.
"""

from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp


def _row(old, new, h, n):
    """One grain's row: ``old (K1,)``, ``new (K2,)`` partners (sorted, padded with ``n``),
    ``h (K1, ...)`` the history in the old slots."""
    pos = jnp.minimum(jnp.searchsorted(old, new), old.shape[0] - 1)
    hit = (old[pos] == new) & (new < n)
    out = jnp.where(hit.reshape(hit.shape + (1,) * (h.ndim - 1)), h[pos], 0)
    back = jnp.minimum(jnp.searchsorted(new, old), new.shape[0] - 1)
    kept = new[back] == old
    held = jnp.any(h.reshape(h.shape[0], -1) != 0, axis=1) & (old < n)
    return out, jnp.sum(held & ~kept)


def carry(old_idx, new_idx, history):
    """The history of one system's contacts moved from the slots of ``old_idx`` to those of
    ``new_idx`` by pair identity.

    Args:
      old_idx: ``(N, K1)`` the list the history was written against (rows sorted, padded
        with ``N``).
      new_idx: ``(N, K2)`` the rebuilt list (``K2`` may differ: a list re-allocated larger).
      history: ``(N, K1, ...)`` per slot of ``old_idx`` (e.g. ``(N, K1, 3)`` springs).

    Returns:
      ``(history (N, K2, ...), lost)``: each new slot holds the history its pair had (zero for
      a pair new to the list and for padding); ``lost`` (int) counts the pairs that had a
      non-zero history and are not in ``new_idx``.

    Example::

        >>> import jax.numpy as jnp
        >>> old = jnp.array([[1, 3, 3], [0, 3, 3], [3, 3, 3]])   # pairs (0, 1); 3 pads
        >>> new = jnp.array([[1, 2, 3], [0, 3, 3], [0, 3, 3]])   # (0, 2) is new
        >>> h = jnp.array([[5.0, 0, 0], [-5.0, 0, 0], [0, 0, 0]])
        >>> out, lost = carry(old, new, h)
        >>> out.tolist(), int(lost)
        ([[5.0, 0.0, 0.0], [-5.0, 0.0, 0.0], [0.0, 0.0, 0.0]], 0)
    """
    n = old_idx.shape[0]
    out, lost = jax.vmap(lambda o, w, h: _row(o, w, h, n))(old_idx, new_idx, history)
    return out, jnp.sum(lost)


def rekey(states, idx):
    """Batched states whose springs (``State.spring_pair``, written against
    ``State.spring_partner``) are carried over to the neighbour blocks ``idx`` ``(B, N, K)``
    by pair identity (:func:`carry`); ``spring_partner`` becomes ``idx``.

    Returns ``(states, lost (B,))``. States without springs (``spring_partner`` empty) come
    back as they are, with ``lost`` zero. Inside ``jit`` the carry runs only when some
    system's list differs from its springs' (a rebuild), else it is skipped."""
    old = states.spring_partner
    b = idx.shape[0]
    if old.shape[-1] == 0 and states.spring_pair.shape[-2] == 0:
        return states, jnp.zeros((b,), jnp.int32)
    idx = jnp.asarray(idx, jnp.int32)

    def moved(_):
        springs, lost = jax.vmap(carry)(old, idx, states.spring_pair)
        return springs, lost.astype(jnp.int32)

    if old.shape == idx.shape:
        springs, lost = jax.lax.cond(
            jnp.any(old != idx), moved,
            lambda _: (states.spring_pair, jnp.zeros((b,), jnp.int32)), None)
    else:  # re-allocated lists: another capacity
        springs, lost = moved(None)
    return dataclasses.replace(states, spring_pair=springs, spring_partner=idx), lost

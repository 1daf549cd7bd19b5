"""Contact history follows the pair, not the slot, across neighbour-list rebuilds
(:mod:`jaxdamp.engine.history`), checked against a dictionary keyed by pair identity."""

import jax
import jax.numpy as jnp
import numpy as np

from jaxdamp.engine import history


def _lists(n, k, pairs):
    """Dense lists ``(n, k)`` of a set of ordered pairs (rows sorted, padded with ``n``)."""
    idx = np.full((n, k), n, np.int32)
    for i in range(n):
        js = sorted(j for (a, j) in pairs if a == i)
        idx[i, :len(js)] = js
    return idx


def _random_pairs(rng, n, k, p):
    pairs = set()
    for i in range(n):
        for j in rng.choice(n, size=rng.integers(0, k + 1), replace=False):
            if j != i and rng.random() < p:
                pairs.add((i, int(j)))
    return pairs


def test_carry_follows_pairs_into_new_slots():
    """Random lists before and after a rebuild (pairs kept, gone and new; rows of other
    lengths, a larger capacity after): every kept pair's 3-vector is in its new slot, new
    pairs and padding are zero, and the histories of pairs gone from the list are counted as
    lost — and nothing else is."""
    rng = np.random.default_rng(1)
    n, k1, k2 = 40, 6, 9
    old_pairs = _random_pairs(rng, n, k1, 0.9)
    kept = {p for p in old_pairs if rng.random() < 0.7}
    new_pairs = kept | {p for p in _random_pairs(rng, n, k2 - 3, 0.5)}
    old, new = _lists(n, k1, old_pairs), _lists(n, k2, new_pairs)
    value = {p: rng.normal(size=3) for p in old_pairs}
    zero = {p for p in list(value)[:5]}  # pairs listed but not touching: zero history
    h = np.zeros((n, k1, 3))
    for i in range(n):
        for s in range(k1):
            j = old[i, s]
            if j < n and (i, j) not in zero:
                h[i, s] = value[(i, j)]
    out, lost = history.carry(jnp.asarray(old), jnp.asarray(new), jnp.asarray(h))
    out = np.asarray(out)
    assert out.shape == (n, k2, 3)
    for i in range(n):
        for s in range(k2):
            j = new[i, s]
            want = value[(i, j)] if (i, j) in old_pairs and (i, j) not in zero else np.zeros(3)
            np.testing.assert_array_equal(out[i, s], want)
    gone = {p for p in old_pairs if p not in new_pairs and p not in zero}
    assert int(lost) == len(gone) > 0


def test_carry_is_the_identity_on_an_unchanged_list_and_jits_over_a_batch():
    """The same list before and after: the history is unchanged, nothing lost; a batch of
    systems through ``jit(vmap(carry))``."""
    rng = np.random.default_rng(2)
    n, k = 30, 5
    idx = np.stack([_lists(n, k, _random_pairs(rng, n, k, 0.8)) for _ in range(3)])
    h = rng.normal(size=(3, n, k, 3)) * (idx < n)[..., None]
    out, lost = jax.jit(jax.vmap(history.carry))(jnp.asarray(idx), jnp.asarray(idx),
                                                 jnp.asarray(h))
    np.testing.assert_array_equal(np.asarray(out), h)
    assert not np.asarray(lost).any()

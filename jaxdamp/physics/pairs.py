"""Grain–grain contacts over a dense neighbour block (docs/physics.md §2).

Each grain ``i`` sees its neighbours ``idx[i, :]`` (dense format, padded with ``N``; :mod:`jaxdamp.engine.neighbors`).
Every pair is evaluated from both sides and forces are summed per row: no scatter, and
Newton's third law holds to the last bit because the two sides run the same arithmetic on
negated inputs. Pair sums of energies and losses are therefore halved.

The constants of a pair are a row of ``Params.pair_table`` (species of ``i``, species of
``j``), mixed when the model was built; only the law's radius- and mass-dependent part
(:attr:`jaxdamp.physics.contact.Law.pair_jax`) is formed here.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
import numpy as np

from jaxdamp.physics import tangential
from jaxdamp.physics.contact import G_STAR, GAMMA_S, LAWS, MU, Vec, contact_force, force_dtype

#: Where padding entries of the neighbour list point: far away, so they never touch.
_GHOST = 1.0e6


class PairForces(NamedTuple):
    """Grain–grain forces. ``force``, ``torque``: ``(N, 3)`` [N], [N m]; totals
    ``elastic_energy`` [J] (the tangential springs' included), ``normal_loss``,
    ``friction_loss`` [W]; ``grain_loss`` ``(N,)`` [W]: each grain's half of the loss (normal +
    friction) of its contacts. With tangential springs (``model.springs``): ``history``
    ``(N, K, 3)`` [N] the springs' forces after the step, per slot of ``idx``; ``turned`` [J] the
    pairs' :attr:`jaxdamp.physics.contact.ContactForce.turned`, ``slip_loss`` [W] the slip's
    part of ``friction_loss``, ``spring_energy`` [J] the springs' part of ``elastic_energy``
    (totals); without, ``history`` is ``(N, 0, 3)`` and the three 0."""

    force: jnp.ndarray
    torque: jnp.ndarray
    elastic_energy: jnp.ndarray
    normal_loss: jnp.ndarray
    friction_loss: jnp.ndarray
    grain_loss: jnp.ndarray
    history: jnp.ndarray
    turned: jnp.ndarray
    slip_loss: jnp.ndarray
    spring_energy: jnp.ndarray


def pair_forces(r, v, w, idx, p, model, history=None, step_vw=None) -> PairForces:
    """Contact forces between grains.

    Args:
      r, v, w: positions [m], velocities [m/s], angular velocities [rad/s], ``(N, 3)``.
      idx: neighbour indices ``(N, K)``, entries ``N`` are padding.
      p: :class:`jaxdamp.physics.model.Params`.
      model: :class:`jaxdamp.physics.model.Model` (the laws and the grains' species).
      history: with tangential springs (``model.springs``), their forces ``(N, K, 3)`` [N]
        per slot of ``idx`` before the step (``None``: none yet); they advance by one
        step ``p.dt``. Ignored without springs.
      step_vw: with springs, the velocities and angular velocities ``(v, w)`` over the step
        with which they grow (:class:`jaxdamp.physics.contact.Mindlin`; ``None``: ``v``, ``w``).
    """
    n = r.shape[0]
    springs = model.springs
    if n < 2 or idx.shape[1] == 0:
        zero = jnp.zeros_like(r)
        return PairForces(zero, zero, jnp.zeros(()), jnp.zeros(()), jnp.zeros(()),
                          jnp.zeros(n, r.dtype), jnp.zeros((n, idx.shape[1] if springs else 0, 3)),
                          jnp.zeros(()), jnp.zeros(()), jnp.zeros(()))

    lo = force_dtype(model)

    def own(x):  # (N,) -> (N, 1): grain i's value against each of its neighbours
        return x[:, None]

    def other(x, fill=0.0):  # (N,) -> (N, K): the neighbours' values, padding gets `fill`
        return jnp.concatenate([x, jnp.full((1,), fill, x.dtype)])[idx]

    def pair_vec(a, fill=0.0):  # own minus other, per component
        return Vec(*(own(a[:, k]) - other(a[:, k], fill) for k in range(3)))

    # geometry in the state's precision: the overlap is a small difference of large numbers
    dr = pair_vec(r, _GHOST)
    dist = jnp.sqrt(dr.dot(dr))  # > 0: grains never coincide, padding is far away
    radius = p.radius
    xi = (own(radius) + other(radius) - dist).astype(lo)
    nrm = dr.scale(1.0 / dist)
    nrm = Vec(*(c.astype(lo) for c in nrm))
    # the contact law in the force precision (``numerics.precision``)
    radius, mass, v, w = (x.astype(lo) for x in (radius, p.mass, v, w))
    R_i, R_j = own(radius), other(radius)

    # padding has R_j = m_j = 0; give it R* = m* = 1 so that square roots have finite gradients
    real = R_j > 0
    r_eff = jnp.where(real, R_i * R_j / (R_i + R_j), 1.0)
    m_i, m_j = own(mass), other(mass)
    m_eff = jnp.where(real, m_i * m_j / (m_i + m_j), 1.0)
    law = LAWS[model.law]
    row = _rows(p.pair_table.astype(lo), model.species_index(), idx)
    stiffness, damping = law.pair_jax(row, r_eff, m_eff)
    def spin_of(w):  # R_i ω_i + R_j ω_j
        Rw = radius[:, None] * w
        return Vec(*(own(Rw[:, k]) + other(Rw[:, k]) for k in range(3)))

    spin = spin_of(w)

    if springs:
        s = jnp.zeros(idx.shape + (3,), lo) if history is None else history.astype(lo)
        v_step = w_step = None
        if step_vw is not None:
            v_step, w_step = (x.astype(lo) for x in step_vw)
        spring = tangential.Mindlin(Vec.of(s), p.dt.astype(lo), row[..., G_STAR], r_eff,
                                    None if v_step is None else pair_vec(v_step),
                                    None if w_step is None else spin_of(w_step))
        c = tangential.contact_force(law, xi, nrm, pair_vec(v), spin, R_i, stiffness, damping,
                                     row[..., MU], spring)
    else:
        c = contact_force(law, xi, nrm, pair_vec(v), spin, R_i, stiffness, damping,
                          row[..., GAMMA_S], row[..., MU])
    hi = r.dtype
    zero = jnp.zeros((), hi)
    return PairForces(
        force=c.force.sum(axis=1).stack().astype(hi),
        torque=c.torque.sum(axis=1).stack().astype(hi),
        elastic_energy=0.5 * c.elastic_energy.astype(hi).sum(),
        normal_loss=0.5 * c.normal_loss.astype(hi).sum(),
        friction_loss=0.5 * c.friction_loss.astype(hi).sum(),
        grain_loss=0.5 * (c.normal_loss + c.friction_loss).astype(hi).sum(axis=1),
        history=(c.history.stack().astype(hi) if springs else jnp.zeros((n, 0, 3), hi)),
        turned=0.5 * c.turned.astype(hi).sum() if springs else zero,
        slip_loss=0.5 * c.slip_loss.astype(hi).sum() if springs else zero,
        spring_energy=0.5 * c.spring_energy.astype(hi).sum() if springs else zero,
    )


def _rows(table, species, idx):
    """Table rows of every (grain, neighbour) slot, ``(N, K, F)`` (``(F,)`` for one species).
    ``species``: the grains' species ``(N,)`` (static); padding slots get species 0 (they never
    touch)."""
    if table.shape[0] == 1:
        return table[0, 0]
    sp = jnp.asarray(np.append(species, 0).astype(np.int32))
    return table[sp[:-1, None], sp[idx]]


def all_pairs(n: int) -> jnp.ndarray:
    """A neighbour block listing every other grain: ``(N, N-1)``, the brute-force reference."""
    full = np.arange(n)[None, :].repeat(n, axis=0)
    return jnp.asarray(full[~np.eye(n, dtype=bool)].reshape(n, n - 1), dtype=jnp.int32)
